//! Top view: debris fainter than the coarse threshold, looked for once the
//! pins are placed, as candidates for the extras only. A flat particle at a
//! tip's rim level, smaller than a tip, peaks on the coarse top-hat at
//! 0.2–0.35 of the tips' (domed) contrast, under the coarse threshold
//! (0.35 of it). Fixture texture peaks as high, so a faint blob is kept
//! only where it stands clear of its own neighbourhood: its peak at least
//! [`FAINT_ISOLATION`] × the 95th percentile of the top-hat in an annulus
//! around it (texture fills that annulus with bumps as high as itself; a
//! particle on a plain housing or fixture has only noise there).

use super::detect::{CoarseBlob, CoarseSearch};
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
        let mut peak = f32::NEG_INFINITY;
        for &ri in &b.runs {
            let r = &lab.runs[ri as usize];
            for x in r.x0..r.x1 {
                peak = peak.max(th[r.y as usize * w + x as usize]);
            }
        }
        // Above the threshold the coarse search has it already, unless
        // too little of it stood above that threshold to count there
        // (under 0.08 tips: Rust 980 637, debris at the tips' rim level
        // on a brighter fixture peaks at 0.38 of the domed tips' contrast,
        // one coarse pixel over the threshold of 0.35).
        let kept = |c: &CoarseBlob| {
            let (x, y) = (c.blob.cx, c.blob.cy);
            x >= b.x_min as f64 - 0.5
                && x <= b.x_max as f64 + 0.5
                && y >= b.y_min as f64 - 0.5
                && y <= b.y_max as f64 + 0.5
        };
        if peak >= cs.threshold && cs.blobs.iter().any(kept) {
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

    /// The particle's height over the housing (the tips' peak is 1000).
    const PARTICLE: u16 = 900;
}
