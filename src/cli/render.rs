//! `pinsight render PANE`: one pane headless, exactly as the TUI draws it
//! (text), or its view model (`--format json|csv|png`).

use crate::batch::{Format, export, parse_size, render_view_text};
use crate::cli::common::{outln, outp};
use crate::panes::{self, PaneId, PaneState, UI_OPTIONS};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Pane: session, signals, overlay, model, study, vision, yield, methods, line, trend.
    pub pane: String,
    /// Logs, images, recipes, parameter files, folders (none: the embedded demo).
    pub inputs: Vec<String>,
    /// Screen size in cells, WIDTHxHEIGHT.
    #[arg(long, default_value = "120x40")]
    pub size: String,
    /// text (the screen), json / csv (the view model), png (its charts or image).
    #[arg(long, default_value = "text")]
    pub format: String,
    /// Write to this file instead of stdout (required for png).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub params: super::common::ParamArgs,
    /// Fidelity level: auto, kinematic, ideal, clearance or motor (with driver = "motor").
    #[arg(long)]
    pub level: Option<String>,
    /// A pane UI option, e.g. `--ui study.factor=speed`, `--ui signals.t0=0.05` (repeatable; `--ui help` lists them).
    #[arg(long = "ui", value_name = "KEY=VALUE")]
    pub ui: Vec<String>,
    /// Study grid file (clearances_mm, speeds_rpm, materials) for the study pane.
    #[arg(long, value_name = "FILE")]
    pub grid: Option<PathBuf>,
    /// Study protocol: warm-up revolutions per case.
    #[arg(long, value_parser = super::common::bounds::warmup)]
    pub warmup: Option<f64>,
    /// Study protocol: reported revolutions per case.
    #[arg(long, value_parser = super::common::bounds::revs)]
    pub revs: Option<f64>,
    /// Do not run the model or the study first (show the panes as they are before any run).
    #[arg(long)]
    pub no_run: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if args.ui.iter().any(|u| u == "help") {
        outln!("UI options: {}", UI_OPTIONS.join(", "))?;
        return Ok(ExitCode::SUCCESS);
    }
    let pane = PaneId::parse(&args.pane).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown pane `{}` (allowed: {})",
            args.pane,
            PaneId::names()
        )
    })?;
    let (w, h) = parse_size(&args.size).map_err(|e| anyhow::anyhow!("--size: {e}"))?;
    let format = Format::parse(&args.format).ok_or_else(|| {
        anyhow::anyhow!(
            "invalid --format `{}` (allowed: text, json, csv, png)",
            args.format
        )
    })?;
    let mut session = super::tui::build_session(&args.inputs, &args.params, args.level.as_deref())?;
    session.display = Some("headless render (16 colours; images: half-blocks)".into());
    if let Some(g) = &args.grid {
        let text = crate::input::read_text(g)
            .map_err(|e| anyhow::anyhow!("reading grid file {}: {e}", g.display()))?;
        session.study_setup.grid = crate::sim::sweep::SweepGrid::from_toml_str(&text)
            .map_err(|e| anyhow::anyhow!("grid file {}: {e}", g.display()))?;
    }
    if let Some(x) = args.warmup {
        anyhow::ensure!(x >= 0.0 && x.is_finite(), "--warmup {x}: allowed ≥ 0");
        session.study_setup.warmup = x;
    }
    if let Some(x) = args.revs {
        anyhow::ensure!(x > 0.0 && x.is_finite(), "--revs {x}: allowed > 0");
        session.study_setup.revs = x;
    }
    let mut ui = PaneState::new(w, h);
    for opt in &args.ui {
        let (k, v) = opt
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--ui `{opt}`: expected KEY=VALUE"))?;
        ui.set_option(k.trim(), v.trim())
            .map_err(|e| anyhow::anyhow!(e))?;
    }
    if !args.no_run {
        session.run_model_now();
        if pane == PaneId::Methods {
            session.run_methods_now();
        }
        // The analyses of the data panes (the TUI runs them on its worker).
        session.prepare_pane(pane, &ui);
        if pane == PaneId::Study {
            let progress = crate::progress::Progress::new(session.study_setup.grid.len() as u64);
            let _bar = crate::progress::ProgressBarGuard::start(progress.clone(), "study");
            let r =
                crate::panes::session::run_study(&session.params, &session.study_setup, &progress);
            session.set_study(r);
        }
    }
    let view = panes::view(pane, &session, &ui);
    match (&args.out, format) {
        (Some(path), f) => {
            let what = export(&session, &view, f, (w, h), path).map_err(|e| anyhow::anyhow!(e))?;
            eprintln!("wrote {} ({what})", path.display());
        }
        (None, Format::Png) => anyhow::bail!("--format png needs --out FILE"),
        (None, Format::Text) => outp!("{}", render_view_text(&session, &view, w, h))?,
        (None, Format::Json) => outln!("{}", serde_json::to_string_pretty(&view.to_json())?)?,
        (None, Format::Csv) => outp!("{}", view.to_csv())?,
    }
    Ok(ExitCode::SUCCESS)
}
