//! Randomised images from the whole imaging envelope ([`super::envelope`]),
//! with exact ground truth: the test of "does the verdict hold on the images
//! a real line produces", not only on images shaped like
//! [`super::synth::Scene`]'s.
//!
//! [`EnvelopeCase::draw`] draws every factor at once and independently —
//! recipe (square/round, rows, columns, pitches, skips, top or side view,
//! polarity), scale (with or without `mm_per_px` in the recipe), image size
//! and aspect ratio, pose, contrast, noise, blur, vignetting, illumination
//! gradient, gain with clipping, JPEG quality, housing texture, bit depth
//! and colour — and the defects (missing, bent, damaged, extras; short and
//! high in the side view). [`EnvelopeCase::render`] paints it.
//!
//! The look deliberately differs from [`super::synth::Scene`] where a real
//! part plausibly differs: tips with rounded corners, soft edges (a linear
//! coverage ramp), a specular dome and a faint shading gradient; a housing
//! with rounded corners, a chamfered rim, an orientation mark beside pin
//! (0, 0) and a grainy texture; a textured fixture behind it; off-centre
//! vignetting `1 / (1 + k r²)²`, a linear gradient, signal-dependent noise.
//! Ground truth stays exact: intact tips are symmetric about their centre,
//! damaged tips and debris are measured by [`Shape::area_centroid`].
//!
//! Guard bands keep the truth away from every limit (an `ok` pin at most
//! 0.85 × `position_mm` off, a `bent` one at least 1.15 ×; a damaged tip's
//! area ratio at least 10 % beyond `tip_area`; debris at least 0.4 tips,
//! 1.6 × the extras' minimum): a wrong answer is the inspection's fault,
//! not a coin toss at a limit.

use super::envelope as env;
use super::fit::Similarity;
use super::gray::{Gray, GrayData, ImageInfo};
use super::recipe::{ExtrasRule, PinShape, Polarity, Recipe, Tolerance, View};
use super::result::{PinStatus, Verdict};
use super::synth::{Damage, Rng, Shape};
use super::truth::{Truth, TruthExtra, TruthPin};
use serde::Serialize;

/// How large an image is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SizeClass {
    /// 320 × 240 up to 0.4 MP.
    Small,
    /// 0.4–1.5 MP.
    Medium,
    /// 1.5–5 MP.
    Large,
}

impl SizeClass {
    fn pixels(self) -> (f64, f64) {
        match self {
            SizeClass::Small => (76_800.0, 400_000.0),
            SizeClass::Medium => (400_000.0, 1_500_000.0),
            SizeClass::Large => (1_500_000.0, env::MAX_PIXELS as f64),
        }
    }
}

/// Every drawn factor of one image (recorded in the truth's `render` and
/// binned by the envelope evaluation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Factors {
    pub seed: u64,
    pub view: View,
    pub polarity: Polarity,
    pub pin_shape: PinShape,
    pub rows: u32,
    pub cols: u32,
    pub mm_per_px: f64,
    /// Whether the recipe handed to the inspection carries `mm_per_px`.
    pub scale_in_recipe: bool,
    pub width: u32,
    pub height: u32,
    /// Tip width, px.
    pub tip_px: f64,
    pub rotation_deg: f64,
    pub centre_px: (f64, f64),
    pub contrast: f64,
    /// Noise σ at mid-grey, 8-bit DN.
    pub noise_dn: f64,
    pub blur_px: f64,
    /// Illumination fall-off at the farthest image corner.
    pub vignetting: f64,
    /// Illumination gradient across the part (peak to peak, fraction).
    pub gradient: f64,
    pub gain: f64,
    pub jpeg_quality: Option<u8>,
    /// Housing texture amplitude (8-bit DN, before contrast).
    pub texture_dn: f64,
    /// 8, 12 (in a 16-bit container) or 16.
    pub bits: u8,
    pub colour: bool,
    /// Width of the tips' soft edge (linear coverage ramp), px.
    pub edge_ramp_px: f64,
    /// Defects drawn, e.g. "missing", "bent", "extra".
    pub defects: Vec<String>,
}

impl Factors {
    /// Numeric factors by name (for binning).
    pub fn numeric(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("mm_per_px", self.mm_per_px),
            ("megapixels", self.width as f64 * self.height as f64 / 1e6),
            (
                "aspect",
                self.width.max(self.height) as f64 / self.width.min(self.height) as f64,
            ),
            ("tip_px", self.tip_px),
            ("rotation_abs_deg", self.rotation_deg.abs()),
            ("contrast", self.contrast),
            ("noise_dn", self.noise_dn),
            ("blur_px", self.blur_px),
            ("vignetting", self.vignetting),
            ("gradient", self.gradient),
            ("gain", self.gain),
            ("texture_dn", self.texture_dn),
            ("edge_ramp_px", self.edge_ramp_px),
        ]
    }

    /// Categorical factors by name.
    pub fn categories(&self) -> Vec<(&'static str, String)> {
        let s = |v: &dyn std::fmt::Debug| format!("{v:?}").to_lowercase();
        vec![
            ("view", s(&self.view)),
            ("polarity", s(&self.polarity)),
            ("pin_shape", s(&self.pin_shape)),
            ("rows", self.rows.to_string()),
            (
                "scale",
                if self.scale_in_recipe {
                    "in recipe".into()
                } else {
                    "estimated".into()
                },
            ),
            (
                "format",
                match self.jpeg_quality {
                    Some(q) if q < 75 => "jpeg q50-74".into(),
                    Some(_) => "jpeg q75-100".into(),
                    None => "lossless".into(),
                },
            ),
            ("bits", self.bits.to_string()),
            ("colour", if self.colour { "colour" } else { "grey" }.into()),
            (
                "defects",
                if self.defects.is_empty() {
                    "good part".into()
                } else {
                    self.defects.join("+")
                },
            ),
        ]
    }
}

