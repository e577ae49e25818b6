//! The calibration job: a log's effective clearance, laser zero and lag,
//! standoff, F_ins table and load-cell lag fitted against the model
//! ([`crate::overlay::calibrate`]), with parameters from a parameter file
//! or the `paper` preset plus the log's `rig` metadata, then `--set`
//! overrides. The one path of `pinsight calibrate`, the Overlay pane's
//! calibration (key `C`), `render overlay --ui overlay.calibrate=yes`,
//! batch `run calibrate`, and each log of the wear trend.

use super::overlay::require_displacement;
use crate::model::params::Params;
use crate::overlay::calibrate::{CalibrateOptions, CalibrationReport, calibrate};
use crate::overlay::compare::model_params;
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::CycleSet;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// One log's calibration, as the session holds it.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationRun {
    /// Index of the log in the session.
    pub log: usize,
    /// Shared with the Overlay pane's view (its JSON carries the whole report).
    pub report: Result<Arc<CalibrationReport>, String>,
    pub wall_ms: f64,
}

/// The calibration job on a loaded log and its cycles: the nominal
/// parameters ([`model_params`]: the parameter file if given, else the
/// `paper` preset plus the log's metadata; then `sets`), the fit, and the
/// parameters' notes first among the report's. A log without a
/// displacement channel is an error naming the file and what the loader
/// found, as [`super::overlay::load_for_overlay`] says it.
pub fn calibrate_job(
    log: &RigLog,
    cycles: &CycleSet,
    file_params: Option<Params>,
    sets: &[String],
    opts: &CalibrateOptions,
    progress: &Progress,
) -> Result<CalibrationReport, String> {
    require_displacement(log)?;
    progress.set_message(format!("calibrating {}", log.file));
    let (base, notes) =
        model_params(log, file_params, sets).map_err(|e| format!("{}: {e}", log.file))?;
    let mut report = calibrate(log, cycles, &base, opts, progress).map_err(|e| e.to_string())?;
    report.notes.splice(0..0, notes);
    Ok(report)
}

/// Calibrates log `index` of a session with the default options (what
/// `pinsight calibrate LOG` does with no options): the Overlay pane's
/// calibration.
pub fn run_calibration(
    index: usize,
    log: &RigLog,
    cycles: &CycleSet,
    progress: &Progress,
) -> CalibrationRun {
    let start = Instant::now();
    let report = calibrate_job(
        log,
        cycles,
        None,
        &[],
        &CalibrateOptions::default(),
        progress,
    )
    .map(Arc::new);
    let report = if progress.is_cancelled() && report.is_err() {
        Err("cancelled".into())
    } else {
        report
    };
    CalibrationRun {
        log: index,
        report,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}
