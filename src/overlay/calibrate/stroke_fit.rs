//! Fitting the clearance from the stroke: curves over the cycle, their
//! interpolation across the simulated clearance grid, a golden-section search.

use rayon::prelude::*;
use std::f64::consts::TAU;

/// Stroke curves of one prediction: mean, spread and the mean's derivative in φ.
#[derive(Clone)]
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

/// Curves of a long simulated ensemble as the measured statistic would see
/// them: the mean over all revolutions, but the spread as the mean, over
/// windows of `w` consecutive revolutions (overlapping by half), of each
/// window's sample standard deviation. The measured spread is the standard
/// deviation of k cycles in a row: for small k it is biased low (the
/// sample-σ factor c4(k), and more so because consecutive revolutions of the
/// chaotic motion are correlated). Compared with the spread of a long
/// ensemble, the fit would then read a smaller clearance; compared with the
/// same statistic at the same k, the bias is the same on both sides.
/// `w` ≥ the number of revolutions (or < 2): the plain [`curves_of`].
pub(super) fn curves_windowed(rows: &[&[f64]], n: usize, w: usize) -> Curves {
    let r = rows.len();
    let mut c = curves_of(rows, n);
    if w < 2 || w >= r {
        return c;
    }
    let step = (w / 2).max(1);
    let starts: Vec<usize> = (0..=r - w).step_by(step).collect();
    // Independent windows in the ensemble (for the spread's own sampling variance).
    let indep = (r as f64 / w as f64).max(1.0);
    for j in 0..n {
        let mut sds = Vec::with_capacity(starts.len());
        for &a in &starts {
            let column: Vec<f64> = rows[a..a + w].iter().map(|row| row[j]).collect();
            // NaN: fewer than two finite values in the window.
            let sd = sample_sd(&column);
            if sd.is_finite() {
                sds.push(sd);
            }
        }
        if sds.len() < 2 {
            continue;
        }
        let k = sds.len() as f64;
        let m = sds.iter().sum::<f64>() / k;
        c.spread[j] = m;
        c.var_spread[j] = sds.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0) / indep;
    }
    c
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

/// The clearance that minimises the stroke objective: the best grid node,
/// a scan of 64 points between its neighbours (the interpolated objective
/// has kinks at the nodes and need not be unimodal there: a golden section
/// alone can end in the wrong dip and move a refit by half a node spacing),
/// then a golden section around the best point of the scan.
pub(super) fn fit_clearance(m: &Curves, grid: &[(f64, Curves)], noise: f64) -> (f64, f64, f64) {
    let obj = |c: f64| stroke_objective(m, &interp_curves(grid, c), noise).0;
    let k = (0..grid.len())
        .min_by(|&a, &b| obj(grid[a].0).total_cmp(&obj(grid[b].0)))
        .unwrap_or(0);
    let lo = grid[k.saturating_sub(1)].0;
    let hi = grid[(k + 1).min(grid.len() - 1)].0;
    let scan = 64;
    let h = (hi - lo) / scan as f64;
    let best = (0..=scan)
        .map(|i| lo + h * i as f64)
        .min_by(|a, b| obj(*a).total_cmp(&obj(*b)))
        .unwrap_or(grid[k].0);
    let c = golden((best - h).max(lo), (best + h).min(hi), 30, obj);
    let (_, dz, psi, _, _) = stroke_objective(m, &interp_curves(grid, c), noise);
    (c, dz, psi)
}

/// Sample standard deviation (n − 1); NaN below 2 values.
pub(super) fn sample_sd(v: &[f64]) -> f64 {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 2 {
        return f64::NAN;
    }
    let k = v.len() as f64;
    let m = v.iter().sum::<f64>() / k;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0)).sqrt()
}

/// Parametric bootstrap of the stroke fit from the long ensembles of the
/// fine grid: each fine node's revolutions are cut into logs of `k`
/// consecutive revolutions; each such log, with noise σ `noise` added, is
/// fitted like a measured log against the grid in which that node's curves
/// are rebuilt without it (so it is not fitted against itself). Returns the
/// errors of the fits against the node's clearance, scaled to `c_ref` (the
/// sampling spread is about proportional to the clearance): (c, Δz, ψ) −
/// (c_node, 0, 0). `fine` holds (index into `grid`, the node's revolutions).
pub(super) fn bootstrap(
    grid: &[(f64, Curves)],
    fine: &[(usize, &[Vec<f64>])],
    k: usize,
    noise: f64,
    c_ref: f64,
) -> Vec<(f64, f64, f64)> {
    let k = k.max(2);
    let n = grid.first().map_or(0, |g| g.1.mean.len());
    let jobs: Vec<(usize, usize)> = fine
        .iter()
        .enumerate()
        .flat_map(|(f, (_, revs))| (0..revs.len() / k).map(move |w| (f, w)))
        .collect();
    jobs.par_iter()
        .map(|&(f, w)| {
            let (gi, revs) = fine[f];
            let c_node = grid[gi].0;
            let rest: Vec<&[f64]> = revs
                .iter()
                .enumerate()
                .filter(|(i, _)| i / k != w)
                .map(|(_, v)| v.as_slice())
                .collect();
            let mut g: Vec<(f64, Curves)> = grid
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != gi)
                .map(|(_, (c, cu))| (*c, cu.clone()))
                .collect();
            let at = g.partition_point(|x| x.0 < c_node);
            g.insert(at, (c_node, curves_windowed(&rest, n, k)));
            let mut rng =
                crate::rng::SplitMix64::<0xB007_57A9_0000_0001>::new((f * 100_003 + w) as u64 + 1);
            let noisy: Vec<Vec<f64>> = revs[w * k..(w + 1) * k]
                .iter()
                .map(|row| row.iter().map(|x| x + noise * rng.normal()).collect())
                .collect();
            let rows: Vec<&[f64]> = noisy.iter().map(|v| v.as_slice()).collect();
            let (c, dz, psi) = fit_clearance(&curves_of(&rows, n), &g, noise);
            ((c - c_node) * c_ref / c_node, dz, psi)
        })
        .collect()
}

/// Student's t two-sided 95 % quantile for ν degrees of freedom (table,
/// linear in 1/ν between its rows; 1.96 for ν → ∞, 12.71 for ν ≤ 1).
pub(super) fn t95(nu: f64) -> f64 {
    const T: [(f64, f64); 16] = [
        (1.0, 12.706),
        (2.0, 4.303),
        (3.0, 3.182),
        (4.0, 2.776),
        (5.0, 2.571),
        (6.0, 2.447),
        (7.0, 2.365),
        (8.0, 2.306),
        (10.0, 2.228),
        (12.0, 2.179),
        (15.0, 2.131),
        (20.0, 2.086),
        (30.0, 2.042),
        (60.0, 2.000),
        (120.0, 1.980),
        (f64::INFINITY, 1.960),
    ];
    if !nu.is_finite() || nu.is_nan() {
        return if nu.is_nan() { 2.0 } else { 1.960 };
    }
    if nu <= 1.0 {
        return T[0].1;
    }
    let i = T.partition_point(|x| x.0 < nu).min(T.len() - 1);
    let (n0, t0) = T[i - 1];
    let (n1, t1) = T[i];
    let x = |n: f64| if n.is_finite() { 1.0 / n } else { 0.0 };
    let w = (x(nu) - x(n0)) / (x(n1) - x(n0));
    t0 + w * (t1 - t0)
}
