//! Fitting the clearance from the stroke: curves over the cycle, their
//! interpolation across the simulated clearance grid, a golden-section search.

use crate::model::Params;
use crate::overlay::predict::{PredictOptions, predict};
use crate::progress::Progress;
use rayon::prelude::*;
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
            let v: Vec<f64> = rows[a..a + w]
                .iter()
                .map(|row| row[j])
                .filter(|x| x.is_finite())
                .collect();
            if v.len() < 2 {
                continue;
            }
            let k = v.len() as f64;
            let m = v.iter().sum::<f64>() / k;
            sds.push((v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0)).sqrt());
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

/// What [`bootstrap`] simulates and fits against.
pub(super) struct BootInput<'a> {
    pub(super) base: &'a Params,
    pub(super) motor_rpm: f64,
    pub(super) popts: &'a PredictOptions,
    /// Clearance simulated (mm).
    pub(super) c: f64,
    /// Cycles per simulated log (the measured log's).
    pub(super) k: usize,
    pub(super) windows: usize,
    pub(super) max_revs: usize,
    /// Laser noise σ added to every sample (mm).
    pub(super) noise: f64,
    pub(super) grid: &'a [(f64, Curves)],
}

/// Parametric bootstrap of the stroke fit: `windows` logs of `k` consecutive
/// revolutions of the model at clearance `c` (fewer when that would exceed
/// `max_revs`, at least 6), simulated as 4 independent runs (clearances
/// c·(1 + i·10⁻⁶): the chaotic motion forgets the difference within a few
/// revolutions), noise added, each fitted like a measured log. Returns the
/// fits (c, Δz, ψ); empty when the model fails.
pub(super) fn bootstrap(b: &BootInput) -> Vec<(f64, f64, f64)> {
    let k = b.k.max(2);
    let windows = b.windows.min(b.max_revs / k).max(6);
    let runs = 4usize.min(windows);
    let per_run = windows.div_ceil(runs);
    let sims: Vec<Vec<Vec<f64>>> = (0..runs)
        .into_par_iter()
        .filter_map(|i| {
            let mut p = b.base.clone();
            p.clearance = b.c * 1e-3 * (1.0 + 1e-6 * (i as f64 + 1.0));
            let o = PredictOptions {
                revs: per_run * k,
                warmup: b.popts.warmup + 2.0,
                ..b.popts.clone()
            };
            predict(&p, b.motor_rpm, &o, &Progress::hidden())
                .ok()
                .map(|r| r.stroke_revs)
        })
        .collect();
    let mut wins: Vec<&[Vec<f64>]> = Vec::new();
    for revs in &sims {
        for w in revs.chunks_exact(k) {
            wins.push(w);
        }
    }
    wins.truncate(windows);
    let n = b.grid.first().map_or(0, |g| g.1.mean.len());
    wins.par_iter()
        .enumerate()
        .map(|(i, w)| {
            let mut rng = crate::rng::SplitMix64::<0xB007_57A9_0000_0001>::new(i as u64 + 1);
            let noisy: Vec<Vec<f64>> = w
                .iter()
                .map(|row| row.iter().map(|x| x + b.noise * rng.normal()).collect())
                .collect();
            let rows: Vec<&[f64]> = noisy.iter().map(|v| v.as_slice()).collect();
            fit_clearance(&curves_of(&rows, n), b.grid, b.noise)
        })
        .collect()
}
