//! What following produces: [`LiveEvent`]s (one JSON line each in `pinsight
//! watch --json-lines`: a new cycle, a new image, an alarm, a finding, a
//! file's state) and, per poll, a [`LiveBatch`] that also carries the raw
//! samples and the cycles' grids the TUI's panes draw.

use super::alarms::AlarmEvent;
use crate::process::CycleVerdict;
use crate::rig::channel_map::SignalKind;
use crate::rig::cycles::{Cycle, CycleSet};
use crate::rig::report::Finding;
use crate::vision::batch::ItemResult;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// A followed file's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FileState {
    /// Named but not there (yet).
    Waiting,
    Following,
    /// The writer finished it (footer read).
    Finished,
    /// The writer left it without finishing (a newer log appeared and it
    /// stopped growing).
    Abandoned,
    /// Deleted (or replaced) while followed.
    Deleted,
    /// A watched folder that is not there (any more).
    Missing,
}

/// A cycle as `watch` prints it (the figures of [`crate::rig::cycles::Cycle`]
/// and, with a process recipe, its verdict).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleEvent {
    pub file: String,
    pub index: u64,
    pub t_start_ns: i64,
    pub t_end_ns: i64,
    pub usable: bool,
    pub crank_rpm: f64,
    pub motor_rpm: f64,
    pub ripple_rms: f64,
    pub stroke_max_mm: f64,
    pub depth_mm: f64,
    pub peak_force_n: f64,
    pub stroke_err_tdc_mm: f64,
    pub stroke_err_bdc_mm: f64,
    pub stroke_dev_rms_mm: f64,
    pub stroke_dev_max_mm: f64,
    /// Process verdict (`ok`, `nok`, `not_evaluated`) with a recipe.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub status: Option<&'static str>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reasons: Vec<String>,
}

impl CycleEvent {
    pub fn of(file: &str, c: &Cycle, v: Option<&CycleVerdict>) -> Self {
        CycleEvent {
            file: file.to_string(),
            index: c.index,
            t_start_ns: c.t_start_ns,
            t_end_ns: c.t_end_ns,
            usable: c.usable,
            crank_rpm: c.crank_rpm,
            motor_rpm: c.motor_rpm_mean,
            ripple_rms: c.ripple_rms,
            stroke_max_mm: c.stroke_max_mm,
            depth_mm: c.depth_mm,
            peak_force_n: c.peak_force_n,
            stroke_err_tdc_mm: c.stroke_err_tdc_mm,
            stroke_err_bdc_mm: c.stroke_err_bdc_mm,
            stroke_dev_rms_mm: c.stroke_dev_rms_mm,
            stroke_dev_max_mm: c.stroke_dev_max_mm,
            status: v.map(|v| v.status.name()),
            reasons: v.map(|v| v.reasons()).unwrap_or_default(),
        }
    }
}

/// An image as `watch` prints it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageEvent {
    pub name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycle: Option<u64>,
    /// `pass`, `fail` or `error`.
    pub status: crate::vision::batch::ItemStatus,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Pins not ok: "r,c status".
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failed_pins: Vec<String>,
}

impl ImageEvent {
    pub fn of(r: &ItemResult) -> Self {
        ImageEvent {
            name: r.name.clone(),
            cycle: r.meta.cycle,
            status: r.status,
            error: r.error.as_ref().map(|e| e.message.clone()),
            failed_pins: r
                .inspection
                .as_ref()
                .map(|i| {
                    i.pins
                        .iter()
                        .filter(|p| p.status != crate::vision::result::PinStatus::Ok)
                        .map(|p| format!("{},{} {}", p.row, p.col, p.status.as_str()))
                        .collect()
                })
                .unwrap_or_default(),
        }
    }
}

/// A followed file's state change.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FileEvent {
    pub path: String,
    pub state: FileState,
    pub bytes: u64,
    pub cycles: u64,
}

/// One thing that happened, in the order it happened.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum LiveEvent {
    Cycle(CycleEvent),
    Image(ImageEvent),
    Alarm(AlarmEvent),
    Finding(Finding),
    File(FileEvent),
}

/// A cycle with its grids (for the Overlay and Line panes) and verdict.
#[derive(Debug, Clone)]
pub struct LiveCycle {
    pub file: String,
    pub cycle: Cycle,
    pub verdict: Option<CycleVerdict>,
}

/// A judged image with what the Vision pane draws.
#[derive(Debug, Clone)]
pub struct LiveImage {
    pub result: ItemResult,
    pub path: Option<PathBuf>,
    pub bytes: Option<Arc<Vec<u8>>>,
    pub width: u32,
    pub height: u32,
    /// Decoded for display (only the newest image of a poll).
    pub preview: Option<Arc<image::RgbImage>>,
    pub annotated: Option<Arc<image::RgbImage>>,
}

/// Everything one poll found.
#[derive(Debug, Clone, Default)]
pub struct LiveBatch {
    /// Log time of the first sample ever seen (the time axis's origin).
    pub t0_ns: Option<i64>,
    /// New raw samples per signal, sorted by time.
    pub samples: Vec<(SignalKind, Vec<(i64, f64)>)>,
    pub cycles: Vec<LiveCycle>,
    /// The cycle set the new cycles were found in (grid, ideal stroke …),
    /// without its cycles.
    pub cycle_set: Option<Arc<CycleSet>>,
    pub images: Vec<LiveImage>,
    pub events: Vec<LiveEvent>,
    pub files: Vec<FileEvent>,
    /// Alarm rules raised now.
    pub active_alarms: Vec<&'static str>,
    /// The yield over every connector so far.
    pub yields: Option<Arc<crate::vision::report::YieldReport>>,
    /// Bytes read and chunks decoded by this poll.
    pub bytes: u64,
    pub chunks: u64,
}

impl LiveBatch {
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
            && self.cycles.is_empty()
            && self.images.is_empty()
            && self.events.is_empty()
            && self.files.is_empty()
    }
}
