//! Synthetic connector images with exact ground truth, for tests, the
//! fixtures (`examples/gen_images.rs`) and the methods lab.
//!
//! Every shape is a polygon, disc or a union / difference of them in pixel
//! coordinates; each pixel's coverage is integrated with 8 × 8 sub-samples
//! where the shape's edge passes through it (an exact early-out elsewhere),
//! so edges are anti-aliased and the truth is exact: intact tips are
//! symmetric about their centre, and the centre of a damaged tip or a
//! debris blob is its area centroid integrated from the same coverage.
//! Layers are composited in order (background, housing, frame, holes, tips,
//! debris), then blurred (Gaussian), then Gaussian noise of `noise_dn`
//! (8-bit DN; scaled to the container for 16-bit) is added and the result
//! quantised.
//!
//! The random numbers come from SplitMix64 written out here, so a fixture
//! regenerated with another version of any crate is bit-identical.

use super::gray::{Gray, GrayData};
use super::recipe::{PinShape, Polarity, Recipe, View};
use super::truth::{Truth, TruthExtra, TruthPin};

/// The image generator's random numbers (see [`crate::rng`]).
pub type Rng = crate::rng::SplitMix64<0x5DEE_CE66_D1CE_4E5B>;

/// A shape in pixel coordinates.
#[derive(Debug, Clone)]
pub enum Shape {
    /// Convex polygon, vertices in order (either orientation).
    Poly(Vec<(f64, f64)>),
    Disc {
        c: (f64, f64),
        r: f64,
    },
    Union(Vec<Shape>),
    /// First minus second.
    Minus(Box<Shape>, Box<Shape>),
}

impl Shape {
    /// A lower bound of the distance to the boundary with the sign of the
    /// exact inside test (negative inside).
    fn sd(&self, p: (f64, f64)) -> f64 {
        match self {
            Shape::Disc { c, r } => (p.0 - c.0).hypot(p.1 - c.1) - r,
            Shape::Poly(v) => {
                // Max of signed distances to the edge lines (exact inside,
                // a lower bound outside). Orientation from the signed area.
                let n = v.len();
                let mut area = 0.0;
                for i in 0..n {
                    let (a, b) = (v[i], v[(i + 1) % n]);
                    area += a.0 * b.1 - b.0 * a.1;
                }
                let s = if area > 0.0 { 1.0 } else { -1.0 };
                let mut d = f64::NEG_INFINITY;
                for i in 0..n {
                    let (a, b) = (v[i], v[(i + 1) % n]);
                    let (ex, ey) = (b.0 - a.0, b.1 - a.1);
                    let len = ex.hypot(ey).max(1e-12);
                    // Outward normal for counter-clockwise (area > 0) order in y-down axes.
                    let (nx, ny) = (ey / len * s, -ex / len * s);
                    d = d.max((p.0 - a.0) * nx + (p.1 - a.1) * ny);
                }
                d
            }
            Shape::Union(v) => v.iter().map(|s| s.sd(p)).fold(f64::INFINITY, f64::min),
            Shape::Minus(a, b) => a.sd(p).max(-b.sd(p)),
        }
    }

    /// Signed distance to the boundary (px; negative inside): exact
    /// inside, a lower bound outside (see [`Shape::coverage`]).
    pub fn signed_distance(&self, p: (f64, f64)) -> f64 {
        self.sd(p)
    }

    fn inside(&self, p: (f64, f64)) -> bool {
        self.sd(p) < 0.0
    }

    /// Fraction of pixel (x, y) covered (8 × 8 sub-samples on edges).
    pub fn coverage(&self, x: f64, y: f64) -> f64 {
        let d = self.sd((x, y));
        if d > 0.75 {
            return 0.0;
        }
        if d < -0.75 {
            return 1.0;
        }
        const N: usize = 8;
        let mut k = 0;
        for j in 0..N {
            for i in 0..N {
                let sx = x - 0.5 + (i as f64 + 0.5) / N as f64;
                let sy = y - 0.5 + (j as f64 + 0.5) / N as f64;
                if self.inside((sx, sy)) {
                    k += 1;
                }
            }
        }
        k as f64 / (N * N) as f64
    }

