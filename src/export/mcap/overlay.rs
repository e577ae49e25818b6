//! The overlay as MCAP: measured against predicted stroke and force on the
//! log's own clock, one message per grid angle per compared cycle, and one
//! residual row per cycle.
//!
//! Topics (JSON, schema names in brackets):
//! - `/pinsight/overlay/stroke` (`pinsight.StrokeSample`) and
//!   `/pinsight/overlay/force` (`pinsight.ForceSample`): the measured value
//!   (laser zero as the report used it), the prediction of the cycle's speed
//!   group (mean, mean ± 2σ, min, max) and the residual. A grid angle θ of a
//!   cycle is stamped at t_start + (θ/360°)·duration: the cycle's mean speed,
//!   since the log's angle is resampled onto the grid.
//! - `/pinsight/overlay/cycle` (`pinsight.CycleResidual`): the report's row
//!   of the cycle at its start (stroke errors at the dead centres, RMS, the
//!   fractions inside the predicted band).
//! - with `signals`, the log's own messages, unchanged, under their topics.
//!
//! In Foxglove a Plot of `/pinsight/overlay/stroke.measured_mm` and
//! `.predicted_mean_mm` shows measured against predicted with no setup.

use super::McapOut;
use crate::overlay::compare::OverlayReport;
use crate::rig::cycles::{Band, CycleSet};
use serde::Serialize;

#[derive(Serialize)]
struct Sample {
    cycle: u64,
    angle_deg: f64,
    measured: f64,
    predicted_mean: f64,
    predicted_lo_2sigma: f64,
    predicted_hi_2sigma: f64,
    predicted_min: f64,
    predicted_max: f64,
    residual: f64,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Builds the overlay's MCAP; `log_bytes` (the rig log) to copy its signals.
pub fn overlay_mcap(
    report: &OverlayReport,
    cs: &CycleSet,
    log_bytes: Option<&[u8]>,
) -> Result<Vec<u8>, String> {
    let mut out = McapOut::new()?;
    if let Some(b) = log_bytes {
        out.copy_messages(b, "")?;
    }
    let shift = report.laser_zero.applied - cs.offsets.laser_zero_mm.applied;
    let grid = &report.grid_deg;
    for row in &report.cycles {
        let Some(c) = cs.cycles.iter().find(|c| c.index == row.index) else {
            continue;
        };
        let t0 = u64::try_from(c.t_start_ns).unwrap_or(0);
        let Some(group) = report.groups.get(row.group) else {
            continue;
        };
        let pred = &group.prediction;
        let time = |deg: f64| t0 + (deg / 360.0 * c.duration_s * 1e9).round().max(0.0) as u64;
        let emit = |out: &mut McapOut,
                    topic: &str,
                    name: &str,
                    unit: &str,
                    measured: &[f64],
                    band: &Band|
         -> Result<(), String> {
            for (j, &deg) in grid.iter().enumerate() {
                let (Some(m), Some(mean)) = (
                    measured.get(j).copied().and_then(finite),
                    band.mean.get(j).copied().and_then(finite),
                ) else {
                    continue;
                };
                let sd = band.std.get(j).copied().unwrap_or(f64::NAN);
                let s = Sample {
                    cycle: c.index,
                    angle_deg: deg,
                    measured: m,
                    predicted_mean: mean,
                    predicted_lo_2sigma: mean - 2.0 * sd,
                    predicted_hi_2sigma: mean + 2.0 * sd,
                    predicted_min: band.min.get(j).copied().unwrap_or(f64::NAN),
                    predicted_max: band.max.get(j).copied().unwrap_or(f64::NAN),
                    residual: m - mean,
                };
                out.log_json(topic, name, &with_unit(&s, unit)?, time(deg))?;
            }
            Ok(())
        };
        let stroke: Vec<f64> = c.stroke_mm.iter().map(|s| s + shift).collect();
        emit(
            &mut out,
            "/pinsight/overlay/stroke",
            "pinsight.StrokeSample",
            "mm",
            &stroke,
            &pred.stroke,
        )?;
        if !c.force_n.is_empty() {
            emit(
                &mut out,
                "/pinsight/overlay/force",
                "pinsight.ForceSample",
                "n",
                &c.force_n,
                &pred.force,
            )?;
        }
        out.log_json("/pinsight/overlay/cycle", "pinsight.CycleResidual", row, t0)?;
    }
    out.finish()
}

/// The sample with its unit in the field names (`measured_mm`, …), as
/// Foxglove shows field names and nothing else.
fn with_unit(s: &Sample, unit: &str) -> Result<serde_json::Value, String> {
    let v = serde_json::to_value(s).map_err(|e| e.to_string())?;
    let serde_json::Value::Object(o) = v else {
        return Ok(v);
    };
    Ok(serde_json::Value::Object(
        o.into_iter()
            .map(|(k, v)| match k.as_str() {
                "cycle" | "angle_deg" => (k, v),
                _ => (format!("{k}_{unit}"), v),
            })
            .collect(),
    ))
}
