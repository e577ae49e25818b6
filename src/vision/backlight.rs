//! Back-lit images (the side view's silhouettes): the backlight is not
//! flat (vignetting, gradients), so one threshold over the raw image cuts
//! pins in the dim corners. Dividing by a smooth fitted backlight puts it at
//! one level everywhere.

use super::detect;
use super::gray::{Coarse, Plane, Px};
use super::side_edge::{BACKLIGHT, silhouette_level};

/// Divides a back-lit coarse image (`sign` space: the backlight is the
/// low level) by its backlight: a cubic surface fitted to the brightest
/// decile of each cell of a 12 × 12 grid, with cells darker than the fit
/// (the housing, pins) weighed down until they stop pulling it. The
/// result is −(image / backlight) × 1000: the backlight at −1000
/// everywhere, silhouettes above it.
pub(crate) fn normalise_backlight(c: &mut Coarse) {
    let (w, h) = (c.w, c.h);
    if w < 8 || h < 8 {
        return;
    }
    let n = 12usize;
    let mut cells: Vec<(f64, f64, f64)> = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x0, x1) = (i * w / n, ((i + 1) * w / n).max(i * w / n + 1));
            let (y0, y1) = (j * h / n, ((j + 1) * h / n).max(j * h / n + 1));
            let mut v: Vec<f32> = Vec::with_capacity((x1 - x0) * (y1 - y0));
            for y in y0..y1.min(h) {
                for x in x0..x1.min(w) {
                    v.push(-c.data[y * w + x]);
                }
            }
            if v.is_empty() {
                continue;
            }
            let q = (v.len() - 1) * 9 / 10;
            let (_, val, _) = v.select_nth_unstable_by(q, |a, b| a.total_cmp(b));
            let u = 2.0 * (0.5 * (x0 + x1) as f64) / w as f64 - 1.0;
            let t = 2.0 * (0.5 * (y0 + y1) as f64) / h as f64 - 1.0;
            cells.push((u, t, *val as f64));
        }
    }
    let basis = |u: f64, t: f64| -> [f64; 10] {
        [
            1.0,
            u,
            t,
            u * u,
            u * t,
            t * t,
            u * u * u,
            u * u * t,
            u * t * t,
            t * t * t,
        ]
    };
    let mut wts = vec![1.0f64; cells.len()];
    let mut coef = nalgebra::SVector::<f64, 10>::zeros();
    for _ in 0..10 {
        let mut ata = nalgebra::SMatrix::<f64, 10, 10>::zeros();
        let mut atb = nalgebra::SVector::<f64, 10>::zeros();
        for (cell, &wt) in cells.iter().zip(&wts) {
            let b = nalgebra::SVector::<f64, 10>::from(basis(cell.0, cell.1));
            ata += wt * b * b.transpose();
            atb += wt * cell.2 * b;
        }
        for d in 0..10 {
            ata[(d, d)] += 1e-9;
        }
        let Some(sol) = ata.lu().solve(&atb) else {
            return;
        };
        coef = sol;
        for (cell, wt) in cells.iter().zip(wts.iter_mut()) {
            let f = coef.dot(&nalgebra::SVector::<f64, 10>::from(basis(cell.0, cell.1)));
            // Darker than the backlight by more than 8 %: a silhouette.
            *wt = if cell.2 >= 0.92 * f { 1.0 } else { 1e-3 };
        }
    }
    let mut peak = 0f64;
    for (cell, _) in cells.iter().zip(&wts) {
        peak = peak.max(cell.2);
    }
    let floor = (0.05 * peak).max(1e-6);
    for y in 0..h {
        let t = 2.0 * (y as f64 + 0.5) / h as f64 - 1.0;
        for x in 0..w {
            let u = 2.0 * (x as f64 + 0.5) / w as f64 - 1.0;
            let b = coef
                .dot(&nalgebra::SVector::<f64, 10>::from(basis(u, t)))
                .max(floor);
            let i = y * w + x;
            c.data[i] = (c.data[i] as f64 / b * 1000.0) as f32;
        }
    }
}

/// Share of the way from the backlight to the silhouette's level above
/// which a coarse pixel is surely silhouette (housing, a pin's core): the
/// backlight's patches that the cubic surface leaves (a sharp gradient
/// band, a mottled diffuser) stay below it.
const SURE_SILHOUETTE: f32 = 0.75;

