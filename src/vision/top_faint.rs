//! Top view: debris fainter than the coarse threshold, looked for once the
//! pins are placed, as candidates for the extras only. A flat particle at a
//! tip's rim level, smaller than a tip, peaks on the coarse top-hat at
//! 0.2–0.35 of the tips' (domed) contrast, under the coarse threshold
//! (0.35 of it). Fixture texture peaks as high, so a faint blob is kept
//! only where it stands clear of its own neighbourhood: its peak at least
//! [`FAINT_ISOLATION`] × the 95th percentile of the top-hat in an annulus
//! around it (texture fills that annulus with bumps as high as itself; a
//! particle on a plain housing or fixture has only noise there).

use super::detect::{self, CoarseBlob, CoarseSearch, Smoothing};
use super::label;

/// The faint pass's level, as a fraction of the typical tip contrast.
const FAINT_LEVEL: f32 = 0.2;
/// How far a faint blob's peak must stand above its neighbourhood's 95th
/// percentile of the top-hat.
const FAINT_ISOLATION: f32 = 4.0;

/// Coarse blobs between `FAINT_LEVEL` of the tip contrast (and the noise
/// floor) and the coarse threshold, tip-sized or smaller, standing
/// `FAINT_ISOLATION` above their neighbourhood.
pub(super) fn faint_blobs(cs: &CoarseSearch, pin_px: f64) -> Vec<CoarseBlob> {
    let (w, h) = (cs.coarse.w, cs.coarse.h);
    let th = &cs.tophat;
    if th.len() != w * h || w < 3 || h < 3 {
        return Vec::new();
    }
    let pin_c = pin_px / cs.coarse.k as f64;
    let tip_area_c = pin_c * pin_c;
    let level = (FAINT_LEVEL * cs.tip_contrast).max(cs.noise_floor);
    if level >= cs.threshold {
        return Vec::new();
    }
    let lab = label::label(w, h, |x, y| th[y * w + x] > level);
    let r_out = (2.5 * pin_c).ceil() as i64 + 1;
    let mut out = Vec::new();
    for b in &lab.blobs {
        let a = b.area as f64 / tip_area_c;
        if !(0.08..=3.0).contains(&a) {
            continue;
        }
        let peak = detect::blob_peak(&lab, b, th, w);
        // Above the threshold the coarse search has it already, unless
        // too little of it stood above that threshold to count there
        // (under 0.08 tips: Rust 980 637, debris at the tips' rim level
        // on a brighter fixture peaks at 0.38 of the domed tips' contrast,
        // one coarse pixel over the threshold of 0.35).
        if peak >= cs.threshold && holds_a_coarse_blob(cs, b) {
            continue;
        }
        let half_diag = 0.5 * (b.width() as f64).hypot(b.height() as f64);
        let r_in = (1.2 * pin_c).max(half_diag + 0.5 * pin_c);
        let r_out = (r_out as f64).max(r_in + 1.5 * pin_c);
        let (cx, cy) = (b.cx, b.cy);
        let mut ring = Vec::new();
        let (x0, x1) = (
            (cx - r_out).floor().max(0.0) as usize,
            ((cx + r_out).ceil() as usize).min(w - 1),
        );
        let (y0, y1) = (
            (cy - r_out).floor().max(0.0) as usize,
            ((cy + r_out).ceil() as usize).min(h - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = (x as f64 - cx).hypot(y as f64 - cy);
                let v = th[y * w + x];
                if d > r_in && d <= r_out && v < cs.threshold {
                    ring.push(v);
                }
            }
        }
        if ring.len() < 8 {
            continue;
        }
        let q = ((ring.len() - 1) as f64 * 0.95).round() as usize;
        let p95 = *ring.select_nth_unstable_by(q, |a, b| a.total_cmp(b)).1;
        if peak < FAINT_ISOLATION * p95.max(0.0) {
            continue;
        }
        let mut blob = b.clone();
        blob.runs = Vec::new();
        out.push(CoarseBlob { blob, peak });
    }
    out
}

/// Whether blob `b`'s bounding box (grown by half a coarse pixel) holds the
/// centre of a blob the coarse search kept: the same structure, found.
fn holds_a_coarse_blob(cs: &CoarseSearch, b: &label::Blob) -> bool {
    cs.blobs.iter().any(|c| {
        let (x, y) = (c.blob.cx, c.blob.cy);
        x >= b.x_min as f64 - 0.5
            && x <= b.x_max as f64 + 0.5
            && y >= b.y_min as f64 - 0.5
            && y <= b.y_max as f64 + 0.5
    })
}

