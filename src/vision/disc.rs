//! A tip's energy inside a fixed disc, and the disc's pixels with their
//! weights: a measure linear in the image, beside the mask-based ones of
//! [`super::measure`], for judging tips under blur and noise (`top`,
//! `top_noisy`, `tip_levels`).

use super::gray::{Plane, Px};

/// A tip's energy inside a fixed disc: Σ (v − `level`) over the pixels
/// around `c` (full-resolution px, `sign` space), each weighted by how
/// much of it lies within radius `r` (a 1 px ramp across the rim). Unlike
/// [`super::measure::BlobMeasure::energy`] it is linear in the image and does not depend
/// on a mask's extent, so noise only adds zero-mean scatter.
pub fn disc_energy<P: Px>(plane: &Plane<P>, sign: f32, c: (f64, f64), r: f64, level: f32) -> f64 {
    let mut e = 0f64;
    for_each_in_disc(plane, sign, c, r, |w, v| e += w * (v - level) as f64);
    e
}

/// Calls `f(weight, value)` for every pixel of the disc of radius `r`
/// around `c` (`sign` space), weighted by how much of it lies within `r`
/// (a 1 px ramp across the rim); pixels beyond the image are left out.
pub(crate) fn for_each_in_disc<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    c: (f64, f64),
    r: f64,
    mut f: impl FnMut(f64, f32),
) {
    let (Some(xm), Some(ym)) = (plane.w.checked_sub(1), plane.h.checked_sub(1)) else {
        return;
    };
    let x0 = (c.0 - r - 1.0).floor().max(0.0) as usize;
    let y0 = (c.1 - r - 1.0).floor().max(0.0) as usize;
    let x1 = ((c.0 + r + 1.0).ceil() as usize).min(xm);
    let y1 = ((c.1 + r + 1.0).ceil() as usize).min(ym);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let d = (x as f64 - c.0).hypot(y as f64 - c.1);
            let w = (r + 0.5 - d).clamp(0.0, 1.0);
            if w > 0.0 {
                f(w, sign * plane.at(x, y));
            }
        }
    }
}
