//! Ground-truth files of synthetic images (spec/vision.md, "Ground truth
//! files") and the comparison of an inspection against them: verdict and
//! per-pin status agreement, centre errors, extras found. Used by the tests,
//! the methods lab and CI jobs that check fixture data.

use super::recipe::Tolerance;
use super::result::{Inspection, PinStatus, Verdict};
use serde::{Deserialize, Serialize};

/// One pin of a truth file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthPin {
    pub row: u32,
    pub col: u32,
    pub x_px: Option<f64>,
    pub y_px: Option<f64>,
    pub defect: PinStatus,
    #[serde(default)]
    pub height_mm: Option<f64>,
    #[serde(default)]
    pub area_ratio: Option<f64>,
    #[serde(default)]
    pub offset_mm: Option<f64>,
}

impl TruthPin {
    /// A top-view tip as a generator painted it: its centre (px), tip area
    /// over the nominal and offset from nominal (mm); its defect by the
    /// recipe's limits — an area outside `tip_area` is damaged, an offset
    /// beyond `position_mm` bent.
    pub fn top(
        (row, col): (u32, u32),
        centre_px: (f64, f64),
        area_ratio: f64,
        offset_mm: f64,
        tip_area: [f64; 2],
        position_mm: f64,
    ) -> TruthPin {
        let defect = if area_ratio < tip_area[0] || area_ratio > tip_area[1] {
            PinStatus::Damaged
        } else if offset_mm > position_mm {
            PinStatus::Bent
        } else {
            PinStatus::Ok
        };
        TruthPin {
            row,
            col,
            x_px: Some(centre_px.0),
            y_px: Some(centre_px.1),
            defect,
            height_mm: None,
            area_ratio: Some(area_ratio),
            offset_mm: Some(offset_mm),
        }
    }

    /// A side-view pin as a generator painted it: its tip point (px),
    /// height above the housing and offset along the row (mm); its defect
    /// as [`PinStatus::side`] judges it.
    pub fn side(
        (row, col): (u32, u32),
        tip_px: (f64, f64),
        height_mm: f64,
        offset_mm: f64,
        tol: &Tolerance,
    ) -> TruthPin {
        TruthPin {
            row,
            col,
            x_px: Some(tip_px.0),
            y_px: Some(tip_px.1),
            defect: PinStatus::side(tol, offset_mm, height_mm),
            height_mm: Some(height_mm),
            area_ratio: None,
            offset_mm: Some(offset_mm.abs()),
        }
    }

    /// A position with no pin.
    pub fn missing(row: u32, col: u32) -> TruthPin {
        TruthPin {
            row,
            col,
            x_px: None,
            y_px: None,
            defect: PinStatus::Missing,
            height_mm: None,
            area_ratio: None,
            offset_mm: None,
        }
    }
}

/// One extra of a truth file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthExtra {
    pub x_px: f64,
    pub y_px: f64,
    #[serde(default)]
    pub kind: Option<String>,
}

/// A ground-truth file (unknown keys ignored).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    pub recipe: String,
    #[serde(default)]
    pub mm_per_px: Option<f64>,
    pub verdict: Verdict,
    pub pins: Vec<TruthPin>,
    #[serde(default)]
    pub extras: Vec<TruthExtra>,
    /// Noise σ of the render in DN (present in this project's generator's
    /// and the interop files under `render`).
    #[serde(default)]
    pub render: Option<serde_json::Value>,
}

impl Truth {
    pub fn from_json(text: &str) -> Result<Truth, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }

    /// The verdict a connector with these pins and counted extras
    /// deserves: pass when every pin is ok and there is no extra.
    pub fn verdict_of(pins: &[TruthPin], extras: &[TruthExtra]) -> Verdict {
        if pins.iter().all(|p| p.defect == PinStatus::Ok) && extras.is_empty() {
            Verdict::Pass
        } else {
            Verdict::Fail
        }
    }

    /// Render noise σ (DN) when the file records it.
    pub fn noise_sigma(&self) -> Option<f64> {
        self.render.as_ref()?.get("noise_sigma_dn")?.as_f64()
    }
}

/// How an inspection compares with the truth.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Comparison {
    pub verdict_ok: bool,
    /// Pins whose status differs: (row, col, truth, found).
    pub status_mismatches: Vec<(u32, u32, PinStatus, PinStatus)>,
    /// Centre errors (px) of pins present in both, with the truth status.
    pub centre_errors: Vec<(u32, u32, PinStatus, f64, f64)>,
    /// Height errors (mm), side view.
    pub height_errors: Vec<f64>,
    /// Area ratio (truth, found) where the truth gives one.
    pub area_ratios: Vec<(f64, f64)>,
    /// Truth extras with a reported extra within `extra_radius` px.
    pub extras_found: usize,
    pub extras_truth: usize,
    /// Reported extras not near any truth extra.
    pub extras_spurious: usize,
}

impl Comparison {
    /// RMS of the centre errors (hypot) of the pins selected by `keep`.
    pub fn rms(&self, keep: impl Fn(PinStatus) -> bool) -> Option<f64> {
        let v: Vec<f64> = self
            .centre_errors
            .iter()
            .filter(|e| keep(e.2))
            .map(|e| e.3 * e.3 + e.4 * e.4)
            .collect();
        (!v.is_empty()).then(|| (v.iter().sum::<f64>() / v.len() as f64).sqrt())
    }
}

/// Compares `ins` with `truth`; an extra matches within `extra_radius` px.
pub fn compare(ins: &Inspection, truth: &Truth, extra_radius: f64) -> Comparison {
    let mut c = Comparison {
        verdict_ok: ins.verdict == truth.verdict,
        ..Default::default()
    };
    for t in &truth.pins {
        let Some(p) = ins.pins.iter().find(|p| p.row == t.row && p.col == t.col) else {
            continue;
        };
        if p.status != t.defect {
            c.status_mismatches.push((t.row, t.col, t.defect, p.status));
        }
        if let (Some(tx), Some(ty), Some(x), Some(y)) = (t.x_px, t.y_px, p.x_px, p.y_px) {
            c.centre_errors
                .push((t.row, t.col, t.defect, x - tx, y - ty));
        }
        if let (Some(th), Some(h)) = (t.height_mm, p.height_mm) {
            c.height_errors.push(h - th);
        }
        if let (Some(ta), Some(a)) = (t.area_ratio, p.area_ratio) {
            c.area_ratios.push((ta, a));
        }
    }
    c.extras_truth = truth.extras.len();
    c.extras_found = truth
        .extras
        .iter()
        .filter(|t| {
            ins.extras
                .iter()
                .any(|e| (e.x_px - t.x_px).hypot(e.y_px - t.y_px) < extra_radius)
        })
        .count();
    c.extras_spurious = ins
        .extras
        .iter()
        .filter(|e| {
            !truth
                .extras
                .iter()
                .any(|t| (e.x_px - t.x_px).hypot(e.y_px - t.y_px) < extra_radius)
        })
        .count();
    c
}
