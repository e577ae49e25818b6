//! Inspection recipes: one TOML file per part number (spec/vision.md).
//!
//! A recipe says what the connector should look like (grid, pitch, tip size
//! and shape, polarity, scale) and how far a pin may deviate. Loading
//! validates every field and names the file and the field in its error, so a
//! typo never turns into a silently wrong inspection (unknown keys are
//! rejected for the same reason).
//!
//! Additions to the format of the spec (all optional):
//! - `tolerance.tip_area` defaults to `[0.6, 1.5]` in the top view; it is
//!   rejected in the side view, where a silhouette has no tip area.
//! - `[extras] min_area_ratio` (default 0.25) and `max_distance_pitch`
//!   (default 1.0): what counts as an extra (spec: at least a quarter of a
//!   nominal tip, within one pitch of the housing).

use crate::fmt::fmt_num;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which way the camera looks at the part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum View {
    /// Down the insertion axis: pin tips as small squares or discs.
    Top,
    /// Back-lit silhouette across the pin row: pin heights above the housing.
    Side,
}

/// Tip cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PinShape {
    Square,
    Round,
}

/// Whether pin tips are brighter (coaxial light) or darker (backlight) than
/// their surroundings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Polarity {
    Bright,
    Dark,
}

impl Polarity {
    /// The sign that makes the pins bright: intensities are multiplied by
    /// it, so the detector always looks for bright features.
    pub fn sign(self) -> f32 {
        match self {
            Polarity::Bright => 1.0,
            Polarity::Dark => -1.0,
        }
    }
}

/// Allowed deviations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// Max distance of a pin centre from its fitted nominal position, mm
    /// (side view: offset along the row).
    pub position_mm: f64,
    /// Allowed ratio of measured to nominal tip area (top view).
    #[serde(default)]
    pub tip_area: Option<[f64; 2]>,
    /// Side view: nominal pin height above the housing's top edge, mm.
    #[serde(default)]
    pub height_mm: Option<f64>,
    /// Side view: allowed |height - nominal|, mm.
    #[serde(default)]
    pub height_tol_mm: Option<f64>,
}

/// What counts as an extra (an addition to the spec's format; the defaults
/// are the spec's rule).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtrasRule {
    /// Minimum blob area as a fraction of a nominal tip area.
    #[serde(default = "default_min_area_ratio")]
    pub min_area_ratio: f64,
    /// Top view: maximum distance from the housing, in pitches (x pitch).
    #[serde(default = "default_max_distance_pitch")]
    pub max_distance_pitch: f64,
}

fn default_min_area_ratio() -> f64 {
    0.25
}
fn default_max_distance_pitch() -> f64 {
    1.0
}

impl Default for ExtrasRule {
    fn default() -> Self {
        Self {
            min_area_ratio: default_min_area_ratio(),
            max_distance_pitch: default_max_distance_pitch(),
        }
    }
}

/// One part number's inspection recipe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    pub part_number: String,
    pub view: View,
    pub rows: u32,
    pub cols: u32,
    /// [along a row (x), between rows (y)], mm.
    pub pitch_mm: [f64; 2],
    /// Tip width (square) or diameter (round), mm.
    pub pin_mm: f64,
    pub pin_shape: PinShape,
    pub polarity: Polarity,
    /// Image scale; `None` means: estimate it from the grid and the pitch.
    #[serde(default)]
    pub mm_per_px: Option<f64>,
    /// [row, col] positions empty by design (0-based).
    #[serde(default)]
    pub skip: Vec<[u32; 2]>,
    pub tolerance: Tolerance,
    #[serde(default)]
    pub extras: ExtrasRule,
}

/// A recipe that cannot be used, with the reason.
#[derive(Debug, Clone, thiserror::Error)]
#[error("invalid recipe {source_name}: {msg}")]
pub struct RecipeError {
    /// The file (or "<string>") the recipe came from.
    pub source_name: String,
    pub msg: String,
}

/// Default allowed tip-area ratio in the top view.
pub const DEFAULT_TIP_AREA: [f64; 2] = [0.6, 1.5];