    /// Bounding box (x0, y0, x1, y1).
    pub fn bbox(&self) -> (f64, f64, f64, f64) {
        match self {
            Shape::Disc { c, r } => (c.0 - r, c.1 - r, c.0 + r, c.1 + r),
            Shape::Poly(v) => v.iter().fold(
                (
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ),
                |b, p| (b.0.min(p.0), b.1.min(p.1), b.2.max(p.0), b.3.max(p.1)),
            ),
            Shape::Union(v) => v.iter().map(|s| s.bbox()).fold(
                (
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ),
                |b, q| (b.0.min(q.0), b.1.min(q.1), b.2.max(q.2), b.3.max(q.3)),
            ),
            Shape::Minus(a, _) => a.bbox(),
        }
    }

    /// Area (px²) and area centroid by the same coverage integration.
    pub fn area_centroid(&self) -> (f64, f64, f64) {
        let (x0, y0, x1, y1) = self.bbox();
        let (mut a, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for y in (y0.floor() as i64 - 1)..=(y1.ceil() as i64 + 1) {
            for x in (x0.floor() as i64 - 1)..=(x1.ceil() as i64 + 1) {
                // Finer integration for the truth: 4 × 4 quadrants of 8 × 8.
                let mut c = 0.0;
                let (mut cx, mut cy) = (0.0, 0.0);
                for j in 0..4 {
                    for i in 0..4 {
                        let qx = x as f64 - 0.375 + i as f64 * 0.25;
                        let qy = y as f64 - 0.375 + j as f64 * 0.25;
                        let q = self.coverage_scaled(qx, qy, 0.25);
                        c += q;
                        cx += q * qx;
                        cy += q * qy;
                    }
                }
                a += c / 16.0;
                sx += cx / 16.0;
                sy += cy / 16.0;
            }
        }
        if a > 0.0 {
            (a, sx / a, sy / a)
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    fn coverage_scaled(&self, x: f64, y: f64, size: f64) -> f64 {
        let d = self.sd((x, y));
        if d > 0.75 * size {
            return 0.0;
        }
        if d < -0.75 * size {
            return 1.0;
        }
        const N: usize = 8;
        let mut k = 0;
        for j in 0..N {
            for i in 0..N {
                let sx = x + size * (-0.5 + (i as f64 + 0.5) / N as f64);
                let sy = y + size * (-0.5 + (j as f64 + 0.5) / N as f64);
                if self.inside((sx, sy)) {
                    k += 1;
                }
            }
        }
        k as f64 / (N * N) as f64
    }
}

/// How a tip is deformed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Damage {
    None,
    /// Linear size × factor (area × factor²).
    Scaled(f64),
    /// A corner cut off: the cut removes `frac` of the tip's area (square tips).
    Chipped(f64),
    /// A disc of radius `r_frac` × pin attached at the rim.
    Burr(f64),
}

/// One grid position of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenePin {
    pub row: u32,
    pub col: u32,
    pub present: bool,
    /// Tip offset from nominal in the part frame, mm.
    pub offset_mm: (f64, f64),
    pub damage: Damage,
    /// Side view: height above the housing edge, mm.
    pub height_mm: f64,
}

/// A piece of debris (top: as bright/dark as a tip; side: semi-opaque dust).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneExtra {
    /// Part-frame centre, mm.
    pub u_mm: f64,
    pub v_mm: f64,
    /// Radius of the main disc, mm (a second, smaller disc makes it irregular).
    pub r_mm: f64,
    pub opacity: f64,
}

/// Everything needed to render one image.
#[derive(Debug, Clone)]
pub struct Scene {
    pub recipe: Recipe,
    pub width: u32,
    pub height: u32,
    pub mm_per_px: f64,
    /// Grid centre (side view: centre of the housing's top edge), px.
    pub centre_px: (f64, f64),
    pub rotation_deg: f64,
    pub blur_px: f64,
    /// Noise σ in 8-bit DN.
    pub noise_dn: f64,
    /// Scales every level's distance from mid-grey.
    pub contrast: f64,
    pub sixteen_bit: bool,
    pub seed: u64,
    pub pins: Vec<ScenePin>,
    pub extras: Vec<SceneExtra>,
}