/// Flattens what the cubic backlight leaves in a normalised back-lit
/// coarse image (`normalise_backlight`): the local backlight is the mean of
/// the pixels that are not surely silhouette (above [`SURE_SILHOUETTE`] of
/// `level`, dilated by `dilate` coarse px) within about `radius` coarse px
/// (two box passes), and is moved to −1000. Pixels with too little
/// backlight about them (inside a large housing block) are left alone.
///
/// A cubic surface cannot follow a gradient band a few tens of pixels wide
/// (800 835: the band's dim side passed the threshold, joined the housing
/// and its edge was found tilted 33°) nor a mottled backlight whose patches
/// are as dark as half a silhouette (py 550 296: the pins merged with dark
/// patches above them and were measured 3–6 mm high or lost).
pub(crate) fn flatten_residual(c: &mut Coarse, level: f32, radius: usize, dilate: usize) {
    let (w, h) = (c.w, c.h);
    if w < 8 || h < 8 || !(level > -1000.0) || radius == 0 {
        return;
    }
    let sure_t = -1000.0 + SURE_SILHOUETTE * (level + 1000.0);
    // Sure silhouette, dilated by a (2 dilate + 1)² square.
    let sure: Vec<f32> = c
        .data
        .iter()
        .map(|&v| if v > sure_t { 1.0 } else { 0.0 })
        .collect();
    let excl: Vec<bool> = super::morph::dilate_square(&sure, w, h, dilate)
        .into_iter()
        .map(|v| v > 0.5)
        .collect();
    let mut num: Vec<f32> = c
        .data
        .iter()
        .zip(&excl)
        .map(|(&v, &e)| if e { 0.0 } else { v + 1000.0 })
        .collect();
    let mut den: Vec<f32> = excl.iter().map(|&e| if e { 0.0 } else { 1.0 }).collect();
    for _ in 0..2 {
        num = super::morph::box_mean(&num, w, h, radius);
        den = super::morph::box_mean(&den, w, h, radius);
    }
    for i in 0..w * h {
        if den[i] > 0.05 {
            c.data[i] -= num[i] / den[i];
        }
    }
}

/// The silhouette's threshold on a back-lit coarse image (`sign` space,
/// built from `plane`), and the silhouette's depth below the backlight
/// (share of it, where a silhouette is found); `coarse` is left
/// normalised and flattened, the image the threshold applies to.
///
/// The backlight is divided out ([`normalise_backlight`]); under noise
/// comparable to the silhouette's half level the image is first box
/// averaged, never wider than `widest` coarse px ([`smoothing_radius`]);
/// what the cubic backlight leaves is flattened over about 36 px (bands
/// and patches wider than that, [`flatten_residual`]), the silhouette's
/// level taken first; the threshold is then Otsu's on the flattened
/// image, never nearer the backlight than halfway to the silhouette's
/// level ([`super::side_edge::silhouette_threshold`]).
///
/// `min_depth` (share of the backlight) is the least depth the
/// silhouette's level is taken at when flattening: 0 at first; a retry
/// passes the envelope's least contrast, for a frame whose darkest
/// percent is a backlight band the cubic left, not the housing (see
/// [`super::side::inspect_side`]).
pub(crate) fn silhouette_threshold_flat<P: Px>(
    plane: &Plane<P>,
    coarse: &mut Coarse,
    sign: f32,
    widest: usize,
    min_depth: f32,
) -> (f32, Option<f32>) {
    let (cw, ch, k) = (coarse.w, coarse.h, coarse.k);
    normalise_backlight(coarse);
    let mut t = detect::otsu(&coarse.data, cw, ch);
    let (r, sigma) = smoothing_radius(
        coarse,
        super::side_edge::silhouette_threshold(&coarse.data, t),
        widest,
    );
    // What the silhouette's level is read beyond: with the box mean, never
    // nearer the backlight than 4 σ of the smoothed noise (a small part in
    // a large frame is under the 1 % quantile the level otherwise starts
    // from, Rust 1 011 186).
    let mut floor = f32::MIN;
    if r > 0 {
        *coarse = Coarse::build(plane, k, sign);
        coarse.data = super::morph::box_mean(&coarse.data, cw, ch, r);
        normalise_backlight(coarse);
        t = detect::otsu(&coarse.data, cw, ch);
        floor = BACKLIGHT + 4.0 * sigma / (2 * r + 1) as f32;
    }
    if let Some(level) = silhouette_level(&coarse.data, t.max(floor)) {
        let radius = (36 / k).max(2);
        let dilate = 6usize.div_ceil(k).max(1);
        flatten_residual(
            coarse,
            level.max(BACKLIGHT * (1.0 - min_depth)),
            radius,
            dilate,
        );
        t = detect::otsu(&coarse.data, cw, ch);
    }
    if let Some(level) = silhouette_level(&coarse.data, t.max(floor)) {
        t = t.max(0.5 * (BACKLIGHT + level));
    }
    let depth = silhouette_level(&coarse.data, t).map(|l| (l - BACKLIGHT) / -BACKLIGHT);
    (t, depth)
}

/// Least signal-to-noise ratio, per coarse pixel, of the silhouette's half
/// level above the backlight for its threshold to cut silhouette from
/// backlight: below it, [`smoothing_radius`] asks for a box mean first.
const MIN_HALF_LEVEL_SNR: f32 = 4.0;

