//! Small fits the cycle analysis is built from: resampling onto the
//! crank-angle grid, line fits, speed statistics, the angle-offset phase fit.

use super::*;
use crate::model::kinematics::Geometry;
use crate::rig::signals::Signal;
use std::f64::consts::TAU;

/// Sample interval (ns) of a signal: the median.
pub(super) fn median_dt(s: &Signal) -> i64 {
    let n = s.len();
    if n < 2 {
        return 1;
    }
    let stride = (n / 20_000).max(1);
    let mut d: Vec<i64> = (1..n)
        .step_by(stride)
        .map(|i| s.t_ns[i] - s.t_ns[i - 1])
        .collect();
    let mid = d.len() / 2;
    *d.select_nth_unstable(mid).1
}

/// Samples of `sig` around a cycle, placed by crank angle φ = θ2 − θ_tdc,
/// sorted by φ, restricted to φ ∈ [−margin, 2π + margin].
pub(super) fn placed(
    sig: &Signal,
    crank: &Crank,
    t0: i64,
    t1: i64,
    theta_tdc: f64,
    margin: f64,
) -> Vec<(f64, i64, f64)> {
    let pad = (t1 - t0) / 4;
    let i0 = sig.t_ns.partition_point(|&t| t < t0.saturating_sub(pad));
    let i1 = sig.t_ns.partition_point(|&t| t <= t1.saturating_add(pad));
    let mut pts = Vec::with_capacity(i1.saturating_sub(i0));
    let mut hint = 0;
    for i in i0..i1 {
        if let Some(th) = crank.at_from(sig.t_ns[i], &mut hint) {
            let phi = th - theta_tdc;
            if (-margin..=TAU + margin).contains(&phi) {
                pts.push((phi, sig.t_ns[i], sig.values[i]));
            }
        }
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

/// Linear interpolation of (φ, value) points onto the grid; NaN across holes wider than `max_dphi`.
pub(super) fn to_grid(pts: &[(f64, f64)], n: usize, max_dphi: f64) -> Vec<f64> {
    let mut out = vec![f64::NAN; n];
    if pts.len() < 2 {
        return out;
    }
    let mut k = 0usize;
    for (j, o) in out.iter_mut().enumerate() {
        let phi = j as f64 * TAU / n as f64;
        while k + 1 < pts.len() && pts[k + 1].0 < phi {
            k += 1;
        }
        if k + 1 >= pts.len() {
            break;
        }
        let (p0, v0) = pts[k];
        let (p1, v1) = pts[k + 1];
        if p0 > phi || p1 < phi || p1 - p0 > max_dphi {
            continue;
        }
        *o = if p1 > p0 {
            v0 + (v1 - v0) * (phi - p0) / (p1 - p0)
        } else {
            v0
        };
    }
    out
}

pub(super) fn mean_std(x: &[f64]) -> (f64, f64) {
    let v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    let s = if v.len() > 1 {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    } else {
        0.0
    };
    (m, s)
}

/// A least-squares line y = a + b·x with what is needed for its uncertainty.
#[derive(Debug, Clone, Copy)]
pub(super) struct LineFit {
    pub(super) a: f64,
    pub(super) b: f64,
    /// Residual variance, number of points, mean of x, Σ(x − x̄)².
    pub(super) s2: f64,
    pub(super) n: f64,
    pub(super) mx: f64,
    pub(super) sxx: f64,
}

impl LineFit {
    pub(super) fn at(&self, x: f64) -> f64 {
        self.a + self.b * x
    }
    /// Standard uncertainty of the fitted line at x.
    pub(super) fn sigma_at(&self, x: f64) -> f64 {
        (self.s2 * (1.0 / self.n + (x - self.mx).powi(2) / self.sxx)).sqrt()
    }
    pub(super) fn sigma_b(&self) -> f64 {
        (self.s2 / self.sxx).sqrt()
    }
}

pub(super) fn line_fit(x: &[f64], y: &[f64]) -> Option<LineFit> {
    let n = x.len();
    if n < 3 {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    let res: f64 = x
        .iter()
        .zip(y)
        .map(|(a2, b2)| (b2 - a - b * a2).powi(2))
        .sum();
    Some(LineFit {
        a,
        b,
        s2: res / (n - 2) as f64,
        n: n as f64,
        mx,
        sxx,
    })
}

/// Motor-speed statistics of one cycle: mean, std, min, max, first-harmonic amplitude (relative).
pub(super) fn speed_stats(samples: &[(f64, f64)]) -> (f64, f64, f64, f64, f64) {
    if samples.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    }
    let v: Vec<f64> = samples.iter().map(|s| s.1).collect();
    let (m, s) = mean_std(&v);
    let mn = v.iter().copied().fold(f64::INFINITY, f64::min);
    let mx = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // speed ≈ a0 + a1 cos φ + b1 sin φ by least squares (normal equations, 3×3).
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for &(phi, y) in samples {
        let r = nalgebra::Vector3::new(1.0, phi.cos(), phi.sin());
        ata += r * r.transpose();
        atb += r * y;
    }
    let h = ata
        .lu()
        .solve(&atb)
        .map(|c| (c[1] * c[1] + c[2] * c[2]).sqrt() / c[0])
        .unwrap_or(f64::NAN);
    (m, s, mn, mx, h)
}

/// Phase φ that best fits displacement d ≈ s_ideal(θ + φ) − z (z free), by
/// grid search over a full turn then golden-section refinement.
pub(super) fn fit_phase(
    geom: &Geometry,
    theta: &[f64],
    d_mm: &[f64],
    around: Option<f64>,
) -> Option<f64> {
    if theta.len() < 20 {
        return None;
    }
    let cost = |phi: f64| -> f64 {
        let r: Vec<f64> = theta
            .iter()
            .zip(d_mm)
            .map(|(th, d)| geom.stroke_at(th + phi) * 1e3 - d)
            .collect();
        let m = r.iter().sum::<f64>() / r.len() as f64;
        r.iter().map(|x| (x - m).powi(2)).sum::<f64>()
    };
    let (lo, hi) = match around {
        Some(c) => (c - 1.5f64.to_radians(), c + 1.5f64.to_radians()),
        None => {
            // Coarse search on a sub-sample, refined on all points below.
            let stride = (theta.len() / 2000).max(1);
            let th2: Vec<f64> = theta.iter().step_by(stride).copied().collect();
            let d2: Vec<f64> = d_mm.iter().step_by(stride).copied().collect();
            let coarse = |phi: f64| -> f64 {
                let r: Vec<f64> = th2
                    .iter()
                    .zip(&d2)
                    .map(|(th, d)| geom.stroke_at(th + phi) * 1e3 - d)
                    .collect();
                let m = r.iter().sum::<f64>() / r.len() as f64;
                r.iter().map(|x| (x - m).powi(2)).sum::<f64>()
            };
            let mut best = (f64::INFINITY, 0.0);
            for k in 0..360 {
                let phi = (k as f64 - 180.0).to_radians();
                let c = coarse(phi);
                if c < best.0 {
                    best = (c, phi);
                }
            }
            (best.1 - 1.5f64.to_radians(), best.1 + 1.5f64.to_radians())
        }
    };
    Some(crate::solver::roots::golden_min(lo, hi, 40, cost))
}