/// Coarse blobs of the wider smoothing box's top-hat ([`Smoothing::Faint`],
/// about four fifths of a tip) above its own noise floor
/// ([`detect::NOISE_FLOOR_SIGMAS`] σ), tip-sized or smaller, that the
/// coarse search did not find: debris under heavy noise. Only where the
/// noise floor, not a fraction of the tip contrast, set the coarse
/// threshold; there [`faint_blobs`] has no level between the two to search.
/// A particle at a tip's rim level, half a tip to a tip in area, peaks at
/// 0.44–0.55 of the tip contrast on the coarse top-hat of a small-tip image
/// under σ 10–14 DN, while the noise floor stands at 0.48–0.74 of it (Rust
/// 920 475, 931 319): the box of half a tip (none at all for tips under
/// 8 coarse px) leaves the pixel noise almost whole. Over four fifths of a
/// tip the noise falls by the box's width again and the particle keeps
/// most of its peak. What a blob found here is, the extras' own tests
/// decide (its level against the tips', its contrast summed over its
/// pixels, its core against its own noise).
pub(super) fn noisy_debris_blobs(cs: &CoarseSearch, pin_px: f64) -> Vec<CoarseBlob> {
    let (w, h) = (cs.coarse.w, cs.coarse.h);
    if cs.noise_floor < cs.threshold || cs.coarse.data.len() != w * h || w < 3 || h < 3 {
        return Vec::new();
    }
    let (th, _) = detect::tophat(&cs.coarse, pin_px, Smoothing::Faint);
    let floor = detect::tophat_noise_floor(&cs.coarse, &th, detect::NOISE_FLOOR_SIGMAS);
    let pin_c = pin_px / cs.coarse.k as f64;
    let tip_area_c = pin_c * pin_c;
    let lab = label::label(w, h, |x, y| th[y * w + x] > floor);
    let mut out = Vec::new();
    for b in &lab.blobs {
        let a = b.area as f64 / tip_area_c;
        if !(0.08..=3.0).contains(&a) {
            continue;
        }
        if holds_a_coarse_blob(cs, b) {
            continue;
        }
        let peak = detect::blob_peak(&lab, b, &th, w);
        let mut blob = b.clone();
        blob.runs = Vec::new();
        out.push(CoarseBlob { blob, peak });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::detect;
    use super::super::gray::Plane;
    use super::*;

    /// A 10 px domed tip (height 1000 over the housing at 1000).
    fn tip(img: &mut [u16], w: usize, cx: f64, cy: f64) {
        for y in 0..img.len() / w {
            for x in 0..w {
                let r = (x as f64 - cx).hypot(y as f64 - cy) / 5.0;
                if r < 1.0 {
                    img[y * w + x] += (1000.0 * (1.0 - 0.5 * r * r)) as u16;
                }
            }
        }
    }

    /// A flat disc of radius `r` and height `v`.
    fn disc(img: &mut [u16], w: usize, cx: f64, cy: f64, r: f64, v: u16) {
        for y in 0..img.len() / w {
            for x in 0..w {
                if (x as f64 - cx).hypot(y as f64 - cy) < r {
                    img[y * w + x] += v;
                }
            }
        }
    }

    /// Four tips in a row, a small flat particle (radius 3.5 px, half
    /// a tip's area) at 0.28 of the tips' peak between the row and the
    /// frame's edge: under the coarse threshold, the faint pass finds it
    /// where it lies, within half a pixel. The same particle among a field
    /// of bumps as high as itself (a textured fixture) is not taken.
    #[test]
    fn a_faint_particle_on_a_plain_housing_is_found_but_not_among_texture() {
        let (w, h) = (160usize, 120usize);
        let plain = |texture: bool| {
            let mut img = vec![1000u16; w * h];
            for i in 0..4 {
                tip(&mut img, w, 35.0 + 30.0 * i as f64, 40.0);
            }
            disc(&mut img, w, 80.0, 85.0, 3.5, 280);
            if texture {
                for j in 0..4 {
                    for i in 0..9 {
                        let (x, y) = (12.0 + 17.0 * i as f64, 65.0 + 14.0 * j as f64);
                        if (x - 80.0).hypot(y - 85.0) > 8.0 {
                            disc(&mut img, w, x, y, 3.5, 280);
                        }
                    }
                }
            }
            img
        };
        for texture in [false, true] {
            let img = plain(texture);
            let plane = Plane {
                w,
                h,
                data: &img[..],
            };
            let cs = detect::coarse_search(&plane, 1.0, 10.0, None, Some(4));
            assert_eq!(cs.blobs.len(), 4, "texture {texture}: the tips only");
            let faint = faint_blobs(&cs, 10.0);
            let near: Vec<_> = faint
                .iter()
                .filter(|b| {
                    let (x, y) = cs.coarse.to_full(b.blob.cx, b.blob.cy);
                    (x - 80.0).hypot(y - 85.0) < 0.5
                })
                .collect();
            if texture {
                assert!(faint.is_empty(), "{faint:?}");
            } else {
                assert_eq!((faint.len(), near.len()), (1, 1), "{faint:?}");
            }
        }
    }

    /// A particle whose smoothed peak just passes the coarse threshold but
    /// over too few pixels for the coarse search to keep it (under 0.08
    /// tips): the faint pass, which used to leave every blob peaking over
    /// that threshold to the coarse search, finds it.
    #[test]
    fn a_particle_peaking_just_over_the_coarse_threshold_is_not_lost_between_passes() {
        let (w, h) = (160usize, 120usize);
        let mut img = vec![1000u16; w * h];
        for i in 0..4 {
            tip(&mut img, w, 35.0 + 30.0 * i as f64, 40.0);
        }
        disc(&mut img, w, 80.0, 85.0, 2.2, PARTICLE);
        let plane = Plane {
            w,
            h,
            data: &img[..],
        };
        let cs = detect::coarse_search(&plane, 1.0, 10.0, None, Some(4));
        assert_eq!(cs.blobs.len(), 4, "the coarse search keeps the tips only");
        let (cx, cy) = cs.coarse.from_full(80.0, 85.0);
        let at = |x: f64, y: f64| cs.tophat[y.round() as usize * cs.coarse.w + x.round() as usize];
        let peak = (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (dx as f64, dy as f64)))
            .map(|(dx, dy)| at(cx + dx, cy + dy))
            .fold(0f32, f32::max);
        assert!(
            peak > cs.threshold,
            "peak {peak} threshold {}",
            cs.threshold
        );
        let faint = faint_blobs(&cs, 10.0);
        let near = faint.iter().filter(|b| {
            let (x, y) = cs.coarse.to_full(b.blob.cx, b.blob.cy);
            (x - 80.0).hypot(y - 85.0) < 1.0
        });
        assert_eq!((faint.len(), near.count()), (1, 1), "{faint:?}");
    }

    /// Under heavy pixel noise the coarse threshold is the noise floor, and
    /// a tip-sized particle at 0.4 of the tips' peak stays under it (and
    /// the faint pass, whose level would lie above that threshold, has
    /// nothing to search); over the wider box the noise falls and the
    /// particle stands clear: found there, where it lies, and nothing
    /// else in the frame is.
    #[test]
    fn a_particle_under_heavy_noise_is_found_over_the_wider_box() {
        let (w, h) = (200usize, 160usize);
        let mut img = vec![0u16; w * h];
        let mut noisy = vec![0f64; w * h];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for v in noisy.iter_mut() {
            // Box–Muller, σ = NOISE.
            let (u1, u2) = (uniform().max(1e-12), uniform());
            *v = 4000.0 + NOISE * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        }
        for (o, v) in img.iter_mut().zip(&noisy) {
            *o = v.round().clamp(0.0, 65535.0) as u16;
        }
        for i in 0..4 {
            tip(&mut img, w, 45.0 + 35.0 * i as f64, 50.0);
        }
        disc(&mut img, w, 100.0, 110.0, 5.5, 400);
        let plane = Plane {
            w,
            h,
            data: &img[..],
        };
        let cs = detect::coarse_search(&plane, 1.0, 10.0, None, Some(4));
        let found = noisy_debris_blobs(&cs, 10.0);
        assert_eq!(cs.threshold, cs.noise_floor, "the noise sets the threshold");
        assert_eq!(cs.blobs.len(), 4, "the coarse search keeps the tips only");
        assert!(faint_blobs(&cs, 10.0).is_empty());
        let near = found.iter().filter(|b| {
            let (x, y) = cs.coarse.to_full(b.blob.cx, b.blob.cy);
            (x - 100.0).hypot(y - 110.0) < 2.0
        });
        assert_eq!((found.len(), near.count()), (1, 1), "{found:?}");
    }

    /// Pixel noise σ of [`a_particle_under_heavy_noise_is_found_over_the_wider_box`].
    const NOISE: f64 = 450.0;

    /// The particle's height over the housing (the tips' peak is 1000).
    const PARTICLE: u16 = 900;
}
