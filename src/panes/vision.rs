//! The Vision pane: the connector image with the fitted grid and the pins
//! coloured by verdict, a per-pin table, next/previous image.

use super::session::Session;
use super::{PaneState, csv_num, parse_usize};
use crate::vision::batch::ItemStatus;
use serde::Serialize;
use std::sync::Arc;

/// UI state of the Vision pane.
#[derive(Debug, Clone, Default, Serialize)]
pub struct VisionUi {
    pub image: usize,
    pub pin: usize,
}

impl VisionUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "image" => self.image = parse_usize(v)?,
            "pin" => self.pin = parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One pin's row.
#[derive(Debug, Clone, Serialize)]
pub struct PinRow {
    pub row: u32,
    pub col: u32,
    pub status: String,
    pub x_px: Option<f64>,
    pub y_px: Option<f64>,
    /// Offset from nominal in the part frame (dx along the row, dy across).
    pub dx_mm: Option<f64>,
    pub dy_mm: Option<f64>,
    pub offset_mm: Option<f64>,
    /// Top view: measured tip area / nominal.
    pub area_ratio: Option<f64>,
    /// Side view: height above the housing's top edge.
    pub height_mm: Option<f64>,
    /// Top view: the tip's level against the local tip level.
    pub contrast_ratio: Option<f64>,
    /// Why the pin is not `ok`, with its numbers against the limit.
    pub reason: Option<String>,
}

impl super::table::Cells for PinRow {
    const HEADER: &'static [&'static str] = &[
        "row",
        "col",
        "status",
        "x_px",
        "y_px",
        "dx_mm",
        "dy_mm",
        "offset_mm",
        "area_ratio",
        "height_mm",
        "reason",
    ];
    fn cells(&self, num: &dyn Fn(Option<f64>) -> String) -> Vec<String> {
        vec![
            self.row.to_string(),
            self.col.to_string(),
            self.status.clone(),
            num(self.x_px),
            num(self.y_px),
            num(self.dx_mm),
            num(self.dy_mm),
            num(self.offset_mm),
            num(self.area_ratio),
            num(self.height_mm),
            self.reason.clone().unwrap_or_default(),
        ]
    }
}

/// The Vision pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct VisionView {
    pub images: usize,
    pub index: usize,
    pub name: Option<String>,
    pub size: Option<(u32, u32)>,
    /// The recipe used and how it was chosen.
    pub recipe: Option<String>,
    /// `pass`, `fail` or `error` once inspected.
    pub verdict: Option<String>,
    /// Pins by status, e.g. "18 ok, 1 bent, 1 missing"; extras.
    pub counts: Option<String>,
    pub extras: usize,
    pub pins: Vec<PinRow>,
    /// The selected pin row.
    pub selected: usize,
    /// Why the connector fails: one line per failing pin and counted
    /// extra with its numbers against the limit (the inspection's
    /// `failed_because`, as the CLI prints it).
    pub failed_because: Vec<String>,
    /// The fitted grid: rotation, scale, fit residual.
    pub grid: Option<String>,
    pub warnings: Vec<String>,
    /// Why the image could not be inspected.
    pub error: Option<String>,
    /// Whether the inspection still has to run (the TUI runs it on its worker).
    pub pending: bool,
    pub wall_ms: Option<f64>,
    pub message: Option<String>,
    /// The job's whole result, exactly as `pinsight inspect --json` gives
    /// it for this image (JSON only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub result: Option<crate::vision::batch::ItemResult>,
    /// The image to draw: vision's annotated overlay once inspected (grid,
    /// pins coloured by verdict, magnified offsets), else the plain image.
    #[serde(skip)]
    pub image: Option<Arc<image::RgbImage>>,
}

impl VisionView {
    pub fn to_csv(&self) -> String {
        super::table::csv_of(&self.pins, &|x| csv_num(x, 4))
    }
}

fn status_counts(c: &crate::vision::StatusCounts) -> String {
    use crate::vision::PinStatus as P;
    let mut parts = Vec::new();
    for s in [P::Ok, P::Missing, P::Damaged, P::Bent, P::Short, P::High] {
        let n = c.get(s);
        if n > 0 {
            parts.push(format!("{n} {}", s.as_str()));
        }
    }
    parts.join(", ")
}

pub fn view(s: &Session, ui: &PaneState) -> VisionView {
    let n = s.images.len();
    let index = if n == 0 {
        0
    } else {
        ui.vision.image.min(n - 1)
    };
    let img = s.images.get(index);
    let mut v = VisionView {
        images: n,
        index,
        name: img.map(|i| i.name.clone()),
        size: img.map(|i| (i.width, i.height)),
        recipe: None,
        verdict: None,
        counts: None,
        extras: 0,
        failed_because: Vec::new(),
        pins: Vec::new(),
        selected: 0,
        grid: None,
        warnings: Vec::new(),
        error: None,
        pending: false,
        wall_ms: None,
        message: None,
        result: None,
        image: img.and_then(|i| i.preview.clone()),
    };
    if n == 0 {
        v.message = Some("no connector image loaded: open images and their recipe (o)".into());
        return v;
    }
    if s.recipes.is_empty() {
        v.message = Some("no recipe loaded: open the part's recipe (.toml) with o".into());
    }
    let Some(done) = s.inspection(index) else {
        v.pending = true;
        if v.message.is_none() {
            v.message = Some("inspecting…".into());
        }
        return v;
    };
    v.recipe = Some(done.recipe_note.clone());
    v.wall_ms = Some(done.wall_ms);
    v.result = Some(done.result.clone());
    v.verdict = Some(
        match done.result.status {
            ItemStatus::Pass => "pass",
            ItemStatus::Fail => "fail",
            ItemStatus::Error => "error",
        }
        .into(),
    );
    if let Some(e) = &done.result.error {
        v.error = Some(e.message.clone());
    }
    if let Some(a) = &done.annotated {
        v.image = Some(a.clone());
    }
    if let Some(ins) = &done.result.inspection {
        v.counts = Some(status_counts(&ins.counts));
        v.extras = ins.extras.len();
        v.grid = Some(format!(
            "{:.4} mm/px{}, rotation {:.2}°, fit {:.2} px RMS ({} inliers)",
            ins.grid.mm_per_px,
            if ins.grid.mm_per_px_estimated {
                " (estimated)"
            } else {
                ""
            },
            ins.grid.rotation_deg,
            ins.grid.fit_rms_px,
            ins.grid.fit_inliers
        ));
        v.warnings = ins.warnings.clone();
        v.failed_because = ins.failed_because.clone();
        v.pins = ins
            .pins
            .iter()
            .map(|p| PinRow {
                row: p.row,
                col: p.col,
                status: p.status.as_str().into(),
                x_px: p.x_px,
                y_px: p.y_px,
                dx_mm: p.dx_mm,
                dy_mm: p.dy_mm,
                offset_mm: p.offset_mm,
                area_ratio: p.area_ratio,
                height_mm: p.height_mm,
                contrast_ratio: p.contrast_ratio,
                reason: p.reason.clone(),
            })
            .collect();
        v.selected = ui.vision.pin.min(v.pins.len().saturating_sub(1));
    }
    v
}
