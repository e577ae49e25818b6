//! Phase breakdown of `pinsight overlay` on one log: wall and process CPU
//! time of each step, run through the same library calls as the CLI.
//!
//! ```sh
//! cargo run --release --example rig_phases -- target/bench/big.mcap [--out DIR] [--sequential] [--no-load-alone]
//! ```
//!
//! `--sequential` runs the whole thing on one rayon thread (a comparison of
//! the parallel decode with the sequential one). A diagnostic, not a
//! benchmark: figures for BENCHMARKS.md come from `/usr/bin/time` on the CLI.

use pinsight::engine::overlay::load_for_overlay;
use pinsight::overlay::compare::{OverlayOptions, model_params, overlay};
use pinsight::overlay::outputs::write_outputs;
use pinsight::progress::Progress;
use pinsight::rig::LoadOptions;
use std::path::PathBuf;
use std::time::Instant;

#[path = "common/proc_stats.rs"]
mod proc_stats;
use proc_stats::{cpu_s, status_kb};

struct Clock(Instant, f64);

impl Clock {
    fn lap(&mut self, what: &str) {
        let (w, c) = (self.0.elapsed().as_secs_f64(), cpu_s());
        eprintln!(
            "{what:<28} wall {w:6.3} s  cpu {:6.3} s  peak RSS so far {} MB  RSS now {} MB",
            c - self.1,
            status_kb("VmHWM:") / 1024,
            status_kb("VmRSS:") / 1024
        );
        *self = Clock(Instant::now(), c);
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let log = PathBuf::from(args.first().cloned().unwrap_or_default());
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from);
    if args.iter().any(|a| a == "--sequential") {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global()?;
    }
    let mut clk = Clock(Instant::now(), cpu_s());
    let lopts = LoadOptions::default();
    if !args.iter().any(|a| a == "--no-load-alone") {
        let _ = pinsight::rig::load(&log, &lopts, &Progress::new(0))?;
        clk.lap("load alone (dropped)");
    }
    let (log_data, cs) =
        load_for_overlay(&log, &lopts, None, 720, &Progress::new(0)).map_err(anyhow::Error::msg)?;
    clk.lap("load + cycles");
    let (params, notes) = model_params(&log_data, None, &[])?;
    let progress = Progress::new(0);
    let report = overlay(
        &log_data,
        &cs,
        &params,
        notes,
        &OverlayOptions::default(),
        &progress,
    )?;
    clk.lap("overlay (predict + compare)");
    if let Some(dir) = out {
        write_outputs(&dir, &report)?;
        clk.lap("outputs");
    }
    Ok(())
}
