//! Fitting the clearance from the stroke: curves over the cycle, their
//! interpolation across the simulated clearance grid, a golden-section search.

use super::types::SCOUT_MARGIN;
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
    // One buffer for every column (this runs for every node of every
    // jackknife replicate and bootstrap log: thousands of columns a call).
    let mut v: Vec<f64> = Vec::with_capacity(rows.len());
    for j in 0..n {
        v.clear();
        v.extend(rows.iter().map(|r| r[j]).filter(|x| x.is_finite()));
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
    // Buffers reused over the n × windows columns (allocating two vectors
    // per column was a tenth of a calibration's CPU).
    let mut sds = Vec::with_capacity(starts.len());
    let mut column = Vec::with_capacity(w);
    for j in 0..n {
        sds.clear();
        for &a in &starts {
            column.clear();
            column.extend(
                rows[a..a + w]
                    .iter()
                    .map(|row| row[j])
                    .filter(|x| x.is_finite()),
            );
            // NaN: fewer than two finite values in the window.
            let sd = sd_of_finite(&column);
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

/// The sampling variances of the measured curves, fixed for a fit: the
/// variance of a spread of k cycles, S²/(2(k − 1)), and of a mean, S²/k,
/// with S the *predicted* total spread √(S_c² + σ_n²) at a reference
/// clearance. Weighting with the measured S instead (Neyman's χ²) gives the
/// points where the sample happened to spread less the larger weight and
/// pulls the fit to smaller clearances: −1.5 to −2 % at k = 12 cycles,
/// seen as the parametric bootstrap's mean error.
#[derive(Clone)]
pub(super) struct Weights {
    pub(super) var_spread: Vec<f64>,
    pub(super) var_mean: Vec<f64>,
}

impl Weights {
    pub(super) fn of(reference: &Curves, noise: f64, k: usize) -> Self {
        let k = k.max(2) as f64;
        let tot2 = |s: f64| s * s + noise * noise;
        Weights {
            var_spread: reference
                .spread
                .iter()
                .map(|s| tot2(*s) / (2.0 * (k - 1.0)))
                .collect(),
            var_mean: reference.spread.iter().map(|s| tot2(*s) / k).collect(),
        }
    }
}

/// The stroke objective at predicted curves `p` for measured curves `m`,
/// the measured curves' variances from `w` when given (else from `m`
/// itself); returns (objective, Δz, ψ, spread RMS residual, mean RMS residual).
pub(super) fn stroke_objective(
    m: &Curves,
    p: &Curves,
    noise: f64,
    w: Option<&Weights>,
) -> (f64, f64, f64, f64, f64) {
    let n = m.mean.len();
    let floor = 1e-8; // (0.1 µm)²
    let var_s = |j: usize| match w {
        Some(w) if w.var_spread[j].is_finite() => w.var_spread[j],
        _ => m.var_spread[j],
    };
    let var_m = |j: usize| match w {
        Some(w) if w.var_mean[j].is_finite() => w.var_mean[j],
        _ => m.var_mean[j],
    };
    // Spread part.
    let mut js = 0.0;
    // The residuals' sums of squares and counts, for their RMS.
    let (mut rs2, mut rs_n) = (0.0, 0usize);
    for j in 0..n {
        let (sm, sp) = (m.spread[j], p.spread[j]);
        if !sm.is_finite() || !sp.is_finite() {
            continue;
        }
        let pred = (sp * sp + noise * noise).sqrt();
        let v = var_s(j) + p.var_spread[j] + floor;
        js += (sm - pred).powi(2) / v;
        rs2 += (sm - pred) * (sm - pred);
        rs_n += 1;
    }
    // Mean part: r = M + Δz − P + ψ·P′, weighted; solve the 2×2 normal equations.
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut pts = Vec::new();
    for j in 0..n {
        let (mm, pm, dp) = (m.mean[j], p.mean[j], p.dmean[j]);
        if !mm.is_finite() || !pm.is_finite() || !dp.is_finite() {
            continue;
        }
        let w = 1.0 / (var_m(j) + p.var_mean[j] + floor);
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
    let (mut rm2, mut rm_n) = (0.0, 0usize);
    for (w, y, dp) in pts {
        let r = y - dz - psi * dp;
        jm += w * r * r;
        rm2 += r * r;
        rm_n += 1;
    }
    let rms = |ss: f64, n: usize| (ss / n.max(1) as f64).sqrt();
    (js + jm, dz, psi, rms(rs2, rs_n), rms(rm2, rm_n))
}

/// The grid with its fine nodes (clearances `fine`, at least 4 in a row)
/// replaced by a dense grid on which the curves are, per crank angle, a
/// weighted least-squares quadratic in c through the fine nodes (the
/// weights their own sampling variances; the dense nodes' variances the
/// quadratic's prediction variance). Each fine node is one chaotic run whose
/// curves carry a few per cent of sampling noise: interpolated node by node,
/// that noise moves the fit, the objective has kinks at the nodes where
/// the minimum likes to stick, and a jackknife over blocks of the runs
/// then sees no variation at all (a non-smooth estimator). Across the fine
/// nodes the noise averages out and c moves the curves smoothly.
pub(super) fn smooth_grid(grid: &[(f64, Curves)], fine: &[f64]) -> Vec<(f64, Curves)> {
    let is_fine = |c: f64| fine.iter().any(|f| (f - c).abs() < 1e-12);
    let idx: Vec<usize> = (0..grid.len()).filter(|&i| is_fine(grid[i].0)).collect();
    if idx.len() < 4 || idx.windows(2).any(|w| w[1] != w[0] + 1) {
        return grid.to_vec();
    }
    let (lo, hi) = (grid[idx[0]].0, grid[idx[idx.len() - 1]].0);
    let n = grid[idx[0]].1.mean.len();
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let xs: Vec<f64> = idx.iter().map(|&i| (grid[i].0 - centre) / half).collect();
    let dense = 41;
    let dc: Vec<f64> = (0..dense)
        .map(|i| lo + (hi - lo) * i as f64 / (dense - 1) as f64)
        .collect();
    let mut out: Vec<Curves> = (0..dense)
        .map(|_| Curves {
            mean: vec![f64::NAN; n],
            spread: vec![f64::NAN; n],
            dmean: vec![f64::NAN; n],
            var_mean: vec![f64::NAN; n],
            var_spread: vec![f64::NAN; n],
        })
        .collect();
    // Weighted quadratic per crank angle: (value, variance) at each dense c.
    let quad = |ys: &[f64], vs: &[f64]| -> Option<Vec<(f64, f64)>> {
        let mut a = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        let mut used = 0;
        for ((x, y), v) in xs.iter().zip(ys).zip(vs) {
            if !(y.is_finite() && v.is_finite()) {
                continue;
            }
            let w = 1.0 / (v + 1e-12);
            let f = [1.0, *x, x * x];
            for r in 0..3 {
                for c in 0..3 {
                    a[r][c] += w * f[r] * f[c];
                }
                b[r] += w * f[r] * y;
            }
            used += 1;
        }
        if used < 4 {
            return None;
        }
        let inv = inverse3(&a)?;
        let coef: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| inv[r][c] * b[c]).sum())
            .collect();
        Some(
            dc.iter()
                .map(|c| {
                    let x = (c - centre) / half;
                    let f = [1.0, x, x * x];
                    let val = coef[0] + coef[1] * x + coef[2] * x * x;
                    let var: f64 = (0..3)
                        .map(|r| (0..3).map(|q| f[r] * inv[r][q] * f[q]).sum::<f64>())
                        .sum();
                    (val, var.max(0.0))
                })
                .collect(),
        )
    };
    for j in 0..n {
        let sp: Vec<f64> = idx.iter().map(|&i| grid[i].1.spread[j]).collect();
        let vsp: Vec<f64> = idx.iter().map(|&i| grid[i].1.var_spread[j]).collect();
        let mn: Vec<f64> = idx.iter().map(|&i| grid[i].1.mean[j]).collect();
        let vmn: Vec<f64> = idx.iter().map(|&i| grid[i].1.var_mean[j]).collect();
        if let Some(q) = quad(&sp, &vsp) {
            for (d, (v, var)) in q.into_iter().enumerate() {
                out[d].spread[j] = v.max(0.0);
                out[d].var_spread[j] = var;
            }
        }
        if let Some(q) = quad(&mn, &vmn) {
            for (d, (v, var)) in q.into_iter().enumerate() {
                out[d].mean[j] = v;
                out[d].var_mean[j] = var;
            }
        }
    }
    for cu in &mut out {
        cu.dmean = (0..n)
            .map(|j| (cu.mean[(j + 1) % n] - cu.mean[(j + n - 1) % n]) / (2.0 * TAU / n as f64))
            .collect();
    }
    let mut g: Vec<(f64, Curves)> = grid[..idx[0]].to_vec();
    g.extend(dc.into_iter().zip(out));
    g.extend_from_slice(&grid[idx[idx.len() - 1] + 1..]);
    g
}

/// Inverse of a symmetric 3×3 matrix (None when singular).
fn inverse3(a: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if !(det.abs() > 1e-300) || !det.is_finite() {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            let (r1, r2) = ((c + 1) % 3, (c + 2) % 3);
            let (c1, c2) = ((r + 1) % 3, (r + 2) % 3);
            inv[r][c] = (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) / det;
        }
    }
    Some(inv)
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
pub(super) fn fit_clearance(
    m: &Curves,
    grid: &[(f64, Curves)],
    noise: f64,
    w: Option<&Weights>,
) -> (f64, f64, f64) {
    let obj = |c: f64| stroke_objective(m, &interp_curves(grid, c), noise, w).0;
    // Each point's objective once (a comparator calling it would evaluate
    // every point twice); the first of equal minima, as before.
    let lowest = |pts: &mut dyn Iterator<Item = (usize, f64)>| {
        pts.map(|(i, x)| (i, x, obj(x)))
            .min_by(|a, b| a.2.total_cmp(&b.2))
    };
    let k = lowest(&mut grid.iter().map(|g| g.0).enumerate()).map_or(0, |b| b.0);
    let lo = grid[k.saturating_sub(1)].0;
    let hi = grid[(k + 1).min(grid.len() - 1)].0;
    let scan = 64;
    let h = (hi - lo) / scan as f64;
    let best = lowest(&mut (0..=scan).map(|i| (i, lo + h * i as f64))).map_or(grid[k].0, |b| b.1);
    let c = golden((best - h).max(lo), (best + h).min(hi), 30, obj);
    let (_, dz, psi, _, _) = stroke_objective(m, &interp_curves(grid, c), noise, w);
    (c, dz, psi)
}

/// Sample standard deviation (n − 1); NaN below 2 values.
pub(super) fn sample_sd(v: &[f64]) -> f64 {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    sd_of_finite(&v)
}

/// [`sample_sd`] of values already known to be finite.
fn sd_of_finite(v: &[f64]) -> f64 {
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
/// (c_node, 0, 0). `fine` holds (index into `grid`, the node's revolutions);
/// `grid` is the raw grid (one node per run), smoothed over the clearances
/// `smooth` after the node is rebuilt ([`smooth_grid`]), as the log's own
/// fit is; `weights` the log fit's.
pub(super) fn bootstrap(
    grid: &[(f64, Curves)],
    fine: &[(usize, &[Vec<f64>])],
    k: usize,
    noise: f64,
    c_ref: f64,
    smooth: &[f64],
    weights: Option<&Weights>,
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
            let g = smooth_grid(&g, smooth);
            let mut rng =
                crate::rng::SplitMix64::<0xB007_57A9_0000_0001>::new((f * 100_003 + w) as u64 + 1);
            let noisy: Vec<Vec<f64>> = revs[w * k..(w + 1) * k]
                .iter()
                .map(|row| row.iter().map(|x| x + noise * rng.normal()).collect())
                .collect();
            let rows: Vec<&[f64]> = noisy.iter().map(|v| v.as_slice()).collect();
            let (c, dz, psi) = fit_clearance(&curves_of(&rows, n), &g, noise, weights);
            ((c - c_node) * c_ref / c_node, dz, psi)
        })
        .collect()
}

/// Student's t two-sided 95 % quantile for ν degrees of freedom
/// ([`crate::wear::fit::t_quantile`]: statrs, Fisher's expansion for large
/// ν, 1.96 for ν = ∞); ν is held at ≥ 1 (12.71) and NaN gives 2.
pub(super) fn t95(nu: f64) -> f64 {
    if nu.is_nan() {
        return 2.0;
    }
    crate::wear::fit::t_quantile(0.975, nu.max(1.0))
}

/// The coarse nodes (sorted, mm) that run at full length after the scout
/// round: those inside the range the fine grid will span around the scout's
/// estimate `c_scout` (`c_scout` × the refine factors' ends, widened by
/// [`SCOUT_MARGIN`] each way), and the node just below and just above it —
/// the neighbours the fine grid's curves are interpolated to and the
/// jackknife may reach. At least three nodes (the nearest by ratio are
/// added); every node when the estimate is not finite.
pub(super) fn scout_near(nodes: &[f64], c_scout: f64, refine_factors: &[f64]) -> Vec<f64> {
    if !c_scout.is_finite() || c_scout <= 0.0 || nodes.len() <= 3 {
        return nodes.to_vec();
    }
    let f_lo = refine_factors.iter().copied().fold(1.0, f64::min);
    let f_hi = refine_factors.iter().copied().fold(1.0, f64::max);
    let (lo, hi) = (c_scout * f_lo / SCOUT_MARGIN, c_scout * f_hi * SCOUT_MARGIN);
    let mut keep: Vec<bool> = nodes.iter().map(|c| *c >= lo && *c <= hi).collect();
    if let Some(i) = nodes.iter().rposition(|c| *c < lo) {
        keep[i] = true;
    }
    if let Some(i) = nodes.iter().position(|c| *c > hi) {
        keep[i] = true;
    }
    while keep.iter().filter(|k| **k).count() < 3 {
        let far = |c: f64| (c / c_scout).ln().abs();
        let Some(i) = (0..nodes.len())
            .filter(|i| !keep[*i])
            .min_by(|a, b| far(nodes[*a]).total_cmp(&far(nodes[*b])))
        else {
            break;
        };
        keep[i] = true;
    }
    nodes
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(c, _)| *c)
        .collect()
}
