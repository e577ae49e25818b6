//! Side view: where the pins' ends lie relative to their measured
//! crossings, from the row's mean end image and a model of a blurred end.
//!
//! A pin's end may be flat, chamfered or rounded, and blur pulls the
//! half-level crossing of a rounded end inside it (by 0.6 px for a
//! semicircular end of a pin 9 px wide under a blur of 2.5 px). The
//! contour's curvature measured on the blurred image is flattened by the
//! same blur (a semicircle's reads 0.04 px⁻¹ there against its 0.11), and
//! under noise one bar's curvature is lost altogether; so ok pins with
//! rounded ends were read short (840 217, 830 377, 830 975: every such
//! case a rounded end under blur ≥ 1.5 px). One part has one end shape and
//! one focus: every bar's end is cut out around its own crossing
//! (`TipCrossing::y_band`), the cut-outs averaged (noise falls with the
//! number of pins), and the mean end fitted by a model — a bar of
//! half-width `hw` whose end's corners are rounded by ρ (0: flat; `hw`: a
//! semicircle), blurred by a Gaussian σ — over ρ, σ, `hw` and the apex.
//! The apex's offset from the crossing is then the same for every bar of
//! the row.

use super::blur_model::erf;
use super::fit;
use super::gray::{Plane, Px};

/// One bar's end as measured: its axis and its band crossing (y px).
#[derive(Debug, Clone, Copy)]
pub(super) struct EndAt {
    pub axis: fit::Line,
    pub y_band: f64,
    /// The housing edge's y below the bar's end (px).
    pub base: f64,
}

/// Lateral samples of the end image, in half-widths (the bar and the
/// backlight beside it).
const OFFSETS: usize = 13;
const REACH: f64 = 1.4;
/// Along-axis sample step, px.
const DY: f64 = 0.5;
/// Points across the width in the model's integral.
const NX: usize = 32;

/// Φ(z), the standard normal distribution function.
#[inline]
fn phi(z: f64) -> f64 {
    0.5 * (1.0 + erf(z * std::f64::consts::FRAC_1_SQRT_2))
}

/// The end's contour below the apex (px) at lateral position `x` of a bar
/// of half-width `hw` whose corners are rounded by `rho`.
#[inline]
fn end_top(x: f64, hw: f64, rho: f64) -> f64 {
    let a = x.abs() - (hw - rho);
    if a <= 0.0 {
        0.0
    } else {
        rho - (rho * rho - a * a).max(0.0).sqrt()
    }
}

/// The model's mean end image at lateral offsets `ds` (px) and rows `ys`
/// (px, relative to the band crossing; the apex at `apex`), normalised to
/// the axis' level far inside the bar: Σ over the width of the lateral
/// blur times the along-axis step at that column's contour.
fn model(ds: &[f64], ys: &[f64], apex: f64, hw: f64, rho: f64, sigma: f64, out: &mut Vec<f64>) {
    out.clear();
    let dx = 2.0 * hw / NX as f64;
    let k = 1.0 / (sigma * (2.0 * std::f64::consts::PI).sqrt());
    let xs: Vec<f64> = (0..NX).map(|i| -hw + (i as f64 + 0.5) * dx).collect();
    let tops: Vec<f64> = xs.iter().map(|&x| end_top(x, hw, rho)).collect();
    let norm = erf(hw / (sigma * std::f64::consts::SQRT_2)).max(1e-6);
    let g: Vec<f64> = ds
        .iter()
        .flat_map(|&d| {
            xs.iter()
                .map(move |&x| k * (-0.5 * ((d - x) / sigma).powi(2)).exp() * dx)
        })
        .collect();
    let mut col = vec![0.0; NX];
    let mut vals = vec![0.0; ds.len() * ys.len()];
    for (j, &y) in ys.iter().enumerate() {
        for i in 0..NX {
            col[i] = phi((y - apex - tops[i]) / sigma);
        }
        for kk in 0..ds.len() {
            let gk = &g[kk * NX..(kk + 1) * NX];
            vals[kk * ys.len() + j] = gk.iter().zip(&col).map(|(a, b)| a * b).sum::<f64>() / norm;
        }
    }
    out.extend(vals);
}

