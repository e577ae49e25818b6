//! Process recipes: the evaluation objects of one part number's insertion,
//! in TOML, as a press monitor (Kistler maXYmos, burster DIGIFORCE) holds
//! them.
//!
//! ```toml
//! part_number = "HDR-2x10-2.54"
//!
//! [spc]
//! subgroup = 5            # consecutive cycles per X̄/R subgroup; 1 = individuals (I-MR)
//!
//! [[window]]              # the curve must enter through `entry` and leave through `exit`
//! name = "press-in"
//! x = "stroke"            # stroke from TDC, mm (default), or "angle": crank angle from TDC, °
//! branch = "down"         # on the stroke axis: "down" (insertion, TDC→BDC, default) or "up"
//! x_range = [13.9, 14.6]
//! y_range = [5.0, 30.0]   # force, N
//! entry = "left"          # left | right | bottom | top
//! exit = "right"
//!
//! [[threshold]]           # crossed exactly once, in the direction, inside x_range
//! name = "seated"
//! level = 15.0            # N
//! direction = "rising"    # rising | falling
//! x_range = [14.0, 16.5]
//! hysteresis = 0.3        # N; default 2 % of |level| (a noisy passage is one crossing)
//!
//! [[envelope]]            # a band learned from good cycles (`pinsight monitor --learn N`)
//! name = "press curve"
//! x = "angle"             # the crank angle is monotonic over the cycle: no turning point
//! x_range = [60.0, 170.0]
//! mode = "sigma"          # "sigma": mean ± k·σ per point; "minmax": the learned extremes ± margin
//! k = 4.0
//! margin = 0.2            # N added on both sides (noise floor)
//!
//! [[value]]               # a derived process value against its limits (also the SPC limits)
//! name = "peak force"
//! quantity = "peak_force_n"
//! min = 18.0
//! max = 30.0
//! ```
//!
//! Quantities: `peak_force_n`, `depth_mm` (deepest stroke − standoff),
//! `depth_at_peak_mm` (stroke at the peak force − standoff),
//! `force_at_depth_n` (with `at_depth_mm`: the force on the insertion branch
//! where the stroke is standoff + at_depth_mm), `bdc_stroke_err_mm`,
//! `tdc_stroke_err_mm` (measured − ideal stroke at the dead centres),
//! `impact_noise_um` (RMS of the displacement's second difference within
//! ±15° of each dead centre: the high-pass energy the joint's impacts leave).
//!
//! Loading rejects unknown keys and names the key and the allowed values.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// The abscissa of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Stroke from TDC (mm), on one branch of the cycle.
    #[default]
    Stroke,
    /// Crank angle from TDC (degrees, 0–360).
    Angle,
}

/// Which half of the cycle a stroke-axis object looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Branch {
    /// TDC → BDC: the pin going in.
    #[default]
    Down,
    /// BDC → TDC: withdrawal.
    Up,
}

/// A side of a window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    Left,
    Right,
    Bottom,
    Top,
}

