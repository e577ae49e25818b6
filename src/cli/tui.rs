//! `pinsight tui PATHS...` and `pinsight` with no arguments.

use crate::panes::{PaneId, Session};
use crate::tui::draw::ImageMode;
use std::io::IsTerminal;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Logs (.mcap), connector images, recipe and parameter .toml files, folders. None: the embedded demo.
    pub paths: Vec<String>,
    #[command(flatten)]
    pub params: super::common::ParamArgs,
    /// Fidelity level: auto, kinematic, ideal or clearance.
    #[arg(long)]
    pub level: Option<String>,
    /// Images in the terminal: auto (kitty / sixel / iTerm2 when the terminal has it, else half-blocks), halfblocks, off.
    #[arg(long, default_value = "auto")]
    pub images: String,
    /// Pane to start on (session, signals, overlay, model, study, vision, yield, methods, line, trend).
    #[arg(long, default_value = "session")]
    pub pane: String,
    /// Follow these logs (.mcap, while written) and folders (images, new logs) live.
    #[arg(long, value_name = "PATH", num_args = 1..)]
    pub follow: Vec<std::path::PathBuf>,
    /// With --follow: poll every DURATION instead of file-system events (network shares).
    #[arg(long, value_name = "DURATION")]
    pub poll: Option<String>,
    /// With --follow: vision recipe(s) of the images (default: the simulated line's connector).
    #[arg(long = "recipe")]
    pub recipes: Vec<std::path::PathBuf>,
    /// With --follow: TOML with [follow] and [alarms] sections.
    #[arg(long, value_name = "FILE")]
    pub config: Option<std::path::PathBuf>,
}

/// The session `tui` and `render` open: the demo when no path is given,
/// else the paths; then the parameter options and level.
pub fn build_session(
    paths: &[String],
    params: &super::common::ParamArgs,
    level: Option<&str>,
) -> anyhow::Result<Session> {
    let mut s = if paths.is_empty() {
        Session::demo()
    } else {
        let mut s = Session::new(format!("{} path(s) opened", paths.len()));
        s.open_paths(paths);
        s
    };
    if params.preset.is_some() || params.params.is_some() || !params.sets.is_empty() {
        s.params = params.resolve()?;
        s.params_source = describe_params(params);
    }
    if let Some(l) = level {
        s.level = crate::sim::LevelChoice::parse(l).ok_or_else(|| {
            anyhow::anyhow!("invalid --level `{l}` (allowed: auto, kinematic, ideal, clearance)")
        })?;
    }
    Ok(s)
}

fn describe_params(p: &super::common::ParamArgs) -> String {
    let mut parts = Vec::new();
    if let Some(f) = &p.params {
        parts.push(f.display().to_string());
    } else {
        parts.push(format!("preset {}", p.preset.as_deref().unwrap_or("paper")));
    }
    if !p.sets.is_empty() {
        parts.push(format!("--set {}", p.sets.join(" ")));
    }
    parts.join(" + ")
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let session = build_session(&args.paths, &args.params, args.level.as_deref())?;
    let images = match args.images.as_str() {
        "auto" => ImageMode::Auto,
        "halfblocks" | "half-blocks" => ImageMode::Halfblocks,
        "off" | "none" => ImageMode::Off,
        other => anyhow::bail!("invalid --images `{other}` (allowed: auto, halfblocks, off)"),
    };
    let pane = PaneId::parse(&args.pane).ok_or_else(|| {
        anyhow::anyhow!(
            "invalid --pane `{}` (allowed: {})",
            args.pane,
            PaneId::names()
        )
    })?;
    if !std::io::stdout().is_terminal() || !std::io::stdin().is_terminal() {
        anyhow::bail!(
            "the TUI needs a terminal on stdin and stdout; use `pinsight render PANE` or `pinsight batch SCRIPT` for headless output"
        );
    }
    let follow = if args.follow.is_empty() {
        None
    } else {
        Some(super::watch::inputs(
            &args.follow,
            &args.recipes,
            None,
            0,
            args.config.as_ref(),
            args.poll.as_deref(),
            &super::common::LogReadArgs {
                channels: None,
                meta: Vec::new(),
            },
        )?)
    };
    let session = if follow.is_some() && args.paths.is_empty() {
        Session::new("live")
    } else {
        session
    };
    crate::tui::run(
        session,
        crate::tui::Options {
            images,
            theme: None,
            pane,
            follow,
        },
    )?;
    Ok(ExitCode::SUCCESS)
}

/// `pinsight` with no arguments: the TUI on the embedded demo when stdout
/// is a terminal, else the demo's headless summary.
pub fn run_default() -> anyhow::Result<ExitCode> {
    if std::io::stdout().is_terminal() && std::io::stdin().is_terminal() {
        crate::tui::run(Session::demo(), crate::tui::Options::default())?;
        Ok(ExitCode::SUCCESS)
    } else {
        super::simulate::run_demo()
    }
}