impl Scene {
    /// A centred, upright, clean scene with every pin present and exactly
    /// nominal, sized so the housing fits with a margin.
    pub fn nominal(recipe: &Recipe, mm_per_px: f64) -> Scene {
        let (w_mm, h_mm) = housing_size(recipe);
        let (w, h) = match recipe.view {
            View::Top => (
                (w_mm / mm_per_px * 1.25 + 64.0) as u32,
                (h_mm / mm_per_px * 1.6 + 64.0) as u32,
            ),
            View::Side => {
                let hh = recipe.tolerance.height_mm.unwrap_or(3.0);
                (
                    (w_mm / mm_per_px * 1.2 + 64.0) as u32,
                    ((hh * 2.2) / mm_per_px + 80.0) as u32,
                )
            }
        };
        let centre = match recipe.view {
            View::Top => (w as f64 / 2.0, h as f64 / 2.0),
            View::Side => (w as f64 / 2.0, h as f64 * 0.62),
        };
        let pins = recipe
            .positions()
            .into_iter()
            .map(|(row, col)| ScenePin {
                row,
                col,
                present: true,
                offset_mm: (0.0, 0.0),
                damage: Damage::None,
                height_mm: recipe.tolerance.height_mm.unwrap_or(0.0),
            })
            .collect();
        Scene {
            recipe: recipe.clone(),
            width: w,
            height: h,
            mm_per_px,
            centre_px: centre,
            rotation_deg: 0.0,
            blur_px: 0.0,
            noise_dn: 0.0,
            contrast: 1.0,
            sixteen_bit: false,
            seed: 1,
            pins,
            extras: Vec::new(),
        }
    }

    /// Random pose, optics and small pin offsets (all pins `ok`): rotation
    /// within ±`max_rot_deg`, shift within ±`max_shift_px`, blur 0–`max_blur`,
    /// offsets |N(0, 0.05)| × the position tolerance.
    pub fn randomise(&mut self, rng: &mut Rng, max_rot_deg: f64, max_shift_px: f64, max_blur: f64) {
        self.rotation_deg = rng.range(-max_rot_deg, max_rot_deg);
        self.centre_px.0 += rng.range(-max_shift_px, max_shift_px);
        self.centre_px.1 += rng.range(-max_shift_px, max_shift_px) * 0.5;
        self.blur_px = rng.range(0.0, max_blur);
        let tol = self.recipe.tolerance.position_mm;
        let side = self.recipe.view == View::Side;
        let h_tol = self.recipe.tolerance.height_tol_mm.unwrap_or(0.0);
        for p in &mut self.pins {
            let a = rng.range(0.0, 2.0 * std::f64::consts::PI);
            let r = (0.05 * rng.normal()).abs() * tol;
            p.offset_mm = if side {
                (0.0, 0.0)
            } else {
                (r * a.cos(), r * a.sin())
            };
            if side {
                p.height_mm += rng.range(-0.5, 0.5) * h_tol;
            }
        }
    }

    fn sim(&self) -> super::fit::Similarity {
        super::fit::Similarity {
            s: 1.0 / self.mm_per_px,
            theta: self.rotation_deg.to_radians(),
            tx: self.centre_px.0,
            ty: self.centre_px.1,
        }
    }

    /// Polygon of a part-frame rectangle [u0, u1] × [v0, v1] in pixels.
    fn rect(&self, u0: f64, u1: f64, v0: f64, v1: f64) -> Shape {
        let s = self.sim();
        Shape::Poly(vec![
            s.apply(u0, v0),
            s.apply(u1, v0),
            s.apply(u1, v1),
            s.apply(u0, v1),
        ])
    }

