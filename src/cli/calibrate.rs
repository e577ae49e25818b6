//! `pinsight calibrate LOG.mcap [--out FILE] [--json]`: fits the effective
//! clearance, the laser zero and lag, the standoff, the F_ins table and the
//! load cell's lag against the model (see [`crate::overlay::calibrate`]),
//! prints each estimate with its uncertainty and the residual before/after,
//! and writes a parameter file that `simulate --params` and
//! `overlay --params` read.

use super::common::ParamArgs;
use super::overlay::load_and_cycles;
use crate::cli::common::{outln, outp};
use crate::overlay::calibrate::{CalibrateOptions, CalibrationReport, calibrate};
use crate::overlay::compare::model_params;
use crate::progress::{Progress, ProgressBarGuard};
use anyhow::{anyhow, bail};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The rig log (MCAP).
    #[arg(value_name = "LOG.mcap")]
    pub log: PathBuf,
    /// Nominal parameters (default: preset paper + the log's `rig` metadata).
    #[command(flatten)]
    pub params: ParamArgs,
    /// Write the calibrated parameter file (TOML) here.
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
    let mut opts = CalibrateOptions {
        fit_f_ins: !args.keep_f_ins,
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
        load_and_cycles(&args.log, &lopts, &args.params, args.points, !args.json)?;
    let (base, notes) = model_params(&log, file_params, &args.params.sets)
        .map_err(|e| anyhow!("{}: {e}", args.log.display()))?;
    let progress = Progress::new(0);
    let mut report = {
        let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "calibrate"));
        calibrate(&log, &cs, &base, &opts, &progress)?
    };
    report.notes.splice(0..0, notes);
    if args.flywheel {
        let fit = crate::overlay::calibrate::flywheel::calibrate_flywheel(&cs, &report.params)
            .map_err(|e| anyhow!(e))?;
        crate::overlay::calibrate::flywheel::apply_to_report(&mut report, &fit);
    }
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
    Ok(ExitCode::SUCCESS)
}

/// The text summary.
pub fn summary_text(r: &CalibrationReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "calibrate {}: {} cycles at {:.1} rpm",
        r.file, r.cycles, r.motor_rpm
    );
    let _ = writeln!(
        s,
        "  {:<14} {:>10} {:>12} {:>10} {:>10}  unit",
        "estimate", "nominal", "value", "σ", "U95"
    );
    for e in &r.estimates {
        let _ = writeln!(
            s,
            "  {:<14} {:>10} {:>12.5} {:>10.5} {:>10.5}  {}",
            e.name,
            e.nominal.map_or("-".to_string(), |v| format!("{v:.4}")),
            e.value,
            e.sigma,
            e.u95,
            e.unit
        );
    }
    if !r.f_ins_table.is_empty() {
        let _ = writeln!(s, "  F_ins table (depth mm → N ± σ):");
        for (d, f, sg) in &r.f_ins_table {
            let _ = writeln!(s, "    {d:>6.3} → {f:>8.3} ± {sg:.3}");
        }
    }
    let _ = writeln!(
        s,
        "  residual before: stroke spread {:.4} mm, stroke mean {:.4} mm, force {:.3} N",
        r.before.stroke_spread_rms_mm, r.before.stroke_mean_rms_mm, r.before.force_rms_n
    );
    let _ = writeln!(
        s,
        "  residual after:  stroke spread {:.4} mm, stroke mean {:.4} mm, force {:.3} N",
        r.after.stroke_spread_rms_mm, r.after.stroke_mean_rms_mm, r.after.force_rms_n
    );
    for n in &r.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}
