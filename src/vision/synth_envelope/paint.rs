//! Painting a drawn case: the part, the scene around it, the light and the
//! camera (exposure, noise, bit depth, JPEG).

use super::raster::*;
use super::*;

impl EnvelopeCase {
    pub(super) fn sim(&self) -> Similarity {
        Similarity {
            s: 1.0 / self.factors.mm_per_px,
            theta: self.factors.rotation_deg.to_radians(),
            tx: self.factors.centre_px.0,
            ty: self.factors.centre_px.1,
        }
    }

    pub(super) fn pin_uv(&self, p: &CasePin) -> (f64, f64) {
        let (u, v) = self.recipe.nominal_uv_mm(p.row, p.col);
        (u + p.offset_mm.0, v + p.offset_mm.1)
    }

    /// A piece of debris (top) or dust (side), clear of every tip and of
    /// every grid node by more than the assignment radius.
    pub(super) fn draw_extra(
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

    pub(super) fn mark_uv(&self) -> (f64, f64) {
        let r = &self.recipe;
        let (u0, v0) = r.nominal_uv_mm(0, 0);
        let (mu, mv) = (self.look.margin_mm.0, self.look.margin_mm.1);
        (u0 - 0.55 * mu, v0 - 0.55 * mv)
    }

    /// Tip shape (top view) in pixels.
    pub(super) fn tip_shape(&self, p: &CasePin) -> Shape {
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

    pub(super) fn extra_shape(&self, e: &CaseExtra) -> Shape {
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
        let (img, truth_pins, truth_extras) = self.scene();
        let (gray, info) = self.expose(&img)?;
        let verdict = Truth::verdict_of(&truth_pins, &truth_extras);
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

    /// The light reaching the sensor before the camera (8-bit units, before
    /// gain): the part painted, illuminated and blurred, with its truth.
    pub(super) fn scene(&self) -> (Vec<f32>, Vec<TruthPin>, Vec<TruthExtra>) {
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
        (img, truth_pins, truth_extras)
    }

    /// Noise variance (8-bit units²) of a pixel whose exposed value is `v`
    /// (after gain): read noise plus shot noise as `expose` draws them,
    /// plus the quantisation of the stored bit depth.
    pub(super) fn noise_variance(&self, v: f32) -> f32 {
        let f = &self.factors;
        let rf = self.look.read_fraction as f32;
        let step = match f.bits {
            8 => 1.0,
            12 => 255.0 / 4095.0,
            _ => 255.0 / 65535.0,
        };
        let sigma = f.noise_dn as f32;
        sigma * sigma * (rf + (1.0 - rf) * (v.max(0.0) / 128.0)) + step * step / 12.0
    }

    pub(super) fn contrast_level(&self, v: f64) -> f32 {
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
                truth_pins.push(TruthPin::missing(p.row, p.col));
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
            let limits = ([ta_lo, ta_hi], tol);
            let pos = (p.row, p.col);
            truth_pins.push(TruthPin::top(pos, (cx, cy), ar, off, limits.0, limits.1));
        }
        let truth_extras = self.paint_extras(img, rim, "debris");
        (truth_pins, truth_extras)
    }

    /// Paints every extra (debris on a top view, dust in a side view's
    /// backlight) at `level`, and returns their truth (area centroids).
    fn paint_extras(&self, img: &mut [f32], level: f32, kind: &str) -> Vec<TruthExtra> {
        let f = &self.factors;
        let (w, h) = (f.width as usize, f.height as usize);
        self.extras
            .iter()
            .map(|e| {
                let s = self.extra_shape(e);
                paint_shape(
                    img,
                    w,
                    h,
                    &s,
                    f.edge_ramp_px,
                    4,
                    e.opacity as f32,
                    |_, _| level,
                );
                let (_, cx, cy) = s.area_centroid();
                TruthExtra {
                    x_px: cx,
                    y_px: cy,
                    kind: Some(kind.into()),
                }
            })
            .collect()
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
        let mut truth_pins = Vec::new();
        for p in &self.pins {
            let (u, _) = r.nominal_uv_mm(p.row, p.col);
            let u = u + p.offset_mm.0;
            if !p.present {
                truth_pins.push(TruthPin::missing(p.row, p.col));
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
            let (pos, tip) = ((p.row, p.col), (tx, ty));
            truth_pins.push(TruthPin::side(pos, tip, p.height_mm, p.offset_mm.0, tol));
        }
        let truth_extras = self.paint_extras(img, solid, "dust");
        (truth_pins, truth_extras)
    }

    /// Vignetting (off-centre, `1 / (1 + k r²)²`, `k` set by the fall-off
    /// at the farthest corner) times a linear gradient across the part.
    /// The gradient is drawn across the part's span; beyond the part it
    /// levels off one span from the centre (the light stays
    /// within 1 ± the drawn gradient over the frame). Extended linearly over
    /// a frame many times the part's size, a 20 % gradient reached 0.05 on
    /// one side and over 2 on the other: the back-lit housing clipped to the
    /// backlight's level (invisible) and the frame went black, far outside
    /// the envelope's "gradient up to 20 % across the part" (seeds 200 078,
    /// 300 062, 300 453: side views without a visible housing).
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
                let d = ((x as f64 - cx) * gc + (y as f64 - cy) * gs).clamp(-span_px, span_px);
                let grad = 1.0 + g * d;
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
            return Ok((
                crate::vision::image_io::to_gray(dynimg),
                info(channels, bd, "png"),
            ));
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
