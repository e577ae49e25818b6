//! `pinsight overlay LOG.mcap [--params FILE] [--set k=v]... [--level L]
//! [--cycles A..B] [--out DIR] [--json]`: the log's measured cycles against
//! the model's predicted ensemble (see [`crate::overlay::compare`]).
//!
//! Outputs in `--out DIR` (created): the report's own forms, written by
//! [`crate::overlay::outputs::write_outputs`] (JSON, CSV tables, PNG charts).
//!
//! Without `--out` only the summary (or with `--json` the report) is printed.
//!
//! Several logs (files or folders of them), or `--shard k/n` (one part of
//! the sorted logs, docs/scale.md): each log's outputs go to `--out
//! DIR/<log name>/`; a log that fails is listed and the others go on (exit
//! status 3). No merge is needed: the shards' folders together hold every
//! log once (`plant::log_batch`).

use super::common::ParamArgs;
use crate::cli::common::{outln, outp};
use crate::engine::overlay::{auto_level, load_for_overlay, overlay_job};
use crate::model::Params;
use crate::overlay::compare::OverlayOptions;
pub use crate::overlay::outputs::{
    curves_csv, cycles_csv, figures_csv, overlay_panels, run_csv, summary_text, write_outputs,
};
use crate::progress::{Progress, ProgressBarGuard};
use crate::rig::cycles::CycleSet;
use crate::rig::{LoadOptions, RigLog};
use crate::sim::LevelChoice;
use anyhow::{anyhow, bail};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: super::common::LogBatchArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Fidelity level of the prediction: clearance (default: the ensemble), ideal, kinematic, or auto.
    #[arg(long, default_value = "clearance")]
    pub level: String,
    /// Cycle indices to compare, `A..B` (B exclusive; either end may be left out).
    #[arg(long, value_name = "A..B")]
    pub cycles: Option<String>,
    /// Output directory for JSON, CSV and PNG files.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also write the overlay as MCAP for Foxglove (measured vs predicted stroke and force on the log's clock, per-cycle residuals).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// With --mcap: copy the log's own messages into the file too.
    #[arg(long, requires = "mcap")]
    pub mcap_signals: bool,
    #[command(flatten)]
    pub log_read: super::common::LogReadArgs,
    /// Simulated revolutions in the predicted ensemble (clearance level).
    #[arg(long, default_value_t = 40, value_parser = super::common::bounds::overlay_revs)]
    pub revs: usize,
    /// Revolutions simulated before the ensemble.
    #[arg(long, default_value_t = 3.0, value_parser = super::common::bounds::warmup)]
    pub warmup: f64,
    /// Integrator relative tolerance of the prediction.
    #[arg(long, default_value_t = 1e-6, value_parser = super::common::bounds::rtol)]
    pub rtol: f64,
    /// Relative spread of cycle speeds above which cycles are predicted per speed group (0.01 = 1 %).
    #[arg(long, default_value_t = 0.01, value_parser = super::common::bounds::fraction)]
    pub speed_threshold: f64,
    /// First-order lag of the displacement sensor (µs), applied to the prediction.
    #[arg(long, default_value_t = 0.0, value_parser = super::common::bounds::lag_us)]
    pub laser_lag_us: f64,
    /// First-order lag of the load cell (µs), applied to the prediction.
    #[arg(long, default_value_t = 0.0, value_parser = super::common::bounds::lag_us)]
    pub force_lag_us: f64,
    /// Crank-angle grid points per revolution.
    #[arg(long, default_value_t = 720, value_parser = super::common::bounds::points)]
    pub points: usize,
}

/// Parses `A..B`, `A..`, `..B` (cycle indices, B exclusive).
pub fn parse_cycle_range(s: &str) -> anyhow::Result<(u64, u64)> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| anyhow!("--cycles '{s}': expected A..B (e.g. 3..10)"))?;
    let num = |x: &str, d: u64| -> anyhow::Result<u64> {
        let x = x.trim();
        if x.is_empty() {
            Ok(d)
        } else {
            x.parse::<u64>()
                .map_err(|_| anyhow!("--cycles '{s}': '{x}' is not a cycle index"))
        }
    };
    let (a, b) = (num(a, 0)?, num(b, u64::MAX)?);
    if b <= a {
        bail!("--cycles '{s}': the range is empty");
    }
    Ok((a, b))
}

