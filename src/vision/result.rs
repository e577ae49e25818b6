//! The inspection result: plain serialisable data with everything the
//! report writers, the overlay and the TUI's Vision pane need (verdict, per
//! pin status and measurements, the fitted grid with nominal positions in
//! pixels, extras, housing).

use super::fit::Similarity;
use super::gray::ImageInfo;
use super::recipe::{Tolerance, View};
use serde::{Deserialize, Serialize};

/// Per-pin verdict (spec/vision.md; first match wins in this order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PinStatus {
    Ok,
    Missing,
    Damaged,
    Bent,
    Short,
    High,
}

impl PinStatus {
    pub const ALL: [PinStatus; 6] = [
        PinStatus::Ok,
        PinStatus::Missing,
        PinStatus::Damaged,
        PinStatus::Bent,
        PinStatus::Short,
        PinStatus::High,
    ];
    pub fn as_str(&self) -> &'static str {
        match self {
            PinStatus::Ok => "ok",
            PinStatus::Missing => "missing",
            PinStatus::Damaged => "damaged",
            PinStatus::Bent => "bent",
            PinStatus::Short => "short",
            PinStatus::High => "high",
        }
    }

    /// The side view's rule (spec/vision.md): `bent` when the offset along
    /// the row exceeds `position_mm`, else `short`/`high` outside
    /// `height_mm ± height_tol_mm`, else `ok`. One rule for the inspection
    /// and for the generators' truth.
    pub fn side(tol: &Tolerance, offset_mm: f64, height_mm: f64) -> PinStatus {
        let h_nom = tol.height_mm.unwrap_or(0.0);
        let h_tol = tol.height_tol_mm.unwrap_or(f64::INFINITY);
        if offset_mm.abs() > tol.position_mm {
            PinStatus::Bent
        } else if height_mm < h_nom - h_tol {
            PinStatus::Short
        } else if height_mm > h_nom + h_tol {
            PinStatus::High
        } else {
            PinStatus::Ok
        }
    }
}

/// Connector verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Pass,
    Fail,
}

/// One grid position.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PinResult {
    pub row: u32,
    pub col: u32,
    pub status: PinStatus,
    /// Fitted nominal position, pixels (side view: nominal tip point).
    pub nominal_x_px: f64,
    pub nominal_y_px: f64,
    /// Measured centre (top view) or tip point on the pin axis (side view).
    pub x_px: Option<f64>,
    pub y_px: Option<f64>,
    /// Offset from nominal in the part frame, mm: dx along the row (towards
    /// higher columns), dy across the rows (towards higher rows). Side view:
    /// dx only.
    pub dx_mm: Option<f64>,
    pub dy_mm: Option<f64>,
    /// |offset| (side view: |dx|), mm.
    pub offset_mm: Option<f64>,
    /// Measured tip area / nominal tip area (top view).
    pub area_ratio: Option<f64>,
    /// Side view: height above the housing's top edge, mm.
    pub height_mm: Option<f64>,
    /// Side view: measured silhouette width / pin_mm.
    pub width_ratio: Option<f64>,
    /// Shape: sqrt of the ratio of the principal second moments (1 = square
    /// or disc, larger = elongated); top view.
    pub elongation: Option<f64>,
    /// Top view: the tip's level above the local background as a fraction
    /// of the tip level expected there from the neighbouring pins (≈ 1 for
    /// a tip; for a missing pin, what its expected position shows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contrast_ratio: Option<f64>,
    /// Why the pin is not `ok`, with the numbers against the limit (e.g.
    /// "offset 0.132 mm = 1.32 × position_mm 0.100").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl PinResult {
    /// A grid position with nothing found yet: `missing` at its fitted
    /// nominal point, every measurement empty. The views fill in what
    /// they measure.
    pub fn missing(row: u32, col: u32, nominal_px: (f64, f64)) -> Self {
        PinResult {
            row,
            col,
            status: PinStatus::Missing,
            nominal_x_px: nominal_px.0,
            nominal_y_px: nominal_px.1,
            x_px: None,
            y_px: None,
            dx_mm: None,
            dy_mm: None,
            offset_mm: None,
            area_ratio: None,
            height_mm: None,
            width_ratio: None,
            elongation: None,
            contrast_ratio: None,
            reason: None,
        }
    }
}

/// Something detected that belongs to no grid position.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtraResult {
    /// Area centroid, pixels.
    pub x_px: f64,
    pub y_px: f64,
    /// Area / nominal tip area.
    pub area_ratio: f64,
    /// Distance from the housing outline, mm (0 inside); side view: None.
    pub distance_mm: Option<f64>,
    /// Why a blob was not counted (only in `ignored`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ignored_because: Option<String>,
    /// Top view: level above the local background / the tip level
    /// expected there (debris as bright as a tip: ≈ 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contrast_ratio: Option<f64>,
    /// Contrast × √(pixels) / local noise σ: how far above the local noise
    /// floor the blob stands.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub snr: Option<f64>,
    /// Why an extra counts, with the numbers against the rule.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The fitted nominal grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridFit {
    /// Part frame (mm, origin at the grid centre; side view: origin at the
    /// housing's top edge below the grid centre) to pixels.
    pub transform: Similarity,
    /// Grid centre in pixels (side view: on the housing's top edge).
    pub centre_px: (f64, f64),
    pub rotation_deg: f64,
    pub mm_per_px: f64,
    /// True when `mm_per_px` was estimated from the pitch (recipe had none).
    pub mm_per_px_estimated: bool,
    /// Pins used in the final least-squares fit.
    pub fit_inliers: usize,
    /// RMS residual of those pins, pixels.
    pub fit_rms_px: f64,
    /// True when the housing had to decide which grid position the pins take
    /// (a whole end column missing, or an end pin on a one-row part).
    pub anchored_by_housing: bool,
}