    /// Tip shape of a pin at its actual position (top view).
    fn tip_shape(&self, p: &ScenePin) -> Shape {
        let (u, v) = self.recipe.nominal_uv_mm(p.row, p.col);
        let (u, v) = (u + p.offset_mm.0, v + p.offset_mm.1);
        let sim = self.sim();
        let half = self.recipe.pin_mm / 2.0;
        let scale = match p.damage {
            Damage::Scaled(f) => f,
            _ => 1.0,
        };
        let hw = half * scale;
        let base = match self.recipe.pin_shape {
            PinShape::Round => Shape::Disc {
                c: sim.apply(u, v),
                r: hw / self.mm_per_px,
            },
            PinShape::Square => {
                // Slightly chamfered corners (octagon), symmetric.
                let c = 0.12 * hw;
                let pts = [
                    (-hw + c, -hw),
                    (hw - c, -hw),
                    (hw, -hw + c),
                    (hw, hw - c),
                    (hw - c, hw),
                    (-hw + c, hw),
                    (-hw, hw - c),
                    (-hw, -hw + c),
                ];
                Shape::Poly(pts.iter().map(|(a, b)| sim.apply(u + a, v + b)).collect())
            }
        };
        match p.damage {
            Damage::Chipped(frac) => {
                // Cut the (+u, −v) corner with a 45° line removing `frac` of
                // the square's area: a right triangle of legs L with
                // L² / 2 = frac (2 hw)².
                let l = (2.0 * frac).sqrt() * 2.0 * hw;
                // The cut line runs through (hw − l, −hw) and (hw, −hw + l);
                // the triangle is extended along it by m past both ends.
                let m = hw;
                let cut = Shape::Poly(vec![
                    sim.apply(u + hw - l - m, v - hw - m),
                    sim.apply(u + hw + m, v - hw - m),
                    sim.apply(u + hw + m, v - hw + l + m),
                ]);
                Shape::Minus(Box::new(base), Box::new(cut))
            }
            Damage::Burr(r_frac) => Shape::Union(vec![
                base,
                Shape::Disc {
                    c: sim.apply(u - hw, v + 0.4 * hw),
                    r: r_frac * self.recipe.pin_mm / self.mm_per_px,
                },
            ]),
            _ => base,
        }
    }

    fn extra_shape(&self, e: &SceneExtra) -> Shape {
        let sim = self.sim();
        let r = e.r_mm / self.mm_per_px;
        let c = sim.apply(e.u_mm, e.v_mm);
        Shape::Union(vec![
            Shape::Disc { c, r },
            Shape::Disc {
                c: (c.0 + 0.6 * r, c.1 - 0.5 * r),
                r: 0.55 * r,
            },
        ])
    }

