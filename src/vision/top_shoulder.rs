//! Top view: debris lying across the housing's edge, measured as what it
//! adds to the outline of the brighter structure beside it.
//!
//! Both renderers (and a real camera) put debris on the housing's edge at
//! about the tips' level, and the fixture beside a bright part is often
//! nearly as bright (Rust 840 297: the fixture at 0.77 of the tip level,
//! the debris at 0.82; Python 620 290, a dark part on a dark fixture). The
//! debris is then no peak but a shoulder of the fixture: its half-level
//! mask runs into the fixture, and cut at the saddle it stands 0.05 of the
//! tip contrast or less above it, so it was set aside as "a ripple of that
//! structure" or "part of a larger structure". What it does have is a
//! protrusion into the housing that no straight edge, rounded corner or
//! chamfer band makes: a grey opening with a square larger than any debris
//! follows the fixture's outline (a half-plane, or the outside of a convex
//! housing, is unchanged by an opening) and leaves the protrusion in the
//! residual. A band along the edge leaves a ridge that runs out of the
//! window, and is not taken.

use super::gray::{Plane, Px};
use super::measure;
use super::morph;

/// What the residual of a local grey opening shows at a candidate.
#[derive(Debug, Clone)]
pub(super) struct Shoulder {
    /// Coverage-weighted centre, full-resolution pixels.
    pub x: f64,
    pub y: f64,
    /// Area, pixels², counted in tip-bright units above the opening's level.
    pub area_px: f64,
    /// Mean rise of the residual over the half-level mask (sign space).
    pub rise: f32,
    /// The level the blob rises from (the opening's, sign space).
    pub base: f32,
    /// Mean rise over a disc of `core_px` at the centre.
    pub core: f32,
    /// Pixel noise σ of the window (neighbour differences, robust).
    pub noise: f32,
    pub mask_px: usize,
    /// The mask reaches the window's border: a ridge along the edge (a
    /// chamfer band) or a structure the window does not hold.
    pub touches_border: bool,
}

impl Shoulder {
    /// The mask's mean rise summed over its pixels against the noise.
    pub fn snr(&self) -> f64 {
        if self.noise > 0.0 {
            self.rise as f64 * (self.mask_px as f64).sqrt() / self.noise as f64
        } else {
            f64::INFINITY
        }
    }
}