/// Largest grid accepted (rows × cols); far beyond any connector, it keeps
/// a corrupt recipe from asking for absurd work.
pub const MAX_POSITIONS: u32 = 10_000;

impl Recipe {
    /// Reads and validates a recipe file.
    pub fn load(path: &Path) -> Result<Recipe, RecipeError> {
        let name = path.display().to_string();
        let text = crate::input::read_text(path).map_err(|e| RecipeError {
            source_name: name.clone(),
            msg: format!("cannot read file: {e}"),
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses and validates recipe text; `source_name` names it in errors.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Recipe, RecipeError> {
        let err = |msg: String| RecipeError {
            source_name: source_name.to_string(),
            msg,
        };
        // Two-number keys must hold exactly two numbers: the decoder would
        // otherwise take the first two of a longer list silently.
        if let Ok(table) = text.parse::<toml::Table>() {
            let pairs = [
                ("pitch_mm", table.get("pitch_mm")),
                (
                    "tolerance.tip_area",
                    table
                        .get("tolerance")
                        .and_then(|t| t.as_table())
                        .and_then(|t| t.get("tip_area")),
                ),
            ];
            for (key, v) in pairs {
                if let Some(toml::Value::Array(a)) = v
                    && a.len() != 2
                {
                    return Err(err(format!(
                        "{key} must be exactly two numbers (got {} values)",
                        a.len()
                    )));
                }
            }
        }
        let recipe: Recipe =
            toml::from_str(text).map_err(|e| err(e.to_string().trim().to_string()))?;
        recipe.validate().map_err(err)?;
        Ok(recipe)
    }

    /// Checks every field for sense; returns the first problem found.
    pub fn validate(&self) -> Result<(), String> {
        let finite_pos = |v: f64| v.is_finite() && v > 0.0;
        if self.part_number.trim().is_empty() {
            return Err("part_number is empty".into());
        }
        if self.rows == 0 || self.cols == 0 {
            return Err(format!(
                "rows and cols must be at least 1 (got {} × {})",
                self.rows, self.cols
            ));
        }
        if self.rows.saturating_mul(self.cols) > MAX_POSITIONS {
            return Err(format!(
                "grid {} × {} has more than {MAX_POSITIONS} positions",
                self.rows, self.cols
            ));
        }
        // Physical ranges (wider than any connector line, far from the
        // 300-digit numbers and "inf px" a hostile file could ask for).
        let phys = |key: &str, v: f64, lo: f64, hi: f64, unit: &str| -> Result<(), String> {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!(
                    "{key} = {} is outside {} … {} {unit}",
                    fmt_num(v),
                    fmt_num(lo),
                    fmt_num(hi)
                ))
            }
        };
        phys("pitch_mm[0]", self.pitch_mm[0], 0.05, 100.0, "mm")?;
        phys("pitch_mm[1]", self.pitch_mm[1], 0.05, 100.0, "mm")?;
        phys("pin_mm", self.pin_mm, 0.01, 50.0, "mm")?;
        if let Some(m) = self.mm_per_px {
            phys("mm_per_px", m, 1e-4, 10.0, "mm/px")?;
        }
        phys(
            "tolerance.position_mm",
            self.tolerance.position_mm,
            1e-4,
            100.0,
            "mm",
        )?;
        if let Some(h) = self.tolerance.height_mm {
            phys("tolerance.height_mm", h, 1e-3, 1000.0, "mm")?;
        }
        if let Some(h) = self.tolerance.height_tol_mm {
            phys("tolerance.height_tol_mm", h, 1e-4, 100.0, "mm")?;
        }
        if let Some([_, hi]) = self.tolerance.tip_area {
            phys("tolerance.tip_area[1]", hi, 1.0, 100.0, "")?;
        }
        let min_pitch = if self.rows > 1 {
            self.pitch_mm[0].min(self.pitch_mm[1])
        } else {
            self.pitch_mm[0]
        };
        if (self.cols > 1 || self.rows > 1) && self.pin_mm >= min_pitch {
            return Err(format!(
                "pin_mm {} is not smaller than the pitch {}: pins would touch",
                fmt_num(self.pin_mm),
                fmt_num(min_pitch)
            ));
        }
        if let Some(m) = self.mm_per_px {
            if !finite_pos(m) {
                return Err(format!("mm_per_px must be positive (got {m})"));
            }
            if self.pin_mm / m < 3.0 {
                return Err(format!(
                    "pin_mm / mm_per_px = {:.2} px: a tip narrower than 3 px cannot be measured",
                    self.pin_mm / m
                ));
            }
        }
        for s in &self.skip {
            if s[0] >= self.rows || s[1] >= self.cols {
                return Err(format!(
                    "skip position [{}, {}] lies outside the {} × {} grid",
                    s[0], s[1], self.rows, self.cols
                ));
            }
        }
        if self.positions().is_empty() {
            return Err("every grid position is skipped: nothing to inspect".into());
        }
        let t = &self.tolerance;
        if !finite_pos(t.position_mm) {
            return Err(format!(
                "tolerance.position_mm must be positive (got {})",
                t.position_mm
            ));
        }
        if let Some([lo, hi]) = t.tip_area
            && !(lo.is_finite() && hi.is_finite() && (0.0..1.0).contains(&lo) && hi > 1.0)
        {
            return Err(format!(
                "tolerance.tip_area must be [low, high] with 0 <= low < 1 < high (got [{}, {}])",
                fmt_num(lo),
                fmt_num(hi)
            ));
        }
        if !(self.extras.min_area_ratio.is_finite() && self.extras.min_area_ratio > 0.0) {
            return Err("extras.min_area_ratio must be positive".into());
        }
        if !(self.extras.max_distance_pitch.is_finite() && self.extras.max_distance_pitch >= 0.0) {
            return Err("extras.max_distance_pitch must be >= 0".into());
        }
        match self.view {
            View::Top => {
                if t.height_mm.is_some() || t.height_tol_mm.is_some() {
                    return Err(
                        "tolerance.height_mm / height_tol_mm apply to the side view only".into(),
                    );
                }
            }
            View::Side => {
                if self.rows != 1 {
                    return Err(format!("side view needs rows = 1 (got {})", self.rows));
                }
                if t.tip_area.is_some() {
                    return Err("tolerance.tip_area does not apply to the side view (a silhouette has no tip area)".into());
                }
                match (t.height_mm, t.height_tol_mm) {
                    (Some(h), Some(tol)) => {
                        if !finite_pos(h) || !finite_pos(tol) {
                            return Err(format!(
                                "tolerance.height_mm and height_tol_mm must be positive (got {h}, {tol})"
                            ));
                        }
                    }
                    _ => {
                        return Err(
                            "side view needs tolerance.height_mm and tolerance.height_tol_mm"
                                .into(),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    /// Allowed tip-area ratio (top view), with the default applied.
    pub fn tip_area(&self) -> [f64; 2] {
        self.tolerance.tip_area.unwrap_or(DEFAULT_TIP_AREA)
    }

    /// The tolerances in force, as a result reports them: the top view's
    /// tip-area default filled in, no tip-area limit in the side view.
    pub fn tolerance_in_force(&self) -> Tolerance {
        Tolerance {
            tip_area: (self.view == View::Top).then(|| self.tip_area()),
            ..self.tolerance.clone()
        }
    }

    /// Whether (row, col) is empty by design.
    pub fn is_skipped(&self, row: u32, col: u32) -> bool {
        self.skip.iter().any(|s| s[0] == row && s[1] == col)
    }

    /// Every inspected position, row-major, skips left out.
    pub fn positions(&self) -> Vec<(u32, u32)> {
        let mut v = Vec::with_capacity((self.rows * self.cols) as usize);
        for r in 0..self.rows {
            for c in 0..self.cols {
                if !self.is_skipped(r, c) {
                    v.push((r, c));
                }
            }
        }
        v
    }

    /// Nominal position of (row, col) in the part frame, mm: u along the
    /// row, v across rows, origin at the grid centre (vision.md README).
    pub fn nominal_uv_mm(&self, row: u32, col: u32) -> (f64, f64) {
        let u = (col as f64 - (self.cols as f64 - 1.0) / 2.0) * self.pitch_mm[0];
        let v = (row as f64 - (self.rows as f64 - 1.0) / 2.0) * self.pitch_mm[1];
        (u, v)
    }

    /// Nominal tip area, mm² (square: w², round: π w²/4).
    pub fn tip_area_mm2(&self) -> f64 {
        match self.pin_shape {
            PinShape::Square => self.pin_mm * self.pin_mm,
            PinShape::Round => std::f64::consts::PI / 4.0 * self.pin_mm * self.pin_mm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HDR: &str = r#"
part_number = "HDR-2x10-2.54"
view = "top"
rows = 2
cols = 10
pitch_mm = [2.54, 2.54]
pin_mm = 0.64
pin_shape = "square"
polarity = "bright"
mm_per_px = 0.03
skip = [[1, 4]]

[tolerance]
position_mm = 0.10
tip_area = [0.6, 1.5]
"#;

    #[test]
    fn parses_spec_example_and_lists_positions() {
        let r = Recipe::from_toml_str(HDR, "hdr").unwrap();
        assert_eq!(r.view, View::Top);
        assert_eq!(r.positions().len(), 19);
        assert!(r.is_skipped(1, 4));
        let (u, v) = r.nominal_uv_mm(0, 0);
        assert!((u + 4.5 * 2.54).abs() < 1e-12 && (v + 1.27).abs() < 1e-12);
        assert!((r.tip_area_mm2() - 0.4096).abs() < 1e-12);
        assert_eq!(r.extras, ExtrasRule::default());
    }

    #[test]
    fn rejects_bad_recipes_with_reasons() {
        let cases = [
            (HDR.replace("rows = 2", "rows = 0"), "at least 1"),
            (
                HDR.replace("pin_mm = 0.64", "pin_mm = 3.0"),
                "not smaller than the pitch",
            ),
            (HDR.replace("skip = [[1, 4]]", "skip = [[2, 4]]"), "outside"),
            (
                HDR.replace("view = \"top\"", "view = \"front\""),
                "unknown variant",
            ),
            (
                HDR.replace("position_mm = 0.10", "position_mm = -1"),
                "position_mm",
            ),
            (
                HDR.replace("tip_area = [0.6, 1.5]", "tip_area = [1.6, 1.5]"),
                "tip_area",
            ),
            (
                HDR.replace("mm_per_px = 0.03", "mm_per_pix = 0.03"),
                "unknown field",
            ),
            (
                HDR.replace("mm_per_px = 0.03", "mm_per_px = 0.5"),
                "narrower than 3 px",
            ),
            (HDR.replace("view = \"top\"", "view = \"side\""), "rows = 1"),
            ("not toml at all [".to_string(), ""),
        ];
        for (text, want) in cases {
            let e = Recipe::from_toml_str(&text, "r.toml").unwrap_err();
            let s = e.to_string();
            assert!(s.starts_with("invalid recipe r.toml: "), "{s}");
            assert!(s.contains(want), "{s} should mention {want}");
        }
    }

    #[test]
    fn side_view_needs_heights() {
        let side = r#"
part_number = "S"
view = "side"
rows = 1
cols = 6
pitch_mm = [2.0, 2.0]
pin_mm = 0.5
pin_shape = "square"
polarity = "dark"
[tolerance]
position_mm = 0.08
height_mm = 2.5
height_tol_mm = 0.08
"#;
        assert!(Recipe::from_toml_str(side, "s").is_ok());
        let e = Recipe::from_toml_str(&side.replace("height_tol_mm = 0.08", ""), "s").unwrap_err();
        assert!(e.to_string().contains("height_tol_mm"));
        let e = Recipe::from_toml_str(
            &side.replace("[tolerance]", "[tolerance]\ntip_area = [0.5, 2.0]"),
            "s",
        )
        .unwrap_err();
        assert!(e.to_string().contains("side view"));
    }

    #[test]
    fn interop_recipes_load() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/images");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                Recipe::load(&p).unwrap();
                n += 1;
            }
        }
        assert_eq!(n, 7);
    }
}