/// Looks that vary but are not binned.
#[derive(Debug, Clone, PartialEq, Serialize)]
struct Look {
    /// Housing margin beyond the outer pins, mm (u, v).
    margin_mm: (f64, f64),
    corner_mm: f64,
    chamfer_mm: f64,
    /// Clearance hole size / pin size.
    hole_f: f64,
    /// Square tips: corner radius / half width.
    tip_corner: f64,
    /// Tip rim level / dome peak (bright) or core / rim (dark).
    dome: f64,
    /// Faint linear shading across a tip (fraction per half width).
    shading: f64,
    shading_dir: f64,
    vignette_centre: (f64, f64),
    gradient_dir: f64,
    /// Fraction of the noise variance independent of the signal (read noise).
    read_fraction: f64,
    tint: (f64, f64),
    levels: Levels,
    /// Side view: rounded (true) or chamfered (false) pin tips.
    round_tips: bool,
    /// Skipped positions show an empty hole (true) or none.
    skip_holes: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct Levels {
    bg: f64,
    housing: f64,
    chamfer: f64,
    hole: f64,
    mark: f64,
    tip_rim: f64,
    tip_peak: f64,
    bg_texture: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct CasePin {
    row: u32,
    col: u32,
    present: bool,
    offset_mm: (f64, f64),
    damage: Damage,
    /// Chipped tips: the cut's distance from the centre along (+u, −v), in
    /// half widths (the synth's `Chipped` fraction is unused here).
    height_mm: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct CaseExtra {
    /// Discs (u, v, r), mm, part frame.
    discs: Vec<(f64, f64, f64)>,
    opacity: f64,
}

/// One drawn image: the recipe handed to the inspection, the factors, and
/// the scene.
#[derive(Debug, Clone)]
pub struct EnvelopeCase {
    pub recipe: Recipe,
    pub factors: Factors,
    look: Look,
    pins: Vec<CasePin>,
    extras: Vec<CaseExtra>,
}

/// A rendered case.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub gray: Gray,
    pub info: ImageInfo,
    pub truth: Truth,
}

fn pick<T: Copy>(rng: &mut Rng, v: &[T]) -> T {
    v[((rng.uniform() * v.len() as f64) as usize).min(v.len() - 1)]
}

fn chance(rng: &mut Rng, p: f64) -> bool {
    rng.uniform() < p
}

fn log_uniform(rng: &mut Rng, a: f64, b: f64) -> f64 {
    (rng.range(a.ln(), b.ln())).exp()
}

/// Half extents (mm) of what must be in frame, in the part frame: (u, v
/// above, v below) — top view symmetric.
fn part_extent(r: &Recipe, look: &Look, max_height: f64) -> (f64, f64, f64) {
    let hu = (r.cols as f64 - 1.0) / 2.0 * r.pitch_mm[0] + look.margin_mm.0;
    match r.view {
        View::Top => {
            let hv = (r.rows as f64 - 1.0) / 2.0 * r.pitch_mm[1] + look.margin_mm.1;
            (hu, hv, hv)
        }
        View::Side => (hu, max_height + 0.4, 1.0),
    }
}

impl EnvelopeCase {
    /// Draws a case; the size class is drawn too (60 % small, 30 %
    /// medium, 10 % large).
    pub fn draw(seed: u64) -> EnvelopeCase {
        let mut rng = Rng::new(seed.wrapping_mul(0x9E37_79B9).wrapping_add(17));
        let u = rng.uniform();
        let class = if u < 0.6 {
            SizeClass::Small
        } else if u < 0.9 {
            SizeClass::Medium
        } else {
            SizeClass::Large
        };
        Self::draw_with(seed, class, None)
    }

    /// Draws a case of the given size class (and view, when given).
    pub fn draw_with(seed: u64, class: SizeClass, view: Option<View>) -> EnvelopeCase {
        let mut rng = Rng::new(seed ^ 0x00E1_5E1F);
        let view = view.unwrap_or_else(|| {
            if chance(&mut rng, 0.22) {
                View::Side
            } else {
                View::Top
            }
        });
        // Recipe.
        let pitches: [f64; 6] = [1.0, 1.27, 1.5, 2.0, 2.54, 3.0];
        let px_mm = pick(&mut rng, &pitches);
        let (rows, cols, py_mm) = match view {
            View::Top => {
                let rows = pick(&mut rng, &[1u32, 1, 2, 2, 2, 3, 4]);
                let cols = if rows == 1 {
                    rng.range(3.0, 17.0) as u32
                } else {
                    rng.range(2.0, 21.0) as u32
                };
                let py = if chance(&mut rng, 0.7) {
                    px_mm
                } else {
                    pick(&mut rng, &pitches).clamp(0.75 * px_mm, 1.6 * px_mm)
                };
                (rows, cols, py)
            }
            View::Side => (1, rng.range(2.0, 17.0) as u32, px_mm),
        };
        let min_pitch = if rows > 1 { px_mm.min(py_mm) } else { px_mm };
        let pin_mm = ((min_pitch * rng.range(0.2, 0.32)).max(0.3) * 100.0).round() / 100.0;
        let pin_shape = if view == View::Top && chance(&mut rng, 0.5) {
            PinShape::Round
        } else {
            PinShape::Square
        };
        let polarity = if view == View::Side || chance(&mut rng, 0.65) {
            if view == View::Side {
                Polarity::Dark
            } else {
                Polarity::Bright
            }
        } else {
            Polarity::Dark
        };
        let position_mm = ((0.04 * px_mm).clamp(0.05, 0.15) * 1000.0).round() / 1000.0;
        let (height_mm, height_tol_mm) = if view == View::Side {
            (
                (rng.range(1.5, 4.0) * 100.0).round() / 100.0,
                (rng.range(0.06, 0.15) * 1000.0).round() / 1000.0,
            )
        } else {
            (0.0, 0.0)
        };
        let mut skip = Vec::new();
        if view == View::Top && rows * cols >= 6 && chance(&mut rng, 0.25) {
            let n = 1 + (rng.uniform() * 2.0) as usize;
            for _ in 0..n {
                let s = [
                    (rng.uniform() * rows as f64) as u32,
                    (rng.uniform() * cols as f64) as u32,
                ];
                if !skip.contains(&s) {
                    skip.push(s);
                }
            }
        }
        let part_number = format!(
            "ENV-{}{}x{}-{:.2}",
            if view == View::Side { "S" } else { "" },
            rows,
            cols,
            px_mm
        );
        let mut recipe = Recipe {
            part_number,
            view,
            rows,
            cols,
            pitch_mm: [px_mm, py_mm],
            pin_mm,
            pin_shape,
            polarity,
            mm_per_px: None,
            skip,
            tolerance: Tolerance {
                position_mm,
                tip_area: None,
                height_mm: (view == View::Side).then_some(height_mm),
                height_tol_mm: (view == View::Side).then_some(height_tol_mm),
            },
            extras: ExtrasRule::default(),
        };

        // Looks.
        let bright = polarity == Polarity::Bright;
        let levels = if view == View::Side {
            let bg = rng.range(195.0, 235.0);
            let solid = rng.range(12.0, 35.0);
            Levels {
                bg,
                housing: solid,
                chamfer: solid,
                hole: solid,
                mark: solid,
                tip_rim: solid,
                tip_peak: solid,
                bg_texture: rng.range(1.0, 8.0),
            }
        } else if bright {
            let housing = rng.range(50.0, 75.0);
            let hole = rng.range(12.0, 28.0);
            let tip_rim = rng.range(175.0, 205.0);
            Levels {
                bg: rng.range(95.0, 140.0),
                housing,
                chamfer: housing + rng.range(15.0, 35.0),
                hole,
                mark: housing - 0.4 * (housing - hole),
                tip_rim,
                tip_peak: (tip_rim / rng.range(0.72, 0.9)).min(252.0),
                bg_texture: rng.range(1.0, 8.0),
            }
        } else {
            let housing = rng.range(150.0, 185.0);
            let hole = rng.range(225.0, 245.0);
            let tip_rim = rng.range(35.0, 70.0);
            Levels {
                bg: rng.range(200.0, 230.0),
                housing,
                chamfer: housing - rng.range(10.0, 30.0),
                hole,
                mark: housing + 0.3 * (hole - housing),
                tip_rim,
                tip_peak: tip_rim * rng.range(0.6, 0.9),
                bg_texture: rng.range(1.0, 8.0),
            }
        };
        let look = Look {
            margin_mm: (
                rng.range(0.5, 0.7) * px_mm,
                rng.range(0.5, 0.7) * py_mm.max(px_mm.min(py_mm)),
            ),
            corner_mm: rng.range(0.1, 0.4) * min_pitch,
            chamfer_mm: rng.range(0.08, 0.2) * min_pitch,
            hole_f: rng.range(1.15, 1.4),
            tip_corner: rng.range(0.0, 0.3),
            dome: if bright {
                levels.tip_rim / levels.tip_peak
            } else {
                levels.tip_peak / levels.tip_rim
            },
            shading: rng.range(0.0, 0.02),
            shading_dir: rng.range(0.0, std::f64::consts::TAU),
            vignette_centre: (rng.range(-0.1, 0.1), rng.range(-0.1, 0.1)),
            gradient_dir: rng.range(0.0, std::f64::consts::TAU),
            read_fraction: rng.range(0.3, 1.0),
            tint: (rng.range(0.85, 1.15), rng.range(0.85, 1.15)),
            levels,
            round_tips: chance(&mut rng, 0.5),
            skip_holes: chance(&mut rng, 0.5),
        };

        // Pose and size: the part must fit, the scale stays in the envelope.
        let rotation_deg = rng.range(-env::ROTATION_DEG, env::ROTATION_DEG);
        let max_height = height_mm + 4.0 * height_tol_mm.max(env::MIN_TOLERANCE_PX * env::MM_PER_PX.1);
        let (hu, hv_up, hv_down) = part_extent(&recipe, &look, max_height);
        let (sn, cs) = rotation_deg.to_radians().sin_cos();
        let (sn, cs) = (sn.abs(), cs.abs());
        let ext_x = cs * hu + sn * hv_up.max(hv_down) + 0.3;
        let ext_y = sn * hu + cs * hv_up.max(hv_down) + 0.3;
        let blur_px = rng.range(0.0, env::BLUR_PX);
        let margin_px = 3.0 * blur_px + 4.0;
        let mut class = class;
        let (mut width, mut height, mut mm_per_px) = (0u32, 0u32, 0.0);
        for attempt in 0..400 {
            if attempt == 200 && class != SizeClass::Large {
                class = SizeClass::Large;
            }
            let (a0, a1) = class.pixels();
            let area = log_uniform(&mut rng, a0, a1);
            let aspect = log_uniform(&mut rng, 1.0 / 3.0, 3.0);
            let w = (area * aspect).sqrt().round();
            let h = (area / aspect).sqrt().round();
            if w.min(h) < env::MIN_SIDES.1 as f64 || w.max(h) < env::MIN_SIDES.0 as f64 {
                continue;
            }
            if w * h > env::MAX_PIXELS as f64 {
                continue;
            }
            let s_fit = (2.0 * ext_x / (w - 2.0 * margin_px))
                .max(2.0 * ext_y / (h - 2.0 * margin_px))
                .max(0.0);
            let lo = env::MM_PER_PX.0.max(s_fit);
            let hi = env::MM_PER_PX.1.min(pin_mm / 6.0);
            if lo <= hi {
                width = w as u32;
                height = h as u32;
                mm_per_px = log_uniform(&mut rng, lo, hi);
                break;
            }
        }
        if width == 0 {
            // Nothing fits (a very long part): the coarsest scale on the
            // largest frame of a 3:1 aspect.
            mm_per_px = env::MM_PER_PX.1.min(pin_mm / 6.0);
            width = ((env::MAX_PIXELS as f64 * 3.0).sqrt()) as u32;
            height = (env::MAX_PIXELS as f64 / width as f64) as u32;
        }
        let (w, h) = (width as f64, height as f64);
        let (ex, ey) = (ext_x / mm_per_px + margin_px, ext_y / mm_per_px + margin_px);
        let cx = if w > 2.0 * ex {
            rng.range(ex, w - ex)
        } else {
            w / 2.0
        };
        let cy = match view {
            View::Top => {
                if h > 2.0 * ey {
                    rng.range(ey, h - ey)
                } else {
                    h / 2.0
                }
            }
            View::Side => {
                let up = (hv_up * cs + hu * sn) / mm_per_px + margin_px;
                let down = (hv_down + hu * sn) / mm_per_px + margin_px;
                if h > up + down {
                    rng.range(up, h - down)
                } else {
                    h * 0.6
                }
            }
        };
        // Tolerances a camera at this scale can resolve (the envelope's
        // MIN_TOLERANCE_PX): a line sets them so.
        let position_mm =
            (position_mm.max(env::MIN_TOLERANCE_PX * mm_per_px) * 1000.0).ceil() / 1000.0;
        recipe.tolerance.position_mm = position_mm;
        let height_tol_mm =
            (height_tol_mm.max(env::MIN_TOLERANCE_PX * mm_per_px) * 1000.0).ceil() / 1000.0;
        if view == View::Side {
            recipe.tolerance.height_tol_mm = Some(height_tol_mm);
        }
        let scale_in_recipe = chance(&mut rng, 0.5);
        if scale_in_recipe {
            recipe.mm_per_px = Some(mm_per_px);
        }
        let bits = pick(&mut rng, &[8u8, 8, 8, 12, 16]);
        let colour = chance(&mut rng, 0.25);
        let jpeg_quality = if bits == 8 && chance(&mut rng, 0.4) {
            Some(rng.range(env::JPEG_QUALITY_MIN as f64, 100.99) as u8)
        } else {
            None
        };
        let mut factors = Factors {
            seed,
            view,
            polarity,
            pin_shape,
            rows,
            cols,
            mm_per_px,
            scale_in_recipe,
            width,
            height,
            tip_px: pin_mm / mm_per_px,
            rotation_deg,
            centre_px: (cx, cy),
            contrast: rng.range(env::CONTRAST.0, env::CONTRAST.1),
            noise_dn: rng.range(0.0, env::NOISE_DN),
            blur_px,
            vignetting: rng.range(0.0, env::VIGNETTING),
            gradient: rng.range(0.0, env::GRADIENT),
            gain: rng.range(env::GAIN.0, env::GAIN.1),
            jpeg_quality,
            texture_dn: rng.range(1.0, 6.0),
            bits,
            colour,
            edge_ramp_px: rng.range(0.0, 1.0),
            defects: Vec::new(),
        };

        // Pins: small offsets, some near the tolerance; then defects.
        let tol = position_mm;
        let mut pins: Vec<CasePin> = recipe
            .positions()
            .into_iter()
            .map(|(row, col)| {
                let near = chance(&mut rng, 0.12);
                let r = if near {
                    rng.range(0.3, 0.85) * tol
                } else {
                    (0.05 * rng.normal()).abs().min(0.3) * tol
                };
                let a = rng.range(0.0, std::f64::consts::TAU);
                let offset_mm = if view == View::Side {
                    (0.0, 0.0)
                } else {
                    (r * a.cos(), r * a.sin())
                };
                let height = if view == View::Side {
                    height_mm + rng.range(-0.8, 0.8) * height_tol_mm
                } else {
                    0.0
                };
                CasePin {
                    row,
                    col,
                    present: true,
                    offset_mm,
                    damage: Damage::None,
                    height_mm: height,
                }
            })
            .collect();
        let mut extras = Vec::new();
        let mut case = EnvelopeCase {
            recipe: recipe.clone(),
            factors: factors.clone(),
            look,
            pins: Vec::new(),
            extras: Vec::new(),
        };
        if chance(&mut rng, 0.5) && !pins.is_empty() {
            let n = 1 + (rng.uniform() * 3.0) as usize;
            let kinds: &[&str] = match view {
                View::Top => &["missing", "bent", "damaged", "extra"],
                View::Side => &["missing", "short", "high", "bent", "extra"],
            };
            for _ in 0..n {
                let kind = pick(&mut rng, kinds);
                let i = (rng.uniform() * pins.len() as f64) as usize % pins.len();
                let done = match kind {
                    "extra" => case
                        .draw_extra(&mut rng, &pins, &extras)
                        .map(|e| extras.push(e))
                        .is_some(),
                    _ if pins[i].present
                        && pins[i].damage == Damage::None
                        && pins[i].offset_mm.0.hypot(pins[i].offset_mm.1) < 0.5 * tol
                        && (view == View::Top
                            || (pins[i].height_mm - height_mm).abs() < height_tol_mm) =>
                    {
                        let p = &mut pins[i];
                        match kind {
                            "missing" => p.present = false,
                            "bent" => {
                                let m = rng.range(1.15, 3.0) * tol;
                                let m = m.min(0.3 * min_pitch).max(1.15 * tol);
                                let a = rng.range(0.0, std::f64::consts::TAU);
                                p.offset_mm = if view == View::Side {
                                    (if chance(&mut rng, 0.5) { m } else { -m }, 0.0)
                                } else {
                                    (m * a.cos(), m * a.sin())
                                };
                            }
                            "short" => {
                                p.height_mm = height_mm - rng.range(1.15, 4.0) * height_tol_mm
                            }
                            "high" => {
                                p.height_mm = height_mm + rng.range(1.15, 4.0) * height_tol_mm
                            }
                            _ => {
                                // Damaged: redraw until its area ratio is
                                // clear of the limits by 10 %.
                                let [lo, hi] = recipe.tip_area();
                                for _ in 0..20 {
                                    let d = match (rng.uniform() * 4.0) as u32 {
                                        0 => Damage::Scaled(rng.range(0.55, 0.72)),
                                        1 => Damage::Scaled(rng.range(1.33, 1.5)),
                                        2 => Damage::Chipped(rng.range(-0.35, 0.0)),
                                        _ => Damage::Burr(rng.range(0.55, 0.75)),
                                    };
                                    let trial = CasePin {
                                        damage: d,
                                        ..p.clone()
                                    };
                                    let (a, _, _) = case.tip_shape(&trial).area_centroid();
                                    let ar = a * mm_per_px * mm_per_px / recipe.tip_area_mm2();
                                    if ar <= 0.9 * lo || ar >= 1.1 * hi {
                                        p.damage = d;
                                        break;
                                    }
                                }
                                if p.damage == Damage::None {
                                    p.damage = Damage::Scaled(0.6);
                                }
                            }
                        }
                        true
                    }
                    _ => false,
                };
                if done {
                    factors.defects.push(kind.to_string());
                }
            }
            factors.defects.sort();
        }
        case.pins = pins;
        case.extras = extras;
        case.factors = factors;
        case
    }

    fn sim(&self) -> Similarity {
        Similarity {
            s: 1.0 / self.factors.mm_per_px,
            theta: self.factors.rotation_deg.to_radians(),
            tx: self.factors.centre_px.0,
            ty: self.factors.centre_px.1,
        }
    }

    fn pin_uv(&self, p: &CasePin) -> (f64, f64) {
        let (u, v) = self.recipe.nominal_uv_mm(p.row, p.col);
        (u + p.offset_mm.0, v + p.offset_mm.1)
    }

    /// A piece of debris (top) or dust (side), clear of every tip and of
    /// every grid node by more than the assignment radius.
    fn draw_extra(
        &self,
        rng: &mut Rng,
        pins: &[CasePin],
        others: &[CaseExtra],
    ) -> Option<CaseExtra> {
        let r = &self.recipe;
        let f = &self.factors;
        let m = f.mm_per_px;
        let tip_mm2 = r.tip_area_mm2();
        let min_pitch = if r.rows > 1 {
            r.pitch_mm[0].min(r.pitch_mm[1])
        } else {
            r.pitch_mm[0]
        };
        let (hu, hv_up, hv_down) = part_extent(r, &self.look, 0.0);
        let reach_px = 2.5 * f.blur_px + f.edge_ramp_px + 2.0;
        for _ in 0..200 {
            let area_ratio = log_uniform(rng, 0.45, 2.5);
            let opacity = if r.view == View::Side {
                rng.range(0.8, 1.0)
            } else {
                1.0
            };
            // Main disc plus a smaller one: an irregular blob whose area is
            // then measured exactly.
            let a_mm2 = area_ratio * tip_mm2 / opacity;
            let r0 = (a_mm2 / (std::f64::consts::PI * 1.2)).sqrt();
            let (u, v) = match r.view {
                View::Top => (
                    rng.range(-hu - 0.6 * r.pitch_mm[0], hu + 0.6 * r.pitch_mm[0]),
                    rng.range(-hv_up - 0.6 * r.pitch_mm[0], hv_down + 0.6 * r.pitch_mm[0]),
                ),
                View::Side => (
                    rng.range(-hu, hu),
                    -rng.range(0.4, r.tolerance.height_mm.unwrap_or(2.0) + 0.8),
                ),
            };
            let ang = rng.range(0.0, std::f64::consts::TAU);
            let discs = vec![
                (u, v, r0),
                (
                    u + 0.7 * r0 * ang.cos(),
                    v + 0.7 * r0 * ang.sin(),
                    0.55 * r0,
                ),
            ];
            let outer = 1.45 * r0 + reach_px * m;
            // In frame.
            let sim = self.sim();
            let (x, y) = sim.apply(u, v);
            let o_px = outer / m + 2.0;
            if x < o_px || y < o_px || x > f.width as f64 - o_px || y > f.height as f64 - o_px {
                continue;
            }
            // Away from every grid node (infinitely extended) by 0.45 pitch
            // plus its size, and from every tip and other extra.
            let node_clear = match r.view {
                View::Top => {
                    let a = u / r.pitch_mm[0] + (r.cols as f64 - 1.0) / 2.0;
                    let b = v / r.pitch_mm[1] + (r.rows as f64 - 1.0) / 2.0;
                    let du = (a - a.round()) * r.pitch_mm[0];
                    let dv = (b - b.round()) * r.pitch_mm[1];
                    du.hypot(dv) > 0.45 * min_pitch + 1.45 * r0
                        && du.hypot(dv) > 0.5 * self.look.hole_f * r.pin_mm * 1.5 + outer
                }
                View::Side => {
                    let a = u / r.pitch_mm[0] + (r.cols as f64 - 1.0) / 2.0;
                    let du = (a - a.round()).abs() * r.pitch_mm[0];
                    du > 0.45 * min_pitch + 1.45 * r0 && du > 0.5 * r.pin_mm + outer + 0.2
                }
            };
            if !node_clear {
                continue;
            }
            let clear_of_pins = pins.iter().all(|p| {
                let (pu, pv) = self.pin_uv(p);
                match r.view {
                    View::Top => (pu - u).hypot(pv - v) > 1.5 * r.pin_mm + outer,
                    View::Side => (pu - u).abs() > r.pin_mm + outer,
                }
            });
            let clear_of_others = others.iter().all(|e| {
                let (eu, ev, er) = e.discs[0];
                (eu - u).hypot(ev - v) > 1.5 * (er + r0) + 2.0 * outer
            });
            // The orientation mark.
            let (mu, mv) = self.mark_uv();
            let clear_of_mark = r.view == View::Side
                || (mu - u).hypot(mv - v) > 0.3 * min_pitch + outer + 1.45 * r0;
            if clear_of_pins && clear_of_others && clear_of_mark {
                return Some(CaseExtra { discs, opacity });
            }
        }
        None
    }

    fn mark_uv(&self) -> (f64, f64) {
        let r = &self.recipe;
        let (u0, v0) = r.nominal_uv_mm(0, 0);
        let (mu, mv) = (self.look.margin_mm.0, self.look.margin_mm.1);
        (u0 - 0.55 * mu, v0 - 0.55 * mv)
    }

    /// Tip shape (top view) in pixels.
    fn tip_shape(&self, p: &CasePin) -> Shape {
        let r = &self.recipe;
        let sim = self.sim();
        let (u, v) = self.pin_uv(p);
        let scale = match p.damage {
            Damage::Scaled(f) => f,
            _ => 1.0,
        };
        let hw = r.pin_mm / 2.0 * scale;
        let base = match r.pin_shape {
            PinShape::Round => Shape::Disc {
                c: sim.apply(u, v),
                r: hw / self.factors.mm_per_px,
            },
            PinShape::Square => {
                let rc = self.look.tip_corner * hw;
                let mut pts = Vec::new();
                let corners = [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)];
                for (k, (sx, sy)) in corners.iter().enumerate() {
                    let c = (u + sx * (hw - rc), v + sy * (hw - rc));
                    if rc <= 1e-9 {
                        pts.push(sim.apply(u + sx * hw, v + sy * hw));
                        continue;
                    }
                    // Arc through the corner, 5 points.
                    let a0 = -std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::FRAC_PI_2;
                    for j in 0..5 {
                        let a = a0 + j as f64 / 4.0 * std::f64::consts::FRAC_PI_2;
                        pts.push(sim.apply(c.0 + rc * a.cos(), c.1 + rc * a.sin()));
                    }
                }
                Shape::Poly(pts)
            }
        };
        match p.damage {
            Damage::Chipped(d) => {
                // Everything beyond the line at distance d·hw from the centre
                // along (+u, −v)/√2 is cut away.
                let n = (
                    std::f64::consts::FRAC_1_SQRT_2,
                    -std::f64::consts::FRAC_1_SQRT_2,
                );
                let t = (n.1, -n.0);
                let big = 4.0 * hw;
                let c = (u + n.0 * d * hw, v + n.1 * d * hw);
                let cut = Shape::Poly(vec![
                    sim.apply(c.0 + t.0 * big, c.1 + t.1 * big),
                    sim.apply(c.0 + t.0 * big + n.0 * big, c.1 + t.1 * big + n.1 * big),
                    sim.apply(c.0 - t.0 * big + n.0 * big, c.1 - t.1 * big + n.1 * big),
                    sim.apply(c.0 - t.0 * big, c.1 - t.1 * big),
                ]);
                Shape::Minus(Box::new(base), Box::new(cut))
            }
            Damage::Burr(rf) => Shape::Union(vec![
                base,
                Shape::Disc {
                    c: sim.apply(u - hw, v + 0.4 * hw),
                    r: rf * r.pin_mm / self.factors.mm_per_px,
                },
            ]),
            _ => base,
        }
    }

    fn extra_shape(&self, e: &CaseExtra) -> Shape {
        let sim = self.sim();
        Shape::Union(
            e.discs
                .iter()
                .map(|&(u, v, r)| Shape::Disc {
                    c: sim.apply(u, v),
                    r: r / self.factors.mm_per_px,
                })
                .collect(),
        )
    }

    /// Renders the image (through the JPEG codec or the colour conversion
    /// when the case says so) and its truth.
    pub fn render(&self) -> Result<Rendered, String> {
        let f = &self.factors;
        let (w, h) = (f.width as usize, f.height as usize);
        let mut img = vec![0f32; w * h];
        let (truth_pins, truth_extras) = match self.recipe.view {
            View::Top => self.paint_top(&mut img),
            View::Side => self.paint_side(&mut img),
        };
        self.illuminate(&mut img);
        if f.blur_px > 0.2 {
            blur(&mut img, w, h, f.blur_px);
        }
        let (gray, info) = self.expose(&img)?;
        let verdict =
            if truth_pins.iter().all(|p| p.defect == PinStatus::Ok) && truth_extras.is_empty() {
                Verdict::Pass
            } else {
                Verdict::Fail
            };
        let truth = Truth {
            recipe: self.recipe.part_number.clone(),
            mm_per_px: Some(f.mm_per_px),
            verdict,
            pins: truth_pins,
            extras: truth_extras,
            render: Some(serde_json::json!({
                "generator": "pinsight::vision::synth_envelope",
                "factors": f,
                "look": self.look,
                "noise_sigma_dn": f.noise_dn,
            })),
        };
        Ok(Rendered { gray, info, truth })
    }

    fn contrast_level(&self, v: f64) -> f32 {
        let l = &self.look.levels;
        let pivot = if self.recipe.view == View::Side {
            l.bg
        } else {
            l.housing
        };
        (pivot + (v - pivot) * self.factors.contrast) as f32
    }

    fn paint_top(&self, img: &mut [f32]) -> (Vec<TruthPin>, Vec<TruthExtra>) {
        let f = &self.factors;
        let r = &self.recipe;
        let l = self.look.levels;
        let (w, h) = (f.width as usize, f.height as usize);
        let m = f.mm_per_px;
        let sim = self.sim();
        let c = f.contrast as f32;
        // Fixture background and housing, with texture.
        let tex_bg = ValueNoise::new(w, h, (1.2 / m).max(6.0), f.seed ^ 1);
        let tex_fine = ValueNoise::new(w, h, (0.06 / m).max(2.0), f.seed ^ 2);
        let tex_mid = ValueNoise::new(w, h, (0.25 / m).max(3.0), f.seed ^ 3);
        let bg = self.contrast_level(l.bg);
        for y in 0..h {
            for x in 0..w {
                let t = tex_bg.at(x, y) * 0.7 + tex_mid.at(x, y) * 0.3;
                img[y * w + x] = bg + c * l.bg_texture as f32 * t;
            }
        }
        let (hu, hv, _) = part_extent(r, &self.look, 0.0);
        let corner = self.look.corner_mm.min(0.9 * hu.min(hv));
        let chamfer = self.look.chamfer_mm;
        let bbox = housing_bbox(&sim, hu, hv);
        let tex_amp = c * f.texture_dn as f32;
        let housing = self.contrast_level(l.housing);
        let chamfer_l = self.contrast_level(l.chamfer);
        let sd_outer = |x: f64, y: f64| {
            let (u, v) = sim.inverse(x, y);
            rounded_rect_sd(u, v, hu, hv, corner) / m
        };
        paint(img, w, h, bbox, &sd_outer, 0.5, 4, 1.0, |x, y| {
            chamfer_l + tex_amp * tex_fine.at(x, y)
        });
        let sd_inner = |x: f64, y: f64| {
            let (u, v) = sim.inverse(x, y);
            rounded_rect_sd(
                u,
                v,
                hu - chamfer,
                hv - chamfer,
                (corner - chamfer).max(0.02),
            ) / m
        };
        paint(img, w, h, bbox, &sd_inner, 0.8, 4, 1.0, |x, y| {
            housing + tex_amp * (0.6 * tex_fine.at(x, y) + 0.4 * tex_mid.at(x, y))
        });
        // Orientation mark beside pin (0, 0): a small triangle, embossed.
        let (mu, mv) = self.mark_uv();
        let ms = 0.22 * r.pitch_mm[0].min(r.pitch_mm[1]);
        let mark = Shape::Poly(vec![
            sim.apply(mu - ms, mv + ms * 0.6),
            sim.apply(mu + ms, mv + ms * 0.6),
            sim.apply(mu, mv - ms),
        ]);
        let mark_l = self.contrast_level(l.mark);
        paint_shape(img, w, h, &mark, 0.5, 4, 1.0, |_, _| mark_l);
        // Clearance holes (skipped positions: an empty hole or none).
        let hole_l = self.contrast_level(l.hole);
        let hole_half = 0.5 * self.look.hole_f * r.pin_mm;
        for row in 0..r.rows {
            for col in 0..r.cols {
                if r.is_skipped(row, col) && !self.look.skip_holes {
                    continue;
                }
                let (u, v) = r.nominal_uv_mm(row, col);
                let hole = match r.pin_shape {
                    PinShape::Round => Shape::Disc {
                        c: sim.apply(u, v),
                        r: hole_half / m,
                    },
                    PinShape::Square => Shape::Poly(vec![
                        sim.apply(u - hole_half, v - hole_half),
                        sim.apply(u + hole_half, v - hole_half),
                        sim.apply(u + hole_half, v + hole_half),
                        sim.apply(u - hole_half, v + hole_half),
                    ]),
                };
                paint_shape(img, w, h, &hole, 0.4, 4, 1.0, |_, _| hole_l);
            }
        }
        // Tips.
        let rim = self.contrast_level(l.tip_rim);
        let peak = self.contrast_level(l.tip_peak);
        let tip_px = r.tip_area_mm2() / (m * m);
        let [ta_lo, ta_hi] = r.tip_area();
        let tol = r.tolerance.position_mm;
        let mut truth_pins = Vec::new();
        for p in &self.pins {
            if !p.present {
                truth_pins.push(TruthPin {
                    row: p.row,
                    col: p.col,
                    x_px: None,
                    y_px: None,
                    defect: PinStatus::Missing,
                    height_mm: None,
                    area_ratio: None,
                    offset_mm: None,
                });
                continue;
            }
            let shape = self.tip_shape(p);
            let (area, cx, cy) = match p.damage {
                Damage::None => {
                    let (u, v) = self.pin_uv(p);
                    let (cx, cy) = sim.apply(u, v);
                    // Area of the rounded square / disc in closed form.
                    let hw = r.pin_mm / 2.0;
                    let a_mm = match r.pin_shape {
                        PinShape::Round => std::f64::consts::PI * hw * hw,
                        PinShape::Square => {
                            let rc = self.look.tip_corner * hw;
                            4.0 * hw * hw - (4.0 - std::f64::consts::PI) * rc * rc
                        }
                    };
                    (a_mm / (m * m), cx, cy)
                }
                _ => shape.area_centroid(),
            };
            let rad = 0.5 * r.pin_mm / m;
            let (sd, cd) = self.look.shading_dir.sin_cos();
            let shading = self.look.shading as f32;
            let domed = p.damage == Damage::None;
            paint_shape(img, w, h, &shape, f.edge_ramp_px, 8, 1.0, |x, y| {
                let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                let q = ((dx * dx + dy * dy) / (rad * rad)).min(1.0) as f32;
                let base = if domed { peak + (rim - peak) * q } else { rim };
                base * (1.0 + shading * ((dx * cd + dy * sd) / rad) as f32)
            });
            let ar = area / tip_px;
            let off = p.offset_mm.0.hypot(p.offset_mm.1);
            let defect = if ar < ta_lo || ar > ta_hi {
                PinStatus::Damaged
            } else if off > tol {
                PinStatus::Bent
            } else {
                PinStatus::Ok
            };
            truth_pins.push(TruthPin {
                row: p.row,
                col: p.col,
                x_px: Some(cx),
                y_px: Some(cy),
                defect,
                height_mm: None,
                area_ratio: Some(ar),
                offset_mm: Some(off),
            });
        }
        let mut truth_extras = Vec::new();
        for e in &self.extras {
            let s = self.extra_shape(e);
            paint_shape(
                img,
                w,
                h,
                &s,
                f.edge_ramp_px,
                4,
                e.opacity as f32,
                |_, _| rim,
            );
            let (_, cx, cy) = s.area_centroid();
            truth_extras.push(TruthExtra {
                x_px: cx,
                y_px: cy,
                kind: Some("debris".into()),
            });
        }
        (truth_pins, truth_extras)
    }

    fn paint_side(&self, img: &mut [f32]) -> (Vec<TruthPin>, Vec<TruthExtra>) {
        let f = &self.factors;
        let r = &self.recipe;
        let l = self.look.levels;
        let (w, h) = (f.width as usize, f.height as usize);
        let m = f.mm_per_px;
        let sim = self.sim();
        let c = f.contrast as f32;
        let mottle = ValueNoise::new(w, h, (1.5 / m).max(8.0), f.seed ^ 5);
        let grain = ValueNoise::new(w, h, (0.08 / m).max(2.0), f.seed ^ 6);
        let bg = self.contrast_level(l.bg);
        for y in 0..h {
            for x in 0..w {
                img[y * w + x] = bg + c * l.bg_texture as f32 * mottle.at(x, y);
            }
        }
        let solid = self.contrast_level(l.housing);
        let tex_amp = c * f.texture_dn as f32;
        let hu = (r.cols as f64 - 1.0) / 2.0 * r.pitch_mm[0] + self.look.margin_mm.0;
        let depth = (w + h) as f64 * m * 2.0;
        let block = Shape::Poly(vec![
            sim.apply(-hu, 0.0),
            sim.apply(hu, 0.0),
            sim.apply(hu, depth),
            sim.apply(-hu, depth),
        ]);
        paint_shape(img, w, h, &block, 0.3, 4, 1.0, |x, y| {
            solid + tex_amp * grain.at(x, y)
        });
        let tol = &r.tolerance;
        let h_nom = tol.height_mm.unwrap_or(0.0);
        let h_tol = tol.height_tol_mm.unwrap_or(f64::INFINITY);
        let mut truth_pins = Vec::new();
        for p in &self.pins {
            let (u, _) = r.nominal_uv_mm(p.row, p.col);
            let u = u + p.offset_mm.0;
            if !p.present {
                truth_pins.push(TruthPin {
                    row: p.row,
                    col: p.col,
                    x_px: None,
                    y_px: None,
                    defect: PinStatus::Missing,
                    height_mm: None,
                    area_ratio: None,
                    offset_mm: None,
                });
                continue;
            }
            let hw = r.pin_mm / 2.0;
            let top = -p.height_mm;
            let mut pts = vec![(u - hw, 0.1)];
            if self.look.round_tips {
                for j in 0..=8 {
                    let a = std::f64::consts::PI * (1.0 - j as f64 / 8.0);
                    pts.push((u + hw * a.cos(), top + hw - hw * a.sin()));
                }
            } else {
                let ch = (0.3 * hw).min(0.08);
                pts.extend([
                    (u - hw, top + ch),
                    (u - hw + ch, top),
                    (u + hw - ch, top),
                    (u + hw, top + ch),
                ]);
            }
            pts.push((u + hw, 0.1));
            let bar = Shape::Poly(pts.iter().map(|&(a, b)| sim.apply(a, b)).collect());
            paint_shape(img, w, h, &bar, f.edge_ramp_px, 4, 1.0, |_, _| solid);
            let (tx, ty) = sim.apply(u, top);
            let defect = if p.offset_mm.0.abs() > tol.position_mm {
                PinStatus::Bent
            } else if p.height_mm < h_nom - h_tol {
                PinStatus::Short
            } else if p.height_mm > h_nom + h_tol {
                PinStatus::High
            } else {
                PinStatus::Ok
            };
            truth_pins.push(TruthPin {
                row: p.row,
                col: p.col,
                x_px: Some(tx),
                y_px: Some(ty),
                defect,
                height_mm: Some(p.height_mm),
                area_ratio: None,
                offset_mm: Some(p.offset_mm.0.abs()),
            });
        }
        let mut truth_extras = Vec::new();
        for e in &self.extras {
            let s = self.extra_shape(e);
            paint_shape(
                img,
                w,
                h,
                &s,
                f.edge_ramp_px,
                4,
                e.opacity as f32,
                |_, _| solid,
            );
            let (_, cx, cy) = s.area_centroid();
            truth_extras.push(TruthExtra {
                x_px: cx,
                y_px: cy,
                kind: Some("dust".into()),
            });
        }
        (truth_pins, truth_extras)
    }

    /// Vignetting (off-centre, `1 / (1 + k r²)²`, `k` set by the fall-off
    /// at the farthest corner) times a linear gradient across the part.
    fn illuminate(&self, img: &mut [f32]) {
        let f = &self.factors;
        let (w, h) = (f.width as usize, f.height as usize);
        let (vx, vy) = (
            w as f64 * (0.5 + self.look.vignette_centre.0),
            h as f64 * (0.5 + self.look.vignette_centre.1),
        );
        let r0 = 0.5 * (w as f64).hypot(h as f64);
        let rc2 = [
            (0.0, 0.0),
            (w as f64, 0.0),
            (0.0, h as f64),
            (w as f64, h as f64),
        ]
        .iter()
        .map(|&(x, y)| ((x - vx).powi(2) + (y - vy).powi(2)) / (r0 * r0))
        .fold(0.0, f64::max);
        let k = ((1.0 - f.vignetting).powf(-0.5) - 1.0) / rc2.max(1e-9);
        let (gs, gc) = self.look.gradient_dir.sin_cos();
        let (hu, hv_up, hv_down) = part_extent(&self.recipe, &self.look, 0.0);
        let span_px = 2.0 * (hu * gc.abs() + hv_up.max(hv_down) * gs.abs()) / f.mm_per_px;
        let g = f.gradient / span_px.max(1.0);
        let (cx, cy) = f.centre_px;
        for y in 0..h {
            let dy = y as f64 - vy;
            for x in 0..w {
                let dx = x as f64 - vx;
                let q = 1.0 + k * (dx * dx + dy * dy) / (r0 * r0);
                let grad = 1.0 + g * ((x as f64 - cx) * gc + (y as f64 - cy) * gs);
                img[y * w + x] *= (grad.max(0.05) / (q * q)) as f32;
            }
        }
    }

    /// Gain, clipping, noise, quantisation; then grey/colour, bit depth and
    /// JPEG as drawn.
    fn expose(&self, img: &[f32]) -> Result<(Gray, ImageInfo), String> {
        let f = &self.factors;
        let (w, h) = (f.width, f.height);
        let full = match f.bits {
            8 => 255.0,
            12 => 4095.0,
            _ => 65535.0,
        };
        let to_fs = full / 255.0;
        let mut rng = Rng::new(f.seed ^ 0xA5A5);
        let sigma = f.noise_dn as f32;
        let rf = self.look.read_fraction as f32;
        let gain = f.gain as f32;
        // Values in 8-bit units after gain and noise (unclipped).
        let mut spare: Option<f32> = None;
        let mut normal = || -> f32 {
            if let Some(v) = spare.take() {
                return v;
            }
            let u1 = rng.uniform().max(1e-300);
            let u2 = rng.uniform();
            let r = (-2.0 * u1.ln()).sqrt();
            let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
            spare = Some((r * s) as f32);
            (r * c) as f32
        };
        let vals: Vec<f32> = img
            .iter()
            .map(|&v| {
                let v = v * gain;
                let var = rf + (1.0 - rf) * (v.max(0.0) / 128.0);
                v + sigma * var.sqrt() * normal()
            })
            .collect();
        let q8 = |v: f32| v.round().clamp(0.0, 255.0) as u8;
        let q16 = |v: f32| (v * to_fs as f32).round().clamp(0.0, full as f32) as u16;
        let info = |channels: u8, bit_depth: u8, format: &str| ImageInfo {
            width: w,
            height: h,
            channels,
            bit_depth,
            format: format.into(),
        };
        if f.colour {
            let (tr, tb) = self.look.tint;
            let tg = (1.0 - 0.2126 * tr - 0.0722 * tb) / 0.7152;
            let t = [tr as f32, tg as f32, tb as f32];
            let dynimg = if f.bits == 8 {
                let px: Vec<u8> = vals
                    .iter()
                    .flat_map(|&v| [q8(v * t[0]), q8(v * t[1]), q8(v * t[2])])
                    .collect();
                image::DynamicImage::ImageRgb8(
                    image::RgbImage::from_raw(w, h, px).ok_or("rgb buffer")?,
                )
            } else {
                let px: Vec<u16> = vals
                    .iter()
                    .flat_map(|&v| [q16(v * t[0]), q16(v * t[1]), q16(v * t[2])])
                    .collect();
                image::DynamicImage::ImageRgb16(
                    image::ImageBuffer::from_raw(w, h, px).ok_or("rgb16 buffer")?,
                )
            };
            if let Some(q) = f.jpeg_quality {
                return jpeg_roundtrip(&dynimg.to_rgb8().into(), q);
            }
            let channels = 3;
            let bd = if f.bits == 8 { 8 } else { 16 };
            return Ok((super::image_io::to_gray(dynimg), info(channels, bd, "png")));
        }
        if f.bits == 8 {
            let px: Vec<u8> = vals.iter().map(|&v| q8(v)).collect();
            if let Some(q) = f.jpeg_quality {
                let g = image::GrayImage::from_raw(w, h, px).ok_or("grey buffer")?;
                return jpeg_roundtrip(&image::DynamicImage::ImageLuma8(g), q);
            }
            return Ok((
                Gray {
                    width: w,
                    height: h,
                    data: GrayData::U8(px),
                },
                info(1, 8, "png"),
            ));
        }
        let px: Vec<u16> = vals.iter().map(|&v| q16(v)).collect();
        Ok((
            Gray {
                width: w,
                height: h,
                data: GrayData::U16(px),
            },
            info(1, 16, "png"),
        ))
    }
}

fn jpeg_roundtrip(img: &image::DynamicImage, q: u8) -> Result<(Gray, ImageInfo), String> {
    let mut bytes = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, q);
    img.write_with_encoder(enc).map_err(|e| e.to_string())?;
    super::image_io::decode_bytes(&bytes).map_err(|e| e.to_string())
}

