//! The clearance history of a head: one point per calibrated log.
//!
//! The abscissa of the wear fit is the head's cumulative cycle count at the
//! log's start (the `rig` metadata key `head_cycles`, the counter a line's
//! PLC keeps) when every log of the head has it, else the time since the
//! first log in days (`log_start` of the MCAP). A log is ordered by start
//! time, then by cycle count.

use crate::model::Params;
use serde::{Deserialize, Serialize};

/// The `rig` metadata key of the head's cumulative cycle counter at the log start.
pub const HEAD_CYCLES_KEY: &str = "head_cycles";

/// One calibrated log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HistoryPoint {
    pub file: String,
    /// SHA-256 of the file's bytes (the cache key).
    pub sha256: String,
    /// `rig_id` of the metadata ("unknown" when absent).
    pub rig: String,
    /// Log start (ns since the Unix epoch) and as UTC text.
    pub start_ns: Option<i64>,
    pub start_utc: String,
    /// The head's cumulative cycle count at the log start (metadata `head_cycles`).
    pub head_cycles: Option<f64>,
    /// Cycles the calibration used and the logged motor speed.
    pub cycles: usize,
    pub motor_rpm: f64,
    /// The calibrated clearance (mm), its standard uncertainty and U95.
    pub clearance_mm: f64,
    pub sigma_mm: f64,
    pub u95_mm: f64,
    /// The calibrated parameters (what the limit is simulated with).
    pub params: Params,
}

impl HistoryPoint {
    /// Standard uncertainty the fit weights with: U95/2, the calibration's σ if larger.
    pub fn weight_sigma_mm(&self) -> f64 {
        (self.u95_mm / 2.0).max(self.sigma_mm)
    }
}

/// What the wear is measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Abscissa {
    /// The head's cumulative cycles.
    Cycles,
    /// Days since the first log.
    Days,
}

impl Abscissa {
    pub fn unit(self) -> &'static str {
        match self {
            Abscissa::Cycles => "cycles",
            Abscissa::Days => "days",
        }
    }
}

/// Sorts by start time (unknown last), then head cycles, then file name.
pub fn order(points: &mut [HistoryPoint]) {
    points.sort_by(|a, b| {
        let ka = (a.start_ns.is_none(), a.start_ns.unwrap_or(0));
        let kb = (b.start_ns.is_none(), b.start_ns.unwrap_or(0));
        ka.cmp(&kb)
            .then(
                a.head_cycles
                    .unwrap_or(f64::NAN)
                    .total_cmp(&b.head_cycles.unwrap_or(f64::NAN)),
            )
            .then(a.file.cmp(&b.file))
    });
}

/// The abscissa of every point: cycles when all have them, else days since
/// the first start (needs every start time). None when neither is known.
pub fn abscissa(points: &[HistoryPoint]) -> Option<(Abscissa, Vec<f64>)> {
    if !points.is_empty() && points.iter().all(|p| p.head_cycles.is_some()) {
        return Some((
            Abscissa::Cycles,
            points
                .iter()
                .map(|p| p.head_cycles.unwrap_or(0.0))
                .collect(),
        ));
    }
    let starts: Option<Vec<i64>> = points.iter().map(|p| p.start_ns).collect();
    let starts = starts?;
    let t0 = *starts.iter().min()?;
    Some((
        Abscissa::Days,
        starts
            .iter()
            .map(|t| (t - t0) as f64 * 1e-9 / 86_400.0)
            .collect(),
    ))
}

/// Cycles per day over the history (first to last log), when both the
/// counter and the start times are known and the span is positive.
pub fn cycles_per_day(points: &[HistoryPoint]) -> Option<f64> {
    let known: Vec<(i64, f64)> = points
        .iter()
        .filter_map(|p| Some((p.start_ns?, p.head_cycles?)))
        .collect();
    let first = known.iter().min_by_key(|k| k.0)?;
    let last = known.iter().max_by_key(|k| k.0)?;
    let days = (last.0 - first.0) as f64 * 1e-9 / 86_400.0;
    let rate = (last.1 - first.1) / days;
    (days > 0.0 && rate.is_finite() && rate > 0.0).then_some(rate)
}
