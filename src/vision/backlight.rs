//! Back-lit images (the side view's silhouettes): the backlight is not
//! flat (vignetting, gradients), so one threshold over the raw image cuts
//! pins in the dim corners. Dividing by a smooth fitted backlight puts it at
//! one level everywhere.

use super::gray::Coarse;

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