/// Residuals of the model against `data` (same layout as [`model`]), its
/// amplitude solved in closed form.
fn residuals(
    data: &[f64],
    ds: &[f64],
    ys: &[f64],
    p: [f64; 3],
    rho_f: f64,
    buf: &mut Vec<f64>,
) -> Vec<f64> {
    let [apex, sigma, hw] = p;
    model(ds, ys, apex, hw, rho_f * hw, sigma, buf);
    let (mut mm, mut dm) = (0.0, 0.0);
    for (m, d) in buf.iter().zip(data) {
        mm += m * m;
        dm += m * d;
    }
    let amp = if mm > 0.0 { dm / mm } else { 1.0 };
    buf.iter().zip(data).map(|(m, d)| d - amp * m).collect()
}

/// Sum of squared [`residuals`].
fn sse(data: &[f64], ds: &[f64], ys: &[f64], p: [f64; 3], rho_f: f64, buf: &mut Vec<f64>) -> f64 {
    residuals(data, ds, ys, p, rho_f, buf)
        .iter()
        .map(|r| r * r)
        .sum()
}

/// Levenberg–Marquardt over (apex, σ, hw) for one corner radius (as a
/// share of the half-width); returns (sse, params).
fn fit_one(data: &[f64], ds: &[f64], ys: &[f64], p0: [f64; 3], rho_f: f64) -> (f64, [f64; 3]) {
    let mut buf = Vec::new();
    let mut p = p0;
    let mut cost = sse(data, ds, ys, p, rho_f, &mut buf);
    let mut lambda = 1e-2;
    let h = [0.02, 0.02, 0.02];
    for _ in 0..25 {
        // Residual Jacobian by finite differences.
        let resid = |q: [f64; 3], buf: &mut Vec<f64>| residuals(data, ds, ys, q, rho_f, buf);
        let r0 = resid(p, &mut buf);
        let mut jac = [vec![], vec![], vec![]];
        for a in 0..3 {
            let mut q = p;
            q[a] += h[a];
            let r1 = resid(q, &mut buf);
            jac[a] = r0.iter().zip(&r1).map(|(x, y)| (y - x) / h[a]).collect();
        }
        let mut jtj = [[0.0; 3]; 3];
        let mut jtr = [0.0; 3];
        for a in 0..3 {
            for b in 0..3 {
                jtj[a][b] = jac[a].iter().zip(&jac[b]).map(|(x, y)| x * y).sum();
            }
            jtr[a] = jac[a].iter().zip(&r0).map(|(x, y)| x * y).sum();
        }
        let mut improved = false;
        for _ in 0..6 {
            let mut m = jtj;
            for (a, row) in m.iter_mut().enumerate() {
                row[a] *= 1.0 + lambda;
                row[a] += 1e-12;
            }
            let Some(step) = solve3(m, jtr) else { break };
            // r = d − m(p): the step that lowers Σr² is −(JᵀJ)⁻¹Jᵀr.
            let q = [p[0] - step[0], p[1] - step[1], p[2] - step[2]];
            if !(q[1] > 0.2 && q[2] > 0.5) {
                lambda *= 10.0;
                continue;
            }
            let c = sse(data, ds, ys, q, rho_f, &mut buf);
            if c < cost {
                let moved = (0..3).map(|a| (q[a] - p[a]).abs()).fold(0.0, f64::max);
                p = q;
                cost = c;
                lambda = (lambda * 0.3).max(1e-6);
                improved = true;
                if moved < 1e-4 {
                    return (cost, p);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (cost, p)
}

/// Solves a 3 × 3 linear system (Cramer's rule); `None` when singular.
fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if !(d.abs() > 1e-300) {
        return None;
    }
    let mut x = [0.0; 3];
    for (c, xc) in x.iter_mut().enumerate() {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = b[r];
        }
        *xc = det(&mc) / d;
    }
    Some(x)
}

/// The apex's offset from the band crossing (px along y, negative: the
/// apex above the crossing), the same for every bar of the row, from the
/// mean of the bars' end images; `hw0` and `sigma0` are the row's median
/// half-width and blur as measured (starting values). `None` when no bar
/// leaves room for its end image or the fit does not settle.
pub(super) fn row_end_offset<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    ends: &[EndAt],
    hw0: f64,
    sigma0: f64,
) -> Option<f64> {
    if !(hw0 >= 2.0 && sigma0.is_finite()) {
        return None;
    }
    let s0 = sigma0.max(0.5);
    let ds: Vec<f64> = (0..OFFSETS)
        .map(|k| (k as f64 / (OFFSETS - 1) as f64 * 2.0 - 1.0) * REACH * hw0)
        .collect();
    let above = 3.0 * s0 + 3.0;
    let below = hw0 + 3.0 * s0 + 3.0;
    let ny = ((above + below) / DY) as usize + 1;
    let ys: Vec<f64> = (0..ny).map(|j| -above + j as f64 * DY).collect();
    let mut mean = vec![0.0; OFFSETS * ny];
    let mut used = 0usize;
    let (w, h) = (plane.w as f64, plane.h as f64);
    for e in ends {
        let (y0, y1) = (e.y_band - above, e.y_band + below);
        let xs = [e.axis.y_at(y0), e.axis.y_at(y1)];
        let room = y0 >= 0.0
            && y1 <= h - 1.0
            && y1 <= e.base - 3.0 * s0 - 2.0
            && xs
                .iter()
                .all(|&x| x - REACH * hw0 >= 0.0 && x + REACH * hw0 <= w - 1.0);
        if !room {
            continue;
        }
        let mut v = vec![0.0; OFFSETS * ny];
        for (k, &d) in ds.iter().enumerate() {
            for (j, &y) in ys.iter().enumerate() {
                let yy = e.y_band + y;
                v[k * ny + j] = (sign * plane.bilinear(e.axis.y_at(yy) + d, yy)) as f64;
            }
        }
        // Backlight: the first 2 px across every offset; the bar: the last
        // 3 px of the three middle offsets.
        let mut top: Vec<f64> = (0..OFFSETS)
            .flat_map(|k| (0..4).map(move |j| (k, j)))
            .map(|(k, j)| v[k * ny + j])
            .collect();
        let mid = OFFSETS / 2;
        let mut bot: Vec<f64> = (mid - 1..=mid + 1)
            .flat_map(|k| (ny - 6..ny).map(move |j| (k, j)))
            .map(|(k, j)| v[k * ny + j])
            .collect();
        let (lo, hi) = (median(&mut top), median(&mut bot));
        if !(hi - lo > 0.0) {
            continue;
        }
        for (m, x) in mean.iter_mut().zip(&v) {
            *m += (x - lo) / (hi - lo);
        }
        used += 1;
    }
    if used == 0 {
        return None;
    }
    for m in &mut mean {
        *m /= used as f64;
    }
    // Over the corner radius from flat to a semicircle, the best fit.
    const STEPS: usize = 10;
    let fits: Vec<(f64, [f64; 3])> = (0..=STEPS)
        .map(|i| fit_one(&mean, &ds, &ys, [0.0, s0, hw0], i as f64 / STEPS as f64))
        .collect();
    let ok = |p: &[f64; 3]| {
        p[0].abs() <= hw0 + 2.0 * s0
            && p[2] >= 0.6 * hw0
            && p[2] <= 1.5 * hw0
            && p[1] <= 2.0 * s0 + 1.0
    };
    let (ib, best) = fits
        .iter()
        .enumerate()
        .filter(|(_, f)| f.0.is_finite() && ok(&f.1))
        .min_by(|a, b| a.1.0.total_cmp(&b.1.0))?;
    // Refined between grid steps by a parabola through the neighbours'
    // costs, the apex interpolated linearly.
    let mut apex = best.1[0];
    if ib > 0 && ib < STEPS {
        let (a, b, c) = (fits[ib - 1].0, best.0, fits[ib + 1].0);
        let den = a - 2.0 * b + c;
        if den > 0.0 {
            let t = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
            let nb = if t < 0.0 {
                &fits[ib - 1]
            } else {
                &fits[ib + 1]
            };
            if ok(&nb.1) {
                apex += t.abs() * (nb.1[0] - best.1[0]);
            }
        }
    }
    apex.is_finite().then_some(apex)
}

fn median(v: &mut [f64]) -> f64 {
    let m = v.len() / 2;
    *v.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model's axis crossing of a flat end is its apex whatever the
    /// blur, and a semicircular end's lies inside it by about σ²/(2r)
    /// (0.59 px for r = 4.43, σ = 2.5, from a numeric 2-D convolution).
    #[test]
    fn the_model_end_crossings() {
        let ys: Vec<f64> = (0..400).map(|j| -10.0 + j as f64 * 0.05).collect();
        let mut out = Vec::new();
        let cross = |v: &[f64]| {
            let i = v.iter().position(|&x| x >= 0.5).unwrap();
            ys[i - 1] + (0.5 - v[i - 1]) / (v[i] - v[i - 1]) * 0.05
        };
        model(&[0.0], &ys, 0.0, 4.43, 0.0, 2.5, &mut out);
        assert!(cross(&out).abs() < 0.01, "{}", cross(&out));
        model(&[0.0], &ys, 0.0, 4.43, 4.43, 2.5, &mut out);
        let c = cross(&out);
        assert!((c - 0.585).abs() < 0.05, "{c}");
    }
}