    /// Renders the image and its ground truth.
    pub fn render(&self) -> (Gray, Truth) {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut img = vec![0f64; w * h];
        let mid = 128.0;
        let lv = |v: f64| mid + (v - mid) * self.contrast;
        let paint = |img: &mut Vec<f64>, shape: &Shape, level: f64, alpha: f64| {
            let (x0, y0, x1, y1) = shape.bbox();
            let xa = (x0.floor() as i64 - 2).max(0) as usize;
            let ya = (y0.floor() as i64 - 2).max(0) as usize;
            let xb = ((x1.ceil() as i64 + 2).max(0) as usize).min(w.saturating_sub(1));
            let yb = ((y1.ceil() as i64 + 2).max(0) as usize).min(h.saturating_sub(1));
            for y in ya..=yb {
                for x in xa..=xb {
                    let c = shape.coverage(x as f64, y as f64) * alpha;
                    if c > 0.0 {
                        let i = y * w + x;
                        img[i] = img[i] * (1.0 - c) + level * c;
                    }
                }
            }
        };
        let r = &self.recipe;
        let dark = r.polarity == Polarity::Dark;
        let mut truth_pins = Vec::new();
        let mut truth_extras = Vec::new();
        let tol = &r.tolerance;
        let [ta_lo, ta_hi] = r.tip_area();
        match r.view {
            View::Top => {
                let (bg, housing, frame, hole, tip) = if dark {
                    (lv(215.0), lv(175.0), lv(90.0), lv(238.0), lv(40.0))
                } else {
                    (lv(115.0), lv(62.0), lv(30.0), lv(22.0), lv(205.0))
                };
                // Background with a gentle illumination gradient.
                for y in 0..h {
                    for x in 0..w {
                        img[y * w + x] = bg * (1.0 + 0.04 * (x as f64 / w as f64 - 0.5));
                    }
                }
                let (hw_mm, hh_mm) = housing_size(r);
                let (hu, hv) = (hw_mm / 2.0, hh_mm / 2.0);
                paint(&mut img, &self.rect(-hu, hu, -hv, hv), frame, 1.0);
                let fw = 0.22;
                paint(
                    &mut img,
                    &self.rect(-hu + fw, hu - fw, -hv + fw, hv - fw),
                    housing,
                    1.0,
                );
                let sim = self.sim();
                for p in &self.pins {
                    let (u, v) = r.nominal_uv_mm(p.row, p.col);
                    let hole_half = r.pin_mm * 0.62;
                    let hole_shape = match r.pin_shape {
                        PinShape::Round => Shape::Disc {
                            c: sim.apply(u, v),
                            r: hole_half / self.mm_per_px,
                        },
                        PinShape::Square => {
                            self.rect(u - hole_half, u + hole_half, v - hole_half, v + hole_half)
                        }
                    };
                    paint(&mut img, &hole_shape, hole, 1.0);
                }
                let tip_area_px = r.tip_area_mm2() / (self.mm_per_px * self.mm_per_px);
                for p in &self.pins {
                    if !p.present {
                        truth_pins.push(TruthPin::missing(p.row, p.col));
                        continue;
                    }
                    let shape = self.tip_shape(p);
                    // A mild symmetric dome: paint the rim level, then a
                    // brighter concentric core (symmetric, so the geometric
                    // centre is unchanged).
                    paint(&mut img, &shape, tip, 1.0);
                    let (area, cx, cy) = match p.damage {
                        // Intact (or uniformly scaled) tips are symmetric:
                        // centre and area in closed form.
                        Damage::None | Damage::Scaled(_) => {
                            let f = match p.damage {
                                Damage::Scaled(f) => f,
                                _ => 1.0,
                            };
                            let (u, v) = r.nominal_uv_mm(p.row, p.col);
                            let c = self.sim().apply(u + p.offset_mm.0, v + p.offset_mm.1);
                            let hw = r.pin_mm / 2.0 * f;
                            let a_mm = match r.pin_shape {
                                PinShape::Round => std::f64::consts::PI * hw * hw,
                                // Octagon: square minus four corner triangles of legs 0.12 hw.
                                PinShape::Square => 4.0 * hw * hw - 2.0 * (0.12 * hw) * (0.12 * hw),
                            };
                            (a_mm / (self.mm_per_px * self.mm_per_px), c.0, c.1)
                        }
                        _ => shape.area_centroid(),
                    };
                    let core = Shape::Disc {
                        c: (cx, cy),
                        r: 0.3 * r.pin_mm / self.mm_per_px,
                    };
                    if p.damage == Damage::None {
                        let bump = if dark { -12.0 } else { 14.0 } * self.contrast;
                        paint(&mut img, &core, tip + bump, 0.6);
                    }
                    let ar = area / tip_area_px;
                    let off = p.offset_mm.0.hypot(p.offset_mm.1);
                    let limits = ([ta_lo, ta_hi], tol.position_mm);
                    let pos = (p.row, p.col);
                    truth_pins.push(TruthPin::top(pos, (cx, cy), ar, off, limits.0, limits.1));
                }
                for e in &self.extras {
                    let s = self.extra_shape(e);
                    paint(&mut img, &s, tip, e.opacity);
                    let (_, cx, cy) = s.area_centroid();
                    truth_extras.push(TruthExtra {
                        x_px: cx,
                        y_px: cy,
                        kind: Some("debris".into()),
                    });
                }
            }
            View::Side => {
                let (bg, solid) = (lv(200.0), lv(18.0));
                for y in 0..h {
                    for x in 0..w {
                        let dx = (x as f64 - w as f64 / 2.0) / w as f64;
                        let dy = (y as f64 - h as f64 / 2.0) / h as f64;
                        img[y * w + x] = bg * (1.0 - 0.08 * (dx * dx + dy * dy));
                    }
                }
                let (hw_mm, _) = housing_size(r);
                let depth = (self.height as f64) * self.mm_per_px * 2.0;
                paint(
                    &mut img,
                    &self.rect(-hw_mm / 2.0, hw_mm / 2.0, 0.0, depth),
                    solid,
                    1.0,
                );
                let sim = self.sim();
                for p in &self.pins {
                    let (u, _) = r.nominal_uv_mm(p.row, p.col);
                    let u = u + p.offset_mm.0;
                    if !p.present {
                        truth_pins.push(TruthPin::missing(p.row, p.col));
                        continue;
                    }
                    let hw = r.pin_mm / 2.0;
                    let c = 0.08f64.min(0.3 * hw);
                    let top = -p.height_mm;
                    let pts = [
                        (u - hw, 0.1),
                        (u - hw, top + c),
                        (u - hw + c, top),
                        (u + hw - c, top),
                        (u + hw, top + c),
                        (u + hw, 0.1),
                    ];
                    let bar = Shape::Poly(pts.iter().map(|(a, b)| sim.apply(*a, *b)).collect());
                    paint(&mut img, &bar, solid, 1.0);
                    let (tx, ty) = sim.apply(u, top);
                    let (pos, tip) = ((p.row, p.col), (tx, ty));
                    truth_pins.push(TruthPin::side(pos, tip, p.height_mm, p.offset_mm.0, tol));
                }
                for e in &self.extras {
                    let s = self.extra_shape(e);
                    paint(&mut img, &s, solid, e.opacity);
                    let (_, cx, cy) = s.area_centroid();
                    truth_extras.push(TruthExtra {
                        x_px: cx,
                        y_px: cy,
                        kind: Some("debris".into()),
                    });
                }
            }
        }
        if self.blur_px > 0.05 {
            gaussian_blur(&mut img, w, h, self.blur_px);
        }
        let mut rng = Rng::new(self.seed);
        let (scale, max) = if self.sixteen_bit {
            (257.0, 65535.0)
        } else {
            (1.0, 255.0)
        };
        let vals: Vec<f64> = img
            .iter()
            .map(|&v| {
                ((v + self.noise_dn * rng.normal()) * scale)
                    .round()
                    .clamp(0.0, max)
            })
            .collect();
        let data = if self.sixteen_bit {
            GrayData::U16(vals.iter().map(|&v| v as u16).collect())
        } else {
            GrayData::U8(vals.iter().map(|&v| v as u8).collect())
        };
        let gray = Gray {
            width: self.width,
            height: self.height,
            data,
        };
        let verdict = Truth::verdict_of(&truth_pins, &truth_extras);
        let truth = Truth {
            recipe: String::new(),
            mm_per_px: Some(self.mm_per_px),
            verdict,
            pins: truth_pins,
            extras: truth_extras,
            render: Some(serde_json::json!({
                "generator": "pinsight::vision::synth",
                "seed": self.seed,
                "pose": {"centre_px": [self.centre_px.0, self.centre_px.1], "rotation_deg": self.rotation_deg},
                "blur_sigma_px": self.blur_px,
                "noise_sigma_dn": self.noise_dn,
                "contrast": self.contrast,
                "bit_depth": if self.sixteen_bit { 16 } else { 8 },
                "supersampling": 8,
            })),
        };
        (gray, truth)
    }
}

