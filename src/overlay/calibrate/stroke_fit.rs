//! Fitting the clearance from the stroke: curves over the cycle, their
//! interpolation across the simulated clearance grid, a golden-section search.

use std::f64::consts::TAU;

/// Stroke curves of one prediction: mean, spread and the mean's derivative in φ.
pub(super) struct Curves {
    pub(super) mean: Vec<f64>,
    pub(super) spread: Vec<f64>,
    pub(super) dmean: Vec<f64>,
    /// Variances of the mean and of the spread (sampling).
    pub(super) var_mean: Vec<f64>,
    pub(super) var_spread: Vec<f64>,
}

pub(super) fn curves_of(rows: &[&[f64]], n: usize) -> Curves {
    let mut mean = vec![f64::NAN; n];
    let mut spread = vec![f64::NAN; n];
    let mut var_mean = vec![f64::NAN; n];
    let mut var_spread = vec![f64::NAN; n];
    for j in 0..n {
        let v: Vec<f64> = rows
            .iter()
            .map(|r| r[j])
            .filter(|x| x.is_finite())
            .collect();
        if v.len() < 2 {
            continue;
        }
        let k = v.len() as f64;
        let m = v.iter().sum::<f64>() / k;
        let s2 = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0);
        mean[j] = m;
        spread[j] = s2.sqrt();
        var_mean[j] = s2 / k;
        var_spread[j] = s2 / (2.0 * (k - 1.0));
    }
    let dmean = (0..n)
        .map(|j| (mean[(j + 1) % n] - mean[(j + n - 1) % n]) / (2.0 * TAU / n as f64))
        .collect();
    Curves {
        mean,
        spread,
        dmean,
        var_mean,
        var_spread,
    }
}

/// Linear interpolation of two curves' values.
pub(super) fn lerp(a: &[f64], b: &[f64], w: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + w * (y - x)).collect()
}

/// The stroke objective at predicted curves `p` for measured curves `m`;
/// returns (objective, Δz, ψ, spread RMS residual, mean RMS residual).
pub(super) fn stroke_objective(m: &Curves, p: &Curves, noise: f64) -> (f64, f64, f64, f64, f64) {
    let n = m.mean.len();
    let floor = 1e-8; // (0.1 µm)²
    // Spread part.
    let mut js = 0.0;
    let mut rs = Vec::new();
    for j in 0..n {
        let (sm, sp) = (m.spread[j], p.spread[j]);
        if !sm.is_finite() || !sp.is_finite() {
            continue;
        }
        let pred = (sp * sp + noise * noise).sqrt();
        let v = m.var_spread[j] + p.var_spread[j] + floor;
        js += (sm - pred).powi(2) / v;
        rs.push(sm - pred);
    }
    // Mean part: r = M + Δz − P + ψ·P′, weighted; solve the 2×2 normal equations.
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut pts = Vec::new();
    for j in 0..n {
        let (mm, pm, dp) = (m.mean[j], p.mean[j], p.dmean[j]);
        if !mm.is_finite() || !pm.is_finite() || !dp.is_finite() {
            continue;
        }
        let w = 1.0 / (m.var_mean[j] + p.var_mean[j] + floor);
        let y = pm - mm; // = Δz + ψ·P′
        a11 += w;
        a12 += w * dp;
        a22 += w * dp * dp;
        b1 += w * y;
        b2 += w * y * dp;
        pts.push((w, y, dp));
    }
    let det = a11 * a22 - a12 * a12;
    let (dz, psi) = if det.abs() > 1e-300 {
        ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det)
    } else {
        (b1 / a11.max(1e-300), 0.0)
    };
    let mut jm = 0.0;
    let mut rm = Vec::new();
    for (w, y, dp) in pts {
        let r = y - dz - psi * dp;
        jm += w * r * r;
        rm.push(r);
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    (js + jm, dz, psi, rms(&rs), rms(&rm))
}

/// Predicted curves at clearance c, interpolated in the grid of predictions.
pub(super) fn interp_curves(grid: &[(f64, Curves)], c: f64) -> Curves {
    let i = grid.partition_point(|g| g.0 < c).clamp(1, grid.len() - 1);
    let (c0, a) = (&grid[i - 1].0, &grid[i - 1].1);
    let (c1, b) = (&grid[i].0, &grid[i].1);
    let w = ((c - c0) / (c1 - c0)).clamp(0.0, 1.0);
    Curves {
        mean: lerp(&a.mean, &b.mean, w),
        spread: lerp(&a.spread, &b.spread, w),
        dmean: lerp(&a.dmean, &b.dmean, w),
        var_mean: lerp(&a.var_mean, &b.var_mean, w),
        var_spread: lerp(&a.var_spread, &b.var_spread, w),
    }
}

pub(super) use crate::solver::roots::golden_min as golden;

/// The clearance that minimises the stroke objective (grid, then golden section).
pub(super) fn fit_clearance(m: &Curves, grid: &[(f64, Curves)], noise: f64) -> (f64, f64, f64) {
    let obj = |c: f64| stroke_objective(m, &interp_curves(grid, c), noise).0;
    let k = (0..grid.len())
        .min_by(|&a, &b| obj(grid[a].0).total_cmp(&obj(grid[b].0)))
        .unwrap_or(0);
    let lo = grid[k.saturating_sub(1)].0;
    let hi = grid[(k + 1).min(grid.len() - 1)].0;
    let c = golden(lo, hi, 40, obj);
    let (_, dz, psi, _, _) = stroke_objective(m, &interp_curves(grid, c), noise);
    (c, dz, psi)
}