/// Signed distance to a rectangle [−hu, hu] × [−hv, hv] with corners
/// rounded by `r` (negative inside).
fn rounded_rect_sd(u: f64, v: f64, hu: f64, hv: f64, r: f64) -> f64 {
    let qx = u.abs() - (hu - r);
    let qy = v.abs() - (hv - r);
    qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0) - r
}

fn housing_bbox(sim: &Similarity, hu: f64, hv: f64) -> (f64, f64, f64, f64) {
    let pts = [
        sim.apply(-hu, -hv),
        sim.apply(hu, -hv),
        sim.apply(hu, hv),
        sim.apply(-hu, hv),
    ];
    pts.iter().fold(
        (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |b, p| (b.0.min(p.0), b.1.min(p.1), b.2.max(p.0), b.3.max(p.1)),
    )
}

/// Pixel coverage of a shape given by its signed distance (px), with a
/// linear ramp of `ramp` px across the edge (0: a hard edge), integrated
/// over `n` × `n` sub-samples where the edge is near.
#[inline]
fn coverage(sd: &dyn Fn(f64, f64) -> f64, x: f64, y: f64, ramp: f64, n: usize) -> f32 {
    let d = sd(x, y);
    let reach = 0.75 + 0.5 * ramp;
    if d > reach {
        return 0.0;
    }
    if d < -reach {
        return 1.0;
    }
    let mut acc = 0.0;
    for j in 0..n {
        for i in 0..n {
            let sx = x - 0.5 + (i as f64 + 0.5) / n as f64;
            let sy = y - 0.5 + (j as f64 + 0.5) / n as f64;
            let ds = sd(sx, sy);
            acc += if ramp > 1e-3 {
                (0.5 - ds / ramp).clamp(0.0, 1.0)
            } else if ds < 0.0 {
                1.0
            } else {
                0.0
            };
        }
    }
    (acc / (n * n) as f64) as f32
}

#[allow(clippy::too_many_arguments)]
fn paint(
    img: &mut [f32],
    w: usize,
    h: usize,
    bbox: (f64, f64, f64, f64),
    sd: &dyn Fn(f64, f64) -> f64,
    ramp: f64,
    n: usize,
    alpha: f32,
    level: impl Fn(usize, usize) -> f32,
) {
    let pad = 2.0 + ramp;
    let xa = ((bbox.0 - pad).floor().max(0.0)) as usize;
    let ya = ((bbox.1 - pad).floor().max(0.0)) as usize;
    let xb = ((bbox.2 + pad).ceil().max(0.0) as usize).min(w.saturating_sub(1));
    let yb = ((bbox.3 + pad).ceil().max(0.0) as usize).min(h.saturating_sub(1));
    for y in ya..=yb {
        for x in xa..=xb {
            let c = coverage(sd, x as f64, y as f64, ramp, n) * alpha;
            if c > 0.0 {
                let i = y * w + x;
                img[i] = img[i] * (1.0 - c) + level(x, y) * c;
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn paint_shape(
    img: &mut [f32],
    w: usize,
    h: usize,
    shape: &Shape,
    ramp: f64,
    n: usize,
    alpha: f32,
    level: impl Fn(usize, usize) -> f32,
) {
    let sd = |x: f64, y: f64| shape.signed_distance((x, y));
    paint(img, w, h, shape.bbox(), &sd, ramp, n, alpha, level);
}

/// Smooth value noise in [−1, 1]: random values on a lattice of `cell` px,
/// interpolated bilinearly.
struct ValueNoise {
    cell: f64,
    gw: usize,
    vals: Vec<f32>,
}

impl ValueNoise {
    fn new(w: usize, h: usize, cell: f64, seed: u64) -> ValueNoise {
        let cell = cell.max(1.0);
        let gw = (w as f64 / cell) as usize + 3;
        let gh = (h as f64 / cell) as usize + 3;
        let mut rng = Rng::new(seed);
        let vals = (0..gw * gh)
            .map(|_| (2.0 * rng.uniform() - 1.0) as f32)
            .collect();
        ValueNoise { cell, gw, vals }
    }

    #[inline]
    fn at(&self, x: usize, y: usize) -> f32 {
        let fx = x as f64 / self.cell;
        let fy = y as f64 / self.cell;
        let (ix, iy) = (fx as usize, fy as usize);
        let (tx, ty) = ((fx - ix as f64) as f32, (fy - iy as f64) as f32);
        let i = iy * self.gw + ix;
        let a = self.vals[i] + (self.vals[i + 1] - self.vals[i]) * tx;
        let b = self.vals[i + self.gw] + (self.vals[i + self.gw + 1] - self.vals[i + self.gw]) * tx;
        a + (b - a) * ty
    }
}

/// Separable Gaussian blur (σ px), edges clamped.
fn blur(img: &mut [f32], w: usize, h: usize, sigma: f64) {
    let rad = (3.0 * sigma).ceil() as usize;
    let k: Vec<f32> = (0..=2 * rad)
        .map(|i| {
            let d = i as f64 - rad as f64;
            (-(d * d) / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    let sum: f32 = k.iter().sum();
    let k: Vec<f32> = k.iter().map(|v| v / sum).collect();
    let mut line = vec![0f32; w.max(h) + 2 * rad];
    for y in 0..h {
        let row = &mut img[y * w..(y + 1) * w];
        for (i, l) in line[..w + 2 * rad].iter_mut().enumerate() {
            *l = row[(i as i64 - rad as i64).clamp(0, w as i64 - 1) as usize];
        }
        for (x, o) in row.iter_mut().enumerate() {
            *o = k
                .iter()
                .zip(&line[x..x + 2 * rad + 1])
                .map(|(a, b)| a * b)
                .sum();
        }
    }
    let mut col = vec![0f32; h];
    for x in 0..w {
        for (i, l) in line[..h + 2 * rad].iter_mut().enumerate() {
            *l = img[(i as i64 - rad as i64).clamp(0, h as i64 - 1) as usize * w + x];
        }
        for (y, o) in col.iter_mut().enumerate() {
            *o = k
                .iter()
                .zip(&line[y..y + 2 * rad + 1])
                .map(|(a, b)| a * b)
                .sum();
        }
        for (y, v) in col.iter().enumerate() {
            img[y * w + x] = *v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_stay_inside_the_envelope_and_parts_fit() {
        for seed in 0..300 {
            let c = EnvelopeCase::draw(seed);
            let f = &c.factors;
            assert!(
                c.recipe.validate().is_ok(),
                "{seed}: {:?}",
                c.recipe.validate()
            );
            assert!(
                f.mm_per_px >= env::MM_PER_PX.0 - 1e-12 && f.mm_per_px <= env::MM_PER_PX.1 + 1e-12,
                "{seed}: {}",
                f.mm_per_px
            );
            assert!(f.width as u64 * f.height as u64 <= env::MAX_PIXELS);
            assert!(f.width.min(f.height) >= 240 && f.width.max(f.height) >= 320);
            assert!(f.rotation_deg.abs() <= env::ROTATION_DEG);
            assert!((env::CONTRAST.0..=env::CONTRAST.1).contains(&f.contrast));
            assert!((env::GAIN.0..=env::GAIN.1).contains(&f.gain));
            // Every node of the grid inside the frame.
            let sim = c.sim();
            for p in &c.pins {
                let (u, v) = c.pin_uv(p);
                let (x, y) = sim.apply(u, v);
                assert!(
                    x > 0.0 && y > 0.0 && x < f.width as f64 && y < f.height as f64,
                    "{seed}"
                );
            }
        }
    }

    #[test]
    fn rendered_truth_agrees_with_the_image() {
        // Clean, sharp top-view cases with large tips: each intact tip's
        // intensity centroid (hole level subtracted) over the pixels well
        // inside its clearance hole is its truth centre.
        let mut checked = 0;
        for seed in 0..200 {
            let mut c = EnvelopeCase::draw_with(seed, SizeClass::Small, Some(View::Top));
            if c.factors.tip_px < 12.0 {
                continue;
            }
            c.factors.noise_dn = 0.0;
            c.factors.blur_px = 0.0;
            c.factors.vignetting = 0.0;
            c.factors.gradient = 0.0;
            c.factors.gain = 1.0;
            c.factors.jpeg_quality = None;
            c.factors.colour = false;
            c.factors.bits = 16;
            c.factors.edge_ramp_px = 0.6;
            c.look.shading = 0.0;
            c.look.hole_f = 1.4;
            for p in &mut c.pins {
                p.damage = Damage::None;
                p.present = true;
                p.offset_mm = (0.0, 0.0);
            }
            c.extras.clear();
            let r = c.render().unwrap();
            assert_eq!(r.truth.verdict, Verdict::Pass);
            let m = c.factors.mm_per_px;
            let sim = c.sim();
            let hole_half = 0.5 * c.look.hole_f * c.recipe.pin_mm - 0.7 * m;
            let hole_l = c.contrast_level(c.look.levels.hole) as f64 * 65535.0 / 255.0;
            let sign = if c.recipe.polarity == Polarity::Dark {
                -1.0
            } else {
                1.0
            };
            for t in &r.truth.pins {
                let (tx, ty) = (t.x_px.unwrap(), t.y_px.unwrap());
                let (nu, nv) = c.recipe.nominal_uv_mm(t.row, t.col);
                let reach = (hole_half / m).ceil() as i64 + 2;
                let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
                for y in (ty.round() as i64 - reach)..=(ty.round() as i64 + reach) {
                    for x in (tx.round() as i64 - reach)..=(tx.round() as i64 + reach) {
                        let (u, v) = sim.inverse(x as f64, y as f64);
                        let (du, dv) = (u - nu, v - nv);
                        let inside = match c.recipe.pin_shape {
                            PinShape::Round => du.hypot(dv) < hole_half,
                            PinShape::Square => du.abs() < hole_half && dv.abs() < hole_half,
                        };
                        if !inside {
                            continue;
                        }
                        let v = sign * (r.gray.get(x as u32, y as u32) as f64 - hole_l);
                        sw += v;
                        sx += v * x as f64;
                        sy += v * y as f64;
                    }
                }
                assert!(
                    (sx / sw - tx).abs() < 0.02 && (sy / sw - ty).abs() < 0.02,
                    "seed {seed} {t:?}: {} {}",
                    sx / sw,
                    sy / sw
                );
            }
            checked += 1;
            if checked == 4 {
                break;
            }
        }
        assert_eq!(checked, 4);
    }
}
