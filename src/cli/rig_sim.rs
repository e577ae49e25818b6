//! `pinsight rig-sim --out run.mcap [--rpm 1200] [--clearance 0.1]
//! [--rate real|8x] [--images DIR] [--faults SPEC] [--duration 60s]`:
//! a rig writing its log in real time (see [`crate::live::sim`]).

use crate::live::parse_duration;
use crate::live::sim::{FaultSpec, SimOptions, run as simulate};
use anyhow::{anyhow, bail};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The log to write (grows while written; the footer comes at the end).
    #[arg(long, value_name = "RUN.mcap")]
    pub out: PathBuf,
    /// Motor speed set-point (rev/min).
    #[arg(long, default_value_t = 1200.0)]
    pub rpm: f64,
    /// Radial clearance of the rod–pin-bar joint (mm); 0: the ideal mechanism.
    #[arg(long, default_value_t = 0.1)]
    pub clearance: f64,
    /// Speed: `real` (1×) or `Nx` (N times real time, e.g. 8x); `max`: as fast as it can.
    #[arg(long, default_value = "real")]
    pub rate: String,
    /// Length of the run (log time), e.g. 90s, 10m, 8h.
    #[arg(long, default_value = "60s")]
    pub duration: String,
    /// Folder the connector photographs are written to (one PNG per cycle).
    #[arg(long, value_name = "DIR")]
    pub images: Option<PathBuf>,
    /// Put the photographs on the log's camera topic too.
    #[arg(long)]
    pub images_in_log: bool,
    /// Distinct photographs rendered per kind of fault and reused (0: render every one).
    #[arg(long, default_value_t = 8)]
    pub image_pool: usize,
    /// Faults: nok=RATE, burst@FROM-TO, wear=MM/h, debris=RATE, corrupt@T, stop=SIGNAL@FROM-TO (comma-separated).
    #[arg(long, default_value = "")]
    pub faults: String,
    /// Start a new file every this much log time (RUN-001.mcap, RUN-002.mcap …).
    #[arg(long)]
    pub rotate: Option<String>,
    /// Log time between chunk flushes.
    #[arg(long, default_value = "250ms")]
    pub flush: String,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sample rates (Hz): spindle, force, displacement.
    #[arg(long, default_value_t = 5000.0)]
    pub spindle_hz: f64,
    #[arg(long, default_value_t = 10_000.0)]
    pub force_hz: f64,
    #[arg(long, default_value_t = 10_000.0)]
    pub displacement_hz: f64,
    /// Production lot written in the metadata.
    #[arg(long, default_value = "LIVE")]
    pub lot: String,
    /// Write what was simulated (files, each connector's fault and true verdict) as JSON here.
    #[arg(long, value_name = "FILE")]
    pub truth: Option<PathBuf>,
}

/// `real`, `1x`, `8x`, `max`, or a number.
pub fn parse_rate(s: &str) -> anyhow::Result<f64> {
    let s = s.trim();
    let r = match s {
        "real" => 1.0,
        "max" => f64::INFINITY,
        _ => s
            .strip_suffix(['x', '×'])
            .unwrap_or(s)
            .parse::<f64>()
            .map_err(|_| anyhow!("--rate `{s}`: real, Nx (e.g. 8x) or max"))?,
    };
    // 0.001× paces a second of log over 17 minutes of wall time; slower is
    // not a rig, and far slower overflows the wall clock's Duration.
    if !(r >= 1e-3) {
        bail!("--rate `{s}` must be at least 0.001 (or max)");
    }
    Ok(r)
}

/// The shortest file rotation `--rotate` accepts (log time): a second
/// holds at least 16 cycles at the 1000 rpm a line runs at least.
pub const MIN_ROTATE_S: f64 = 1.0;

pub fn options(args: &Args) -> anyhow::Result<SimOptions> {
    let pos = |v: f64, what: &str, max: f64| -> anyhow::Result<f64> {
        if v.is_finite() && v > 0.0 && v <= max {
            Ok(v)
        } else {
            bail!(
                "{what} must be above 0 and at most {max}, not {}",
                crate::fmt::plain(v)
            )
        }
    };
    if !(args.clearance.is_finite() && (0.0..=2.0).contains(&args.clearance)) {
        bail!(
            "--clearance must be between 0 and 2 mm, not {}",
            crate::fmt::plain(args.clearance)
        );
    }
    Ok(SimOptions {
        out: args.out.clone(),
        rpm: pos(args.rpm, "--rpm", 6000.0)?,
        clearance_mm: args.clearance,
        rate: parse_rate(&args.rate)?,
        duration_s: pos(
            parse_duration(&args.duration).map_err(|e| anyhow!("--duration: {e}"))?,
            "--duration",
            7.0 * 86400.0,
        )?,
        images: args.images.clone(),
        images_in_log: args.images_in_log,
        image_pool: args.image_pool,
        faults: FaultSpec::parse(&args.faults).map_err(|e| anyhow!("--faults: {e}"))?,
        seed: args.seed,
        flush_s: pos(
            parse_duration(&args.flush).map_err(|e| anyhow!("--flush: {e}"))?,
            "--flush",
            3600.0,
        )?,
        rotate_s: match &args.rotate {
            None => None,
            Some(r) => {
                let v = pos(
                    parse_duration(r).map_err(|e| anyhow!("--rotate: {e}"))?,
                    "--rotate",
                    1e7,
                )?;
                // A file per message is no rig log (the options fuzz found
                // `--rotate 1e-300` writing one file per message: 25 000
                // files for one second of line, 38 s).
                if v < MIN_ROTATE_S {
                    bail!(
                        "--rotate must be at least {MIN_ROTATE_S} s (a file holds whole cycles), not {}",
                        crate::fmt::plain(v)
                    );
                }
                Some(v)
            }
        },
        spindle_hz: pos(args.spindle_hz, "--spindle-hz", 100_000.0)?,
        force_hz: pos(args.force_hz, "--force-hz", 100_000.0)?,
        displacement_hz: pos(args.displacement_hz, "--displacement-hz", 100_000.0)?,
        lot: args.lot.clone(),
        record_truth: args.truth.is_some(),
        on_flush: None,
    })
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let opts = options(&args)?;
    let stop = Arc::new(AtomicBool::new(false));
    // Ctrl-C ends the run cleanly: the last chunk and the footer are written.
    crate::progress::stop_on_signals(&stop)?;
    let report = simulate(&opts, &stop).map_err(|e| anyhow!(e))?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(t) = &args.truth {
        let json = serde_json::to_vec_pretty(&report)?;
        crate::output::atomic::write_file(t, &json)?;
    }
    eprintln!(
        "rig-sim: {} cycle(s), {} image(s), {} message(s) in {} in {:.1} s",
        report.cycles,
        report.images,
        report.messages,
        report.files.join(", "),
        report.wall_s
    );
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn opts(extra: &[&str]) -> anyhow::Result<SimOptions> {
        let mut argv = vec!["rig-sim", "--out", "x.mcap"];
        argv.extend_from_slice(extra);
        options(&Cli::try_parse_from(argv)?.args)
    }

    #[test]
    fn a_rotation_shorter_than_a_second_is_refused_and_one_of_a_second_taken() {
        let e = opts(&["--rotate", "1e-300"]).unwrap_err().to_string();
        assert!(e.contains("--rotate must be at least 1 s"), "{e}");
        assert!(opts(&["--rotate", "500ms"]).is_err());
        assert_eq!(opts(&["--rotate", "1s"]).unwrap().rotate_s, Some(1.0));
        assert_eq!(opts(&["--rotate", "10m"]).unwrap().rotate_s, Some(600.0));
    }
}