/// Housing outline size (mm): the grid plus 0.55 pitch on each side (top);
/// side view: the row plus 0.55 pitch at each end.
pub fn housing_size(r: &Recipe) -> (f64, f64) {
    let w = (r.cols as f64 - 1.0) * r.pitch_mm[0] + 1.1 * r.pitch_mm[0];
    let h = (r.rows as f64 - 1.0) * r.pitch_mm[1] + 1.1 * r.pitch_mm[1];
    (w, h)
}

fn gaussian_blur(img: &mut [f64], w: usize, h: usize, sigma: f64) {
    let rad = (3.0 * sigma).ceil() as i64;
    let k: Vec<f64> = (-rad..=rad)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = k.iter().sum();
    let k: Vec<f64> = k.iter().map(|v| v / sum).collect();
    let mut tmp = vec![0f64; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (j, kv) in k.iter().enumerate() {
                let xx = (x as i64 + j as i64 - rad).clamp(0, w as i64 - 1) as usize;
                s += kv * img[y * w + xx];
            }
            tmp[y * w + x] = s;
        }
    }
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (j, kv) in k.iter().enumerate() {
                let yy = (y as i64 + j as i64 - rad).clamp(0, h as i64 - 1) as usize;
                s += kv * tmp[yy * w + x];
            }
            img[y * w + x] = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_integrates_area_and_centroid() {
        let d = Shape::Disc {
            c: (10.3, 7.6),
            r: 4.0,
        };
        let (a, cx, cy) = d.area_centroid();
        assert!((a - std::f64::consts::PI * 16.0).abs() < 0.05, "{a}");
        assert!((cx - 10.3).abs() < 1e-3 && (cy - 7.6).abs() < 1e-3);
        let sq = Shape::Poly(vec![(2.0, 2.0), (8.0, 2.0), (8.0, 5.0), (2.0, 5.0)]);
        let (a, cx, cy) = sq.area_centroid();
        assert!((a - 18.0).abs() < 1e-6 && (cx - 5.0).abs() < 1e-9 && (cy - 3.5).abs() < 1e-9);
        // Pixel coverage sums to the area.
        let total: f64 = (0..12)
            .flat_map(|y| (0..12).map(move |x| (x, y)))
            .map(|(x, y)| sq.coverage(x as f64, y as f64))
            .sum();
        assert!((total - 18.0).abs() < 1e-9);
        let cut = Shape::Minus(
            Box::new(sq.clone()),
            Box::new(Shape::Poly(vec![
                (5.0, 0.0),
                (9.0, 0.0),
                (9.0, 6.0),
                (5.0, 6.0),
            ])),
        );
        let (a, cx, _) = cut.area_centroid();
        assert!((a - 9.0).abs() < 1e-6 && (cx - 3.5).abs() < 1e-6);
    }

    #[test]
    fn closed_form_tip_truth_matches_integration() {
        let r = Recipe::from_toml_str(
            "part_number = \"T\"\nview = \"top\"\nrows = 1\ncols = 2\npitch_mm = [2.0, 2.0]\npin_mm = 0.6\npin_shape = \"square\"\npolarity = \"bright\"\nmm_per_px = 0.03\n[tolerance]\nposition_mm = 0.1\n",
            "t",
        )
        .unwrap();
        let mut sc = Scene::nominal(&r, 0.03);
        sc.rotation_deg = 3.3;
        sc.pins[1].offset_mm = (0.031, -0.017);
        sc.pins[1].damage = Damage::Scaled(1.2);
        let (_, t) = sc.render();
        for (p, tp) in sc.pins.iter().zip(&t.pins) {
            let (a, cx, cy) = sc.tip_shape(p).area_centroid();
            let tip_px = 0.36 / (0.03 * 0.03);
            assert!((tp.x_px.unwrap() - cx).abs() < 2e-3 && (tp.y_px.unwrap() - cy).abs() < 2e-3);
            assert!((tp.area_ratio.unwrap() - a / tip_px).abs() < 1e-3);
        }
    }

    #[test]
    fn rng_is_deterministic_and_normal() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        assert_eq!(a.next_u64(), b.next_u64());
        let v: Vec<f64> = (0..20000).map(|_| a.normal()).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let s = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt();
        assert!(m.abs() < 0.03 && (s - 1.0).abs() < 0.03, "{m} {s}");
    }
}