/// The box-mean radius (coarse px) that lifts the half level `t` of a
/// normalised back-lit coarse image to [`MIN_HALF_LEVEL_SNR`] times the
/// pixel noise, and never a box wider than `max_width` coarse px (a pin's
/// width: a wider box would melt the pins into the backlight); 0 when the
/// image is quiet enough; and the pixel noise σ.
///
/// At coarse factor 1 (pins about 7 px wide) on a dim, noisy backlight
/// (Rust 1 030 800: σ 15 DN, silhouette 26 % below the backlight, gain
/// 0.78, vignetting 0.40) the half level stood about one σ above the
/// backlight: a third of the backlight passed the threshold, the pins
/// were lost in it and noise clumps in a dim corner stood on the
/// housing's edge as "pins" 500 px from the part. The noise is the
/// median absolute difference of horizontal neighbours (edges are too
/// few to move it), as a σ of one pixel.
pub(crate) fn smoothing_radius(c: &Coarse, t: f32, max_width: usize) -> (usize, f32) {
    let (w, h) = (c.w, c.h);
    let half = t - BACKLIGHT;
    if w < 2 || h == 0 || !(half > 0.0) {
        return (0, 0.0);
    }
    let mut d: Vec<f32> = Vec::with_capacity((w - 1) * h);
    for row in c.data.chunks_exact(w) {
        d.extend(row.windows(2).map(|p| (p[1] - p[0]).abs()));
    }
    let m = d.len() / 2;
    let med = *d.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1;
    // |N(0, 2σ²)| has median 0.954 σ.
    let sigma = med / 0.954;
    let width = (MIN_HALF_LEVEL_SNR * sigma / half).ceil();
    if !(width > 1.0) {
        return (0, sigma);
    }
    let widest = max_width.max(1);
    (((width as usize).min(widest)).saturating_sub(1) / 2, sigma)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dark_patch_of_backlight_is_flattened_and_the_silhouette_kept() {
        // Normalised sign space, 120 × 80: backlight at -1000 with a dark
        // patch (Gaussian, σ 6 px, +300 at (30, 20): beyond the half-level
        // threshold -750 of a silhouette at -500); a housing block (rows
        // 50..80) and a pin 4 px wide (columns 80..84, rows 30..50) at -500.
        let (w, h) = (120usize, 80usize);
        let solid = |x: usize, y: usize| y >= 50 || ((80..84).contains(&x) && y >= 30);
        let mut data = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f32 - 30.0, y as f32 - 20.0);
                let patch = 300.0 * (-(dx * dx + dy * dy) / 72.0).exp();
                data[y * w + x] = if solid(x, y) { -500.0 } else { -1000.0 + patch };
            }
        }
        assert!(data[20 * w + 30] > -750.0);
        let mut c = Coarse {
            w,
            h,
            k: 1,
            data,
            quantum: 0.0,
        };
        flatten_residual(&mut c, -500.0, 8, 1);
        for y in 0..h {
            for x in 0..w {
                let v = c.data[y * w + x];
                assert_eq!(v > -750.0, solid(x, y), "({x}, {y}) {v}");
            }
        }
        // The pin's level is kept within a few per cent of the contrast.
        assert!((c.data[40 * w + 81] + 500.0).abs() < 25.0);
    }

    /// A normalised frame at the backlight (-1000) with Gaussian noise of
    /// σ `sigma`, 200 × 150.
    fn noisy(sigma: f64) -> Coarse {
        let mut rng = crate::vision::synth::Rng::new(7);
        let (w, h) = (200usize, 150usize);
        let data = (0..w * h)
            .map(|_| (-1000.0 + sigma * rng.normal()) as f32)
            .collect();
        Coarse {
            w,
            h,
            k: 1,
            data,
            quantum: 0.0,
        }
    }

    #[test]
    fn the_box_lifts_the_half_level_to_four_sigmas_and_is_never_wider_than_a_pin() {
        // Half level 130 above the backlight: σ 20 leaves 6.5 σ (no box);
        // σ 95 leaves 1.4 σ and asks for a box 3 px wide (4 × 95 / 130 =
        // 2.9), σ 200 for 7 px (6.2), unless a pin is narrower.
        let t = -870.0;
        let (r, sigma) = smoothing_radius(&noisy(20.0), t, 7);
        assert_eq!(r, 0);
        assert!((sigma - 20.0).abs() < 1.0, "σ {sigma}");
        let (r, sigma) = smoothing_radius(&noisy(95.0), t, 7);
        assert_eq!(r, 1);
        assert!((sigma - 95.0).abs() < 3.0, "σ {sigma}");
        assert_eq!(smoothing_radius(&noisy(200.0), t, 9).0, 3);
        assert_eq!(smoothing_radius(&noisy(200.0), t, 5).0, 2);
        // No half level above the backlight: nothing to lift.
        assert_eq!(smoothing_radius(&noisy(95.0), -1000.0, 7).0, 0);
    }
}