/// The residual of a grey opening (square of ≈ 2.6 tip widths, larger than
/// the largest debris either renderer draws, 2.5 tip areas) around `at`,
/// on a 3 × 3 mean: the component at half the residual's peak near `at`,
/// its area in tip-bright units (`tip_level`, sign space, is what a tip
/// there would reach), its centre, rise and core (mean over `core_px`).
pub(super) fn measure_shoulder<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    at: (f64, f64),
    pin_px: f64,
    tip_level: f32,
    core_px: f64,
) -> Option<Shoulder> {
    let r_se = (1.3 * pin_px).ceil().max(3.0) as usize;
    let half = 2 * r_se + pin_px.ceil() as usize;
    let (cx, cy) = (at.0.round() as i64, at.1.round() as i64);
    let x0 = (cx - half as i64).max(0) as usize;
    let y0 = (cy - half as i64).max(0) as usize;
    let x1 = ((cx + half as i64 + 1).max(0) as usize).min(plane.w);
    let y1 = ((cy + half as i64 + 1).max(0) as usize).min(plane.h);
    if x1 <= x0 + 8 || y1 <= y0 + 8 {
        return None;
    }
    let (w, h) = (x1 - x0, y1 - y0);
    let mut v = vec![0f32; w * h];
    for y in 0..h {
        let row = &plane.data[(y0 + y) * plane.w + x0..(y0 + y) * plane.w + x1];
        for (o, s) in v[y * w..(y + 1) * w].iter_mut().zip(row) {
            *o = sign * s.f();
        }
    }
    // Pixel noise from neighbour differences (smooth texture cancels).
    let mut d: Vec<f32> = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 1..w {
            d.push((v[y * w + x] - v[y * w + x - 1]).abs());
        }
    }
    let noise = measure::percentile(&mut d, 0.5) * 1.4826 / std::f32::consts::SQRT_2;
    let vs = morph::box_mean(&v, w, h, 1);
    let open = morph::open_square(&vs, w, h, r_se);
    let r: Vec<f32> = vs.iter().zip(&open).map(|(a, b)| a - b).collect();
    // The residual's peak within 0.6 tip widths of `at`.
    let rad = (0.6 * pin_px).max(2.0);
    let (ax, ay) = (at.0 - x0 as f64, at.1 - y0 as f64);
    let mut best: Option<(usize, f32)> = None;
    for y in 0..h {
        for x in 0..w {
            if (x as f64 - ax).hypot(y as f64 - ay) <= rad {
                let i = y * w + x;
                if best.is_none_or(|b| r[i] > b.1) {
                    best = Some((i, r[i]));
                }
            }
        }
    }
    let (pi, peak) = best?;
    if peak <= 0.0 {
        return None;
    }
    // The component at half the peak (8-connected).
    let cut = 0.5 * peak;
    let mut mask = vec![0u8; w * h];
    let mut stack = vec![pi];
    mask[pi] = 1;
    let mut touches = false;
    while let Some(i) = stack.pop() {
        let (x, y) = (i % w, i / w);
        if x == 0 || y == 0 || x == w - 1 || y == h - 1 {
            touches = true;
            continue;
        }
        for (dx, dy) in [
            (-1i64, -1i64),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let j = ((y as i64 + dy) as usize) * w + (x as i64 + dx) as usize;
            if mask[j] == 0 && r[j] >= cut {
                mask[j] = 1;
                stack.push(j);
            }
        }
    }
    // The residual's own floor (the opening sits under a noisy surface):
    // its median beyond the mask grown by the blur's reach.
    let grow = ((0.12 * pin_px).round() as usize).max(2);
    let grown = morph::dilate_square(
        &mask.iter().map(|&m| m as f32).collect::<Vec<_>>(),
        w,
        h,
        grow,
    );
    let mut rest: Vec<f32> = (0..w * h)
        .filter(|&i| grown[i] == 0.0)
        .map(|i| r[i])
        .collect();
    if rest.len() < 16 {
        return None;
    }
    let r0 = measure::percentile(&mut rest, 0.5);
    let mut n = 0usize;
    let mut sum = 0f64;
    for i in 0..w * h {
        if mask[i] != 0 {
            n += 1;
            sum += (r[i] - r0) as f64;
        }
    }
    let rise = (sum / n.max(1) as f64) as f32;
    let base = open[pi] + r0;
    let unit = (tip_level - base).max(peak - r0).max(1e-6);
    let (mut a, mut sx, mut sy) = (0f64, 0f64, 0f64);
    for i in 0..w * h {
        if grown[i] != 0.0 {
            let c = ((r[i] - r0) / unit).clamp(0.0, 1.0) as f64;
            a += c;
            sx += c * (i % w) as f64;
            sy += c * (i / w) as f64;
        }
    }
    if a <= 0.0 {
        return None;
    }
    let (mx, my) = (sx / a, sy / a);
    let rc = (core_px.max(1.0) / std::f64::consts::PI).sqrt();
    let (mut cs, mut cn) = (0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            if (x as f64 - mx).hypot(y as f64 - my) <= rc {
                cs += (r[y * w + x] - r0) as f64;
                cn += 1;
            }
        }
    }
    Some(Shoulder {
        x: mx + x0 as f64,
        y: my + y0 as f64,
        area_px: a,
        rise,
        base,
        core: (cs / cn.max(1) as f64) as f32,
        noise,
        mask_px: n,
        touches_border: touches,
    })
}
