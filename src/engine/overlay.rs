//! The overlay job: a log's measured cycles against the model's predicted
//! ensemble, with parameters from the log's `rig` metadata.

use crate::model::kinematics::Geometry;
use crate::model::params::Params;
use crate::overlay::compare::{OverlayOptions, OverlayReport, model_params, overlay};
use crate::progress::Progress;
use crate::rig::cycles::{CycleOptions, CycleSet, analyse};
use crate::rig::{LoadOptions, RigLog, load};
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Measured against predicted for one log.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayRun {
    /// Index of the log in the session.
    pub log: usize,
    /// Shared with the Overlay pane's view (its JSON carries the whole report).
    pub report: Result<Arc<OverlayReport>, String>,
    pub wall_ms: f64,
}

/// A log's cycles delimited with a mechanism's geometry (`points` crank
/// angles per revolution): what the loader does with the `paper` preset and
/// `pinsight overlay`/`calibrate` with the parameters given.
pub fn cycles_of(log: &RigLog, geometry: &Params, points: usize) -> CycleSet {
    analyse(
        log,
        &CycleOptions {
            geometry: Geometry::of(geometry),
            points_per_rev: points.max(8),
            ..CycleOptions::default()
        },
    )
}

/// Loads a rig log for measured-against-predicted work (`overlay`,
/// `calibrate`): the log, and its cycles delimited with the mechanism of
/// `geometry` (the `paper` preset when none is given). A log with no
/// displacement channel is an error naming the file and what the loader
/// found, since the stroke cannot be compared.
pub fn load_for_overlay(
    path: &Path,
    opts: &LoadOptions,
    geometry: Option<&Params>,
    points: usize,
    progress: &Progress,
) -> Result<(RigLog, CycleSet), String> {
    let log = load(path, opts, progress).map_err(|e| e.to_string())?;
    let paper;
    let geometry = match geometry {
        Some(p) => p,
        None => {
            paper = Params::paper();
            &paper
        }
    };
    let cs = cycles_of(&log, geometry, points);
    require_displacement(&log)?;
    Ok((log, cs))
}

/// A log with no displacement channel cannot be compared with the model:
/// the error names the file and what the loader found.
pub fn require_displacement(log: &RigLog) -> Result<(), String> {
    if log.signals.displacement.is_some() {
        return Ok(());
    }
    Err(format!(
        "{}: no displacement channel ({}): the stroke cannot be compared",
        log.file,
        log.report
            .findings
            .iter()
            .map(|f| f.message.clone())
            .collect::<Vec<_>>()
            .join("; ")
    ))
}

/// The fidelity level `--level auto` picks for a log's overlay: the
/// cheapest that resolves 2 µm of stroke and 0.05 N of force with the
/// parameters the job will use.
pub fn auto_level(
    log: &RigLog,
    file_params: Option<Params>,
    sets: &[String],
) -> Result<crate::sim::Level, String> {
    let (params, _) = model_params(log, file_params, sets)
        .map_err(|e| format!("{}: model parameters: {e}", log.file))?;
    let f = crate::sim::fidelity::assess(
        &params,
        crate::sim::fidelity::SceneResolution {
            stroke_mm: 0.002,
            force_n: 0.05,
            needs_forces: true,
        },
        crate::solver::Method::Dop853,
    )
    .map_err(|e| e.to_string())?;
    Ok(f.chosen)
}

/// The overlay job: the model parameters (a parameter file if given, else
/// the `paper` preset plus the log's `rig` metadata, then `sets`), and the
/// comparison of every cycle with the predicted ensemble. The one path of
/// `pinsight overlay`, the Overlay pane, `render overlay` and batch.
pub fn overlay_job(
    log: &RigLog,
    cycles: &CycleSet,
    file_params: Option<Params>,
    sets: &[String],
    opts: &OverlayOptions,
    progress: &Progress,
) -> Result<OverlayReport, String> {
    progress.set_message(format!("overlay: predicting {}", log.file));
    let (params, notes) = model_params(log, file_params, sets)
        .map_err(|e| format!("{}: model parameters: {e}", log.file))?;
    overlay(log, cycles, &params, notes, opts, progress).map_err(|e| e.to_string())
}

/// Compares a log's cycles with the model's predicted ensemble with the
/// default options (what the Overlay pane shows): parameters from the
/// `paper` preset plus the log's `rig` metadata (clearance, standoff,
/// material, gear ratio), the clearance level, each speed group at its
/// logged speed.
pub fn run_overlay(
    index: usize,
    log: &RigLog,
    cycles: &CycleSet,
    progress: &Progress,
) -> OverlayRun {
    let start = Instant::now();
    let report =
        overlay_job(log, cycles, None, &[], &OverlayOptions::default(), progress).map(Arc::new);
    let report = if progress.is_cancelled() && report.is_err() {
        Err("cancelled".into())
    } else {
        report
    };
    OverlayRun {
        log: index,
        report,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}
