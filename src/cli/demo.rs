//! `pinsight demo [--live]`: the embedded demo (as `pinsight` alone), or
//! with `--live` a simulated line — `rig-sim` writing a log and connector
//! photographs in real time into a temporary folder — followed by the TUI,
//! so a newcomer sees the live mode with one command. Without a terminal
//! the live demo prints what `watch` would for `--for` seconds.

use crate::live::sim::{FaultSpec, SimOptions};
use anyhow::anyhow;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A simulated line written in real time, followed live.
    #[arg(long)]
    pub live: bool,
    /// Motor speed of the simulated line (rev/min).
    #[arg(long, default_value_t = 1200.0)]
    pub rpm: f64,
    /// Faults of the simulated line (see `pinsight rig-sim --help`).
    #[arg(
        long,
        default_value = "nok=0.04,debris=0.02,burst@40s-42s,wear=0.5mm/h"
    )]
    pub faults: String,
    /// Without a terminal: seconds to follow before stopping.
    #[arg(long = "for", default_value = "10s")]
    pub for_: String,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if !args.live {
        return super::tui::run_default();
    }
    // Every argument is read before anything is made, so a bad one leaves
    // no folder behind; the folder goes when `_cleanup` drops, on every path.
    let faults = FaultSpec::parse(&args.faults).map_err(|e| anyhow!("--faults: {e}"))?;
    let secs = crate::live::parse_duration(&args.for_).map_err(|e| anyhow!("--for: {e}"))?;
    let dir = std::env::temp_dir().join(format!("pinsight-live-demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let _cleanup = RemoveOnDrop(dir.clone());
    let log = dir.join("line.mcap");
    let img = dir.join("camera");
    let opts = SimOptions {
        out: log.clone(),
        rpm: args.rpm,
        rate: 1.0,
        duration_s: 8.0 * 3600.0,
        images: Some(img.clone()),
        faults,
        ..SimOptions::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let sim = {
        let stop = stop.clone();
        std::thread::Builder::new()
            .name("pinsight-rig-sim".into())
            .spawn(move || crate::live::sim::run(&opts, &stop))?
    };
    // The simulator stops whatever the follower did, error or not.
    let result = follow(vec![log, img], secs);
    stop.store(true, Ordering::Relaxed);
    let _ = sim.join();
    result?;
    Ok(ExitCode::SUCCESS)
}

/// Follows the demo's line: the TUI on a terminal, else `secs` of `watch`.
fn follow(paths: Vec<std::path::PathBuf>, secs: f64) -> anyhow::Result<()> {
    // The technician's config file: its [follow] and [alarms] apply to the
    // demo's line too, its keys and colours to the TUI.
    let config = crate::tui::config::load(None);
    let inputs = super::watch::inputs(
        &paths,
        &[],
        None,
        0,
        config.config.follow_settings(),
        None,
        &super::common::LogReadArgs {
            channels: None,
            meta: Vec::new(),
        },
    )?;
    if std::io::stdout().is_terminal() && std::io::stdin().is_terminal() {
        crate::tui::run(
            crate::panes::Session::new("live demo"),
            crate::tui::Options {
                follow: Some(inputs),
                config: Some(config),
                pane: crate::panes::PaneId::Signals,
                ..Default::default()
            },
        )
    } else {
        let mut f = crate::live::Follower::new(inputs);
        let t = std::time::Instant::now();
        let mut out = Ok(());
        while t.elapsed().as_secs_f64() < secs && out.is_ok() {
            let b = f.poll(None);
            for e in &b.events {
                if let crate::live::LiveEvent::Cycle(c) = e
                    && c.index % 20 != 0
                {
                    continue;
                }
                out = out.and_then(|_| {
                    super::common::outln!("{}", serde_json::to_string(e).unwrap_or_default())
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(250));
        }
        out
    }
}

/// The demo's temporary folder, removed however `run` ends.
struct RemoveOnDrop(std::path::PathBuf);

impl Drop for RemoveOnDrop {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
