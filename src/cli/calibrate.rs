//! `pinsight calibrate LOG.mcap [--out FILE] [--json]`: fits the effective
//! clearance, the laser zero and lag, the standoff, the F_ins table and the
//! load cell's lag against the model (see [`crate::overlay::calibrate`]),
//! prints each estimate with its uncertainty and the residual before/after,
//! and writes a parameter file that `simulate --params` and
//! `overlay --params` read. The job is the engine's
//! ([`crate::engine::calibrate::calibrate_job`]), as for the Overlay pane's
//! calibration and batch `run calibrate`.
//!
//! Several logs (files or folders of them), or `--shard k/n` (one part of
//! the sorted logs, docs/scale.md): `--out` is a folder and each log gets
//! `DIR/<log name>/params.toml` and `calibration.json`; a log that fails is
//! listed and the others go on (exit status 3). Nothing to merge: the
//! shards' folders together hold every log once (`plant::log_batch`).

use super::common::ParamArgs;
use super::overlay::load_and_cycles;
use crate::cli::common::{outln, outp};
use crate::engine::calibrate::calibrate_job;
use crate::overlay::calibrate::{CalibrateOptions, CalibrationReport};
pub use crate::overlay::outputs::calibration_text as summary_text;
use crate::progress::{Progress, ProgressBarGuard};
use anyhow::bail;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: super::common::LogBatchArgs,
    /// Nominal parameters (default: preset paper + the log's `rig` metadata).
    #[command(flatten)]
    pub params: ParamArgs,
    /// Write the calibrated parameter file (TOML) here (several logs: a folder,
    /// one sub-folder per log).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub log_read: super::common::LogReadArgs,
    /// Simulated revolutions per clearance of the grid.
    #[arg(long, default_value_t = 48, value_parser = super::common::bounds::calibrate_revs)]
    pub revs: usize,
    /// Clearances simulated (mm, comma-separated); the nominal one is added.
    #[arg(long, value_name = "C1,C2,...")]
    pub clearance_grid: Option<String>,
    /// Keep the nominal F_ins table (fit only the standoff and the load cell's lag).
    #[arg(long)]
    pub keep_f_ins: bool,
    /// Crank-angle grid points per revolution.
    #[arg(long, default_value_t = 720, value_parser = super::common::bounds::points)]
    pub points: usize,
    /// Also fit the flywheel inertia to the crank speed ripple (the motor
    /// level); the parameter file then says driver = "motor".
    #[arg(long)]
    pub flywheel: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let (shard, single) = args.input.resolve()?;
    if let Some(log) = single {
        let report = calibrate_one(&args, log)?;
        if let Some(path) = &args.out {
            crate::output::write_file(path, report.params_toml.as_bytes())?;
        }
        if args.json {
            outln!("{}", serde_json::to_string_pretty(&report)?)?;
        } else {
            outp!("{}", summary_text(&report))?;
            if let Some(path) = &args.out {
                outln!("  wrote the parameter file {}", path.display())?;
            }
        }
        return Ok(ExitCode::SUCCESS);
    }
    super::common::run_log_batch(shard, &args.input.logs, args.json, |l| {
        let report = calibrate_one(&args, &l.path)?;
        if let Some(dir) = &args.out {
            let mut out = crate::output::Report::new_in(&dir.join(&l.name))?;
            out.add("params.toml", report.params_toml.as_bytes())?;
            out.add("calibration.json", &serde_json::to_vec_pretty(&report)?)?;
            out.commit()?;
        }
        let text = summary_text(&report);
        Ok((report, text))
    })
}

/// One log's calibration.
fn calibrate_one(args: &Args, path: &std::path::Path) -> anyhow::Result<CalibrationReport> {
    let mut opts = CalibrateOptions {
        fit_f_ins: !args.keep_f_ins,
        flywheel: args.flywheel,
        ..CalibrateOptions::default()
    };
    opts.predict.revs = args.revs.max(8);
    if let Some(g) = &args.clearance_grid {
        let v = super::common::parse_list_f64(g, "--clearance-grid")?;
        if v.len() < 3 || v.iter().any(|c| !(c.is_finite() && *c > 0.0)) {
            bail!("--clearance-grid needs at least 3 positive clearances (mm)");
        }
        opts.clearance_grid_mm = v;
    }
    let lopts = args.log_read.load_options()?;
    let (log, file_params, cs) =
        load_and_cycles(path, &lopts, &args.params, args.points, !args.json)?;
    let progress = Progress::new(0);
    let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "calibrate"));
    calibrate_job(&log, &cs, file_params, &args.params.sets, &opts, &progress)
        .map_err(anyhow::Error::msg)
}
