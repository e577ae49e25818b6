//! The Vision pane: the connector image with the fitted grid and the pins
//! coloured by verdict, a per-pin table, next/previous image.

use super::session::Session;
use super::{PaneState, csv_table, parse_usize};
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
    pub offset_mm: Option<f64>,
    pub area_ratio: Option<f64>,
}

/// The Vision pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct VisionView {
    pub images: usize,
    pub index: usize,
    pub name: Option<String>,
    pub size: Option<(u32, u32)>,
    pub recipe: Option<String>,
    pub verdict: Option<String>,
    pub pins: Vec<PinRow>,
    pub message: Option<String>,
    /// The image to draw (annotated when inspected).
    #[serde(skip)]
    pub image: Option<Arc<image::RgbImage>>,
}

impl VisionView {
    pub fn to_csv(&self) -> String {
        let f = |x: Option<f64>| x.map(|v| format!("{v:.4}")).unwrap_or_default();
        let rows: Vec<Vec<String>> = self
            .pins
            .iter()
            .map(|p| {
                vec![
                    p.row.to_string(),
                    p.col.to_string(),
                    p.status.clone(),
                    f(p.x_px),
                    f(p.y_px),
                    f(p.offset_mm),
                    f(p.area_ratio),
                ]
            })
            .collect();
        csv_table(
            &[
                "row",
                "col",
                "status",
                "x_px",
                "y_px",
                "offset_mm",
                "area_ratio",
            ],
            &rows,
        )
    }
}

pub fn view(s: &Session, ui: &PaneState) -> VisionView {
    let n = s.images.len();
    let index = if n == 0 {
        0
    } else {
        ui.vision.image.min(n - 1)
    };
    let img = s.images.get(index);
    VisionView {
        images: n,
        index,
        name: img.map(|i| i.name.clone()),
        size: img.map(|i| (i.width, i.height)),
        recipe: s.recipes.first().map(|r| r.part_number.clone()),
        verdict: None,
        pins: Vec::new(),
        message: Some(if n == 0 {
            "no connector image loaded: open images and their recipe (o)".into()
        } else {
            "pins not analysed: the vision module is not on main yet".into()
        }),
        image: img.and_then(|i| i.preview.clone()),
    }
}