/// Loads the log and delimits its cycles with the model's geometry (the
/// engine's [`load_for_overlay`], with a progress bar unless
/// `show_progress` is off). Returns the parameter file's values too
/// (without the `--set` overrides, applied after the metadata).
pub fn load_and_cycles(
    path: &Path,
    opts: &LoadOptions,
    params: &ParamArgs,
    points: usize,
    show_progress: bool,
) -> anyhow::Result<(RigLog, Option<Params>, CycleSet)> {
    let file_params = if params.params.is_some() || params.preset.is_some() {
        Some(
            ParamArgs {
                sets: Vec::new(),
                ..params.clone()
            }
            .resolve()?,
        )
    } else {
        None
    };
    let progress = Progress::new(0);
    let _bar = show_progress.then(|| ProgressBarGuard::start(progress.clone(), "loading"));
    let (log, cs) = load_for_overlay(path, opts, file_params.as_ref(), points, &progress)
        .map_err(anyhow::Error::msg)?;
    Ok((log, file_params, cs))
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let (shard, single) = args.input.resolve()?;
    if let Some(log) = single {
        let report = overlay_one(&args, log, args.out.as_deref(), args.mcap.as_deref())?;
        if args.json {
            outln!("{}", serde_json::to_string_pretty(&report)?)?;
        } else {
            outp!("{}", summary_text(&report, args.out.as_deref()))?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    if args.mcap.is_some() {
        bail!("--mcap takes one log (one file per log): run the logs one at a time");
    }
    super::common::run_log_batch(shard, &args.input.logs, args.json, |l| {
        let dir = args.out.as_ref().map(|d| d.join(&l.name));
        let report = overlay_one(&args, &l.path, dir.as_deref(), None)?;
        let text = summary_text(&report, dir.as_deref());
        Ok((report, text))
    })
}

/// One log's overlay, its outputs written to `out` and `mcap` when given.
fn overlay_one(
    args: &Args,
    path: &Path,
    out: Option<&Path>,
    mcap: Option<&Path>,
) -> anyhow::Result<crate::overlay::compare::OverlayReport> {
    let cycles = args.cycles.as_deref().map(parse_cycle_range).transpose()?;
    let level = match LevelChoice::parse(&args.level) {
        Some(LevelChoice::Fixed(l)) => Some(l),
        Some(LevelChoice::Auto) => None,
        None => bail!(
            "invalid --level `{}` (allowed: auto, kinematic, ideal, clearance, motor)",
            args.level
        ),
    };
    if !(args.rtol > 0.0 && args.rtol < 1.0) {
        bail!("--rtol {} must lie in (0, 1)", args.rtol);
    }
    if !(args.laser_lag_us >= 0.0 && args.force_lag_us >= 0.0) {
        bail!("--laser-lag-us and --force-lag-us must be ≥ 0");
    }
    if !(args.speed_threshold >= 0.0) {
        bail!("--speed-threshold must be ≥ 0");
    }
    let lopts = args.log_read.load_options()?;
    let (log, file_params, cs) =
        load_and_cycles(path, &lopts, &args.params, args.points, !args.json)?;
    let mut extra_notes = Vec::new();
    let level = match level {
        Some(l) => l,
        None => {
            let chosen = auto_level(&log, file_params.clone(), &args.params.sets)
                .map_err(anyhow::Error::msg)?;
            extra_notes.push(format!("--level auto chose {}", chosen.name()));
            chosen
        }
    };
    let mut opts = OverlayOptions {
        speed_threshold: args.speed_threshold,
        cycles,
        ..OverlayOptions::default()
    };
    opts.predict.level = level;
    opts.predict.revs = args.revs.max(2);
    opts.predict.warmup = args.warmup;
    opts.predict.rtol = args.rtol;
    opts.predict.laser_lag_s = args.laser_lag_us * 1e-6;
    opts.predict.force_lag_s = args.force_lag_us * 1e-6;
    let progress = Progress::new(0);
    let mut report = {
        let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "overlay"));
        overlay_job(&log, &cs, file_params, &args.params.sets, &opts, &progress)
            .map_err(anyhow::Error::msg)?
    };
    report.notes.extend(extra_notes);
    if let Some(dir) = out {
        write_outputs(dir, &report)?;
    }
    if let Some(file) = mcap {
        // The log is mapped, not read (it may be large).
        let src = if args.mcap_signals {
            Some(crate::rig::mcap_read::Source::open(path)?)
        } else {
            None
        };
        let bytes = crate::export::mcap::overlay::overlay_mcap(
            &report,
            &cs,
            src.as_ref().map(|s| s.bytes()),
        )
        .map_err(|e| anyhow!("{}: {e}", file.display()))?;
        crate::output::write_file(file, &bytes)?;
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycle_ranges() {
        assert_eq!(parse_cycle_range("3..10").unwrap(), (3, 10));
        assert_eq!(parse_cycle_range("..4").unwrap(), (0, 4));
        assert_eq!(parse_cycle_range("5..").unwrap(), (5, u64::MAX));
        assert!(parse_cycle_range("5").is_err());
        assert!(parse_cycle_range("5..5").is_err());
        assert!(parse_cycle_range("a..5").is_err());
    }
}
