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
use super::result::PinStatus;
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

impl Rendered {
    /// Compares an inspection of this image with its truth; extras are
    /// matched within half a tip (at least 4 px) plus 6 px.
    pub fn compare(&self, f: &Factors, ins: &super::Inspection) -> super::truth::Comparison {
        super::truth::compare(ins, &self.truth, 0.5 * f.tip_px.max(8.0) + 6.0)
    }

    /// Centre errors (px) of the pins that are truly ok, from a comparison.
    pub fn ok_centre_errors(c: &super::truth::Comparison) -> Vec<f64> {
        c.centre_errors
            .iter()
            .filter(|e| e.2 == PinStatus::Ok)
            .map(|e| e.3.hypot(e.4))
            .collect()
    }
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
        let max_height =
            height_mm + 4.0 * height_tol_mm.max(env::MIN_TOLERANCE_PX * env::MM_PER_PX.1);
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
}

mod bound;
mod paint;
mod raster;
#[cfg(test)]
mod tests;