/// The housing outline found in the image.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Housing {
    /// Corners in pixels (top view: the body's rectangle in the part frame;
    /// side view: the block's top edge ends and two points below).
    pub corners_px: [(f64, f64); 4],
    /// Part-frame extent, mm: [u_min, u_max, v_min, v_max].
    pub extent_mm: [f64; 4],
    /// Side view: the top edge as y = a + b x (pixels) and its RMS residual.
    pub edge: Option<EdgeLine>,
}

/// Side view: the housing's top edge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EdgeLine {
    pub a: f64,
    pub b: f64,
    pub rms_px: f64,
    pub points: usize,
}

/// Counts of pin statuses.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct StatusCounts {
    pub ok: u32,
    pub missing: u32,
    pub damaged: u32,
    pub bent: u32,
    pub short: u32,
    pub high: u32,
}

impl StatusCounts {
    pub fn add(&mut self, s: PinStatus) {
        match s {
            PinStatus::Ok => self.ok += 1,
            PinStatus::Missing => self.missing += 1,
            PinStatus::Damaged => self.damaged += 1,
            PinStatus::Bent => self.bent += 1,
            PinStatus::Short => self.short += 1,
            PinStatus::High => self.high += 1,
        }
    }
    pub fn get(&self, s: PinStatus) -> u32 {
        match s {
            PinStatus::Ok => self.ok,
            PinStatus::Missing => self.missing,
            PinStatus::Damaged => self.damaged,
            PinStatus::Bent => self.bent,
            PinStatus::Short => self.short,
            PinStatus::High => self.high,
        }
    }
}

/// Everything found on one image.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Inspection {
    pub part_number: String,
    pub view: View,
    pub verdict: Verdict,
    /// The recipe's tolerances (with defaults applied), for the report and
    /// the overlay.
    pub tolerance: Tolerance,
    pub image: ImageInfo,
    pub grid: GridFit,
    pub housing: Option<Housing>,
    /// Every inspected position, row-major (skips left out).
    pub pins: Vec<PinResult>,
    /// Extras that count (fail the connector).
    pub extras: Vec<ExtraResult>,
    /// Blobs seen but not counted (too small, too far from the housing).
    pub ignored: Vec<ExtraResult>,
    pub counts: StatusCounts,
    /// Things the user should know (e.g. scale estimated, housing not found).
    pub warnings: Vec<String>,
    /// Why the connector fails, one line per failing pin and counted extra,
    /// each with its numbers against the limit (empty when it passes): what
    /// the report, the CLI and the Vision pane show so that a verdict can be
    /// checked (or a wrong one diagnosed) from the report alone.
    pub failed_because: Vec<String>,
}

/// What a view found on the part: every grid position, the extras that
/// count, and the blobs seen but not counted.
pub struct Findings {
    pub pins: Vec<PinResult>,
    pub extras: Vec<ExtraResult>,
    pub ignored: Vec<ExtraResult>,
}

impl Inspection {
    /// The inspection of one image by `recipe`: what the view found, judged
    /// by the pass rule (counts and verdict filled in).
    pub fn judged(
        recipe: &super::recipe::Recipe,
        image: ImageInfo,
        grid: GridFit,
        housing: Option<Housing>,
        found: Findings,
        warnings: Vec<String>,
    ) -> Inspection {
        let mut ins = Inspection {
            part_number: recipe.part_number.clone(),
            view: recipe.view,
            verdict: Verdict::Fail,
            tolerance: recipe.tolerance_in_force(),
            image,
            grid,
            housing,
            pins: found.pins,
            extras: found.extras,
            ignored: found.ignored,
            counts: StatusCounts::default(),
            warnings,
            failed_because: Vec::new(),
        };
        ins.finish();
        ins
    }

    /// Applies the pass rule and fills `counts` (call after pins and extras are set).
    pub fn finish(&mut self) {
        let mut c = StatusCounts::default();
        for p in &self.pins {
            c.add(p.status);
        }
        self.counts = c;
        self.verdict =
            if self.pins.iter().all(|p| p.status == PinStatus::Ok) && self.extras.is_empty() {
                Verdict::Pass
            } else {
                Verdict::Fail
            };
        self.failed_because = self.explain();
    }

    /// One line per failing pin and counted extra: which one, and by how
    /// much (the view's reason, or the bare measurements when it gave none).
    fn explain(&self) -> Vec<String> {
        let mut out = Vec::new();
        for p in self.pins.iter().filter(|p| p.status != PinStatus::Ok) {
            let why = p.reason.clone().unwrap_or_else(|| {
                let mut m = Vec::new();
                if let Some(o) = p.offset_mm {
                    m.push(format!("offset {o:.3} mm"));
                }
                if let Some(a) = p.area_ratio {
                    m.push(format!("tip area {a:.2} × nominal"));
                }
                if let Some(h) = p.height_mm {
                    m.push(format!("height {h:.3} mm"));
                }
                if m.is_empty() {
                    "nothing measured there".into()
                } else {
                    m.join(", ")
                }
            });
            out.push(format!(
                "pin row {} col {} {}: {why}",
                p.row,
                p.col,
                p.status.as_str()
            ));
        }
        for e in &self.extras {
            let why = e
                .reason
                .clone()
                .unwrap_or_else(|| format!("area {:.2} of a tip", e.area_ratio));
            out.push(format!("extra at ({:.1}, {:.1}) px: {why}", e.x_px, e.y_px));
        }
        out
    }
}
