//! The overlay job: a log's measured cycles against the model's predicted
//! ensemble, with parameters from the log's `rig` metadata.

use crate::overlay::compare::{OverlayOptions, OverlayReport, model_params, overlay};
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::CycleSet;
use serde::Serialize;
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

/// Compares a log's cycles with the model's predicted ensemble
/// (`pinsight::overlay`): parameters from the `paper` preset plus the log's
/// `rig` metadata (clearance, standoff, material, gear ratio), the
/// clearance level, each speed group at its logged speed.
pub fn run_overlay(
    index: usize,
    log: &RigLog,
    cycles: &CycleSet,
    progress: &Progress,
) -> OverlayRun {
    let start = Instant::now();
    progress.set_message(format!("overlay: predicting {}", log.file));
    let report = model_params(log, None, &[])
        .map_err(|e| format!("model parameters from the log's metadata: {e}"))
        .and_then(|(params, notes)| {
            overlay(
                log,
                cycles,
                &params,
                notes,
                &OverlayOptions::default(),
                progress,
            )
            .map(Arc::new)
            .map_err(|e| e.to_string())
        });
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