impl Side {
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
            Side::Bottom => "bottom",
            Side::Top => "top",
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Window {
    pub name: String,
    #[serde(default)]
    pub x: Axis,
    #[serde(default)]
    pub branch: Branch,
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
    pub entry: Side,
    pub exit: Side,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    Rising,
    Falling,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Threshold {
    pub name: String,
    #[serde(default)]
    pub x: Axis,
    #[serde(default)]
    pub branch: Branch,
    pub x_range: [f64; 2],
    /// Force level, N.
    pub level: f64,
    pub direction: Direction,
    /// A crossing counts again only after the force went back past
    /// level ∓ hysteresis (N; default 2 % of |level|, at least 0.05 N), so
    /// noise on a slow passage is one crossing, as on a press monitor.
    #[serde(default)]
    pub hysteresis: Option<f64>,
}

impl Threshold {
    pub fn hysteresis_n(&self) -> f64 {
        self.hysteresis
            .unwrap_or((0.02 * self.level.abs()).max(0.05))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EnvelopeMode {
    /// mean ± k·σ of the learned cycles, per point.
    #[default]
    Sigma,
    /// the learned minimum and maximum, per point.
    Minmax,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Envelope {
    pub name: String,
    #[serde(default)]
    pub x: Axis,
    #[serde(default)]
    pub branch: Branch,
    pub x_range: [f64; 2],
    #[serde(default)]
    pub mode: EnvelopeMode,
    #[serde(default = "default_k")]
    pub k: f64,
    /// Added on both sides, N.
    #[serde(default)]
    pub margin: f64,
    /// Cycles the band was learned from (0: not learned yet).
    #[serde(default)]
    pub learned_from: usize,
    /// The learned band: abscissae and the lower/upper force (N) there.
    #[serde(default)]
    pub x_grid: Vec<f64>,
    #[serde(default)]
    pub lo: Vec<f64>,
    #[serde(default)]
    pub hi: Vec<f64>,
}

fn default_k() -> f64 {
    4.0
}

/// A derived process value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    PeakForceN,
    DepthMm,
    DepthAtPeakMm,
    ForceAtDepthN,
    BdcStrokeErrMm,
    TdcStrokeErrMm,
    ImpactNoiseUm,
}

impl Quantity {
    pub const ALL: [Quantity; 7] = [
        Quantity::PeakForceN,
        Quantity::DepthMm,
        Quantity::DepthAtPeakMm,
        Quantity::ForceAtDepthN,
        Quantity::BdcStrokeErrMm,
        Quantity::TdcStrokeErrMm,
        Quantity::ImpactNoiseUm,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Quantity::PeakForceN => "peak_force_n",
            Quantity::DepthMm => "depth_mm",
            Quantity::DepthAtPeakMm => "depth_at_peak_mm",
            Quantity::ForceAtDepthN => "force_at_depth_n",
            Quantity::BdcStrokeErrMm => "bdc_stroke_err_mm",
            Quantity::TdcStrokeErrMm => "tdc_stroke_err_mm",
            Quantity::ImpactNoiseUm => "impact_noise_um",
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            Quantity::PeakForceN | Quantity::ForceAtDepthN => "N",
            Quantity::ImpactNoiseUm => "µm",
            _ => "mm",
        }
    }

    /// Whether the value needs the load cell.
    pub fn needs_force(self) -> bool {
        matches!(
            self,
            Quantity::PeakForceN | Quantity::DepthAtPeakMm | Quantity::ForceAtDepthN
        )
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValueCheck {
    pub name: String,
    pub quantity: Quantity,
    /// For `force_at_depth_n`: depth below the standoff, mm.
    #[serde(default)]
    pub at_depth_mm: Option<f64>,
    /// Lower and upper limits (either may be left out); also the SPC LSL/USL.
    #[serde(default)]
    pub min: Option<f64>,
    #[serde(default)]
    pub max: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpcSettings {
    /// Consecutive cycles per subgroup (2–10: X̄/R charts; 1: I-MR).
    #[serde(default = "default_subgroup")]
    pub subgroup: usize,
}

fn default_subgroup() -> usize {
    5
}

impl Default for SpcSettings {
    fn default() -> Self {
        SpcSettings {
            subgroup: default_subgroup(),
        }
    }
}

/// One part number's process recipe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessRecipe {
    pub part_number: String,
    #[serde(default)]
    pub spc: SpcSettings,
    #[serde(default)]
    pub window: Vec<Window>,
    #[serde(default)]
    pub threshold: Vec<Threshold>,
    #[serde(default)]
    pub envelope: Vec<Envelope>,
    #[serde(default)]
    pub value: Vec<ValueCheck>,
}

/// A process recipe that cannot be used.
#[derive(Debug, Clone, thiserror::Error)]
#[error("invalid process recipe {source_name}: {msg}")]
pub struct ProcessRecipeError {
    pub source_name: String,
    pub msg: String,
}

/// Most points a learned envelope may hold (a corrupt file must not ask for more).
pub const MAX_ENVELOPE_POINTS: usize = 100_000;

impl ProcessRecipe {
    pub fn load(path: &Path) -> Result<Self, ProcessRecipeError> {
        let name = path.display().to_string();
        let text = crate::input::read_text(path).map_err(|e| ProcessRecipeError {
            source_name: name.clone(),
            msg: format!("cannot read file: {e}"),
        })?;
        Self::from_toml_str(&text, &name)
    }

    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Self, ProcessRecipeError> {
        let err = |msg: String| ProcessRecipeError {
            source_name: source_name.to_string(),
            msg,
        };
        // serde names the key and, for a wrong choice, every allowed value.
        let r: ProcessRecipe =
            toml::from_str(text).map_err(|e| err(e.to_string().trim().to_string()))?;
        r.validate().map_err(err)?;
        Ok(r)
    }

    /// The recipe as TOML (what `--learn` writes back).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Number of evaluation objects.
    pub fn object_count(&self) -> usize {
        self.window.len() + self.threshold.len() + self.envelope.len() + self.value.len()
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.part_number.trim().is_empty() {
            return Err("part_number is empty".into());
        }
        if !(1..=10).contains(&self.spc.subgroup) {
            return Err(format!(
                "spc.subgroup = {}: allowed 1 (individuals) to 10",
                self.spc.subgroup
            ));
        }
        if self.object_count() == 0 {
            return Err(
                "no evaluation object: add a [[window]], [[threshold]], [[envelope]] or [[value]]"
                    .into(),
            );
        }
        let range = |what: &str, name: &str, r: [f64; 2]| {
            if r.iter().all(|v| v.is_finite()) && r[0] < r[1] {
                Ok(())
            } else {
                Err(format!(
                    "{what} '{name}': range [{}, {}] must be two finite numbers, low < high",
                    r[0], r[1]
                ))
            }
        };
        for w in &self.window {
            range("window", &w.name, w.x_range)?;
            range("window", &w.name, w.y_range)?;
        }
        for t in &self.threshold {
            range("threshold", &t.name, t.x_range)?;
            if !t.level.is_finite() {
                return Err(format!("threshold '{}': level must be a number", t.name));
            }
            if t.hysteresis.is_some_and(|h| !(h.is_finite() && h >= 0.0)) {
                return Err(format!("threshold '{}': hysteresis must be ≥ 0 N", t.name));
            }
        }
        for e in &self.envelope {
            range("envelope", &e.name, e.x_range)?;
            if !(e.k.is_finite() && e.k > 0.0 && e.margin.is_finite() && e.margin >= 0.0) {
                return Err(format!(
                    "envelope '{}': k must be > 0 and margin ≥ 0",
                    e.name
                ));
            }
            let n = e.x_grid.len();
            if n > MAX_ENVELOPE_POINTS || e.lo.len() != n || e.hi.len() != n {
                return Err(format!(
                    "envelope '{}': x_grid, lo and hi must have the same length (≤ {MAX_ENVELOPE_POINTS}); got {}, {}, {}",
                    e.name,
                    n,
                    e.lo.len(),
                    e.hi.len()
                ));
            }
        }
        for v in &self.value {
            if v.quantity == Quantity::ForceAtDepthN && v.at_depth_mm.is_none_or(|d| !d.is_finite())
            {
                return Err(format!(
                    "value '{}': force_at_depth_n needs at_depth_mm (depth below the standoff, mm)",
                    v.name
                ));
            }
            if let (Some(a), Some(b)) = (v.min, v.max)
                && !(a < b)
            {
                return Err(format!("value '{}': min {a} must be below max {b}", v.name));
            }
            if v.min.is_some_and(|x| !x.is_finite()) || v.max.is_some_and(|x| !x.is_finite()) {
                return Err(format!("value '{}': limits must be numbers", v.name));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
part_number = "P"
[[window]]
name = "w"
x_range = [13.9, 14.6]
y_range = [5.0, 30.0]
entry = "left"
exit = "right"
[[value]]
name = "peak"
quantity = "peak_force_n"
min = 18.0
max = 30.0
"#;

    #[test]
    fn loads_and_round_trips() {
        let r = ProcessRecipe::from_toml_str(GOOD, "t").unwrap();
        assert_eq!(r.window[0].x, Axis::Stroke);
        assert_eq!(r.spc.subgroup, 5);
        let again = ProcessRecipe::from_toml_str(&r.to_toml(), "t2").unwrap();
        assert_eq!(again, r);
    }

    #[test]
    fn errors_name_the_key_and_the_allowed_values() {
        let e = ProcessRecipe::from_toml_str(&GOOD.replace("\"left\"", "\"sideways\""), "r.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("r.toml") && e.contains("sideways") && e.contains("left"),
            "{e}"
        );
        let e = ProcessRecipe::from_toml_str(&GOOD.replace("peak_force_n", "peak"), "r")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("peak_force_n") && e.contains("impact_noise_um"),
            "{e}"
        );
        let e = ProcessRecipe::from_toml_str(&GOOD.replace("min = 18.0", "min = 40.0"), "r")
            .unwrap_err()
            .to_string();
        assert!(e.contains("min 40 must be below max 30"), "{e}");
        let e = ProcessRecipe::from_toml_str(
            &GOOD.replace("name = \"w\"", "name = \"w\"\nwidth = 3"),
            "r",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("width"), "{e}");
        let e = ProcessRecipe::from_toml_str("part_number = \"P\"", "r")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no evaluation object"), "{e}");
    }
}
