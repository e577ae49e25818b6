//! Statistics over realisations, and the prediction horizon.
//!
//! The clearance motion is chaotic (model.md): trajectories started 1 nm
//! apart separate to the size of the clearance within a revolution or two.
//! So past the deterministic window the product reports distributions:
//! N realisations, realisation k starting with the pin bar offset by k·dx
//! (dx = 1 nm by default, as in flores-benchmark.md), and for every summary
//! figure the mean, the sample standard deviation (n − 1), min and max.

use super::{SimError, SimOptions, SimResult, Summary, simulate};
use crate::model::params::Params;
use crate::progress::Progress;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Distribution of one figure over the realisations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FigureStats {
    pub mean: f64,
    /// Sample standard deviation (n − 1; 0 for one realisation).
    pub std: f64,
    pub min: f64,
    pub max: f64,
}

impl FigureStats {
    pub fn of(values: &[f64]) -> Self {
        let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
            };
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = if v.len() > 1 {
            v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        Self {
            mean,
            std: var.sqrt(),
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// The figures reported per realisation, by name (the `--json` keys).
pub const FIGURES: [&str; 12] = [
    "impacts_per_rev",
    "peak_accel_mps2",
    "peak_contact_force_n",
    "disp_dev_mean_mm",
    "disp_dev_max_mm",
    "vel_dev_mean_mps",
    "vel_dev_max_mps",
    "peak_torque_nm",
    "torque_dev_rms_nm",
    "stroke_min_mm",
    "stroke_max_mm",
    "peak_process_force_n",
];

/// A figure of a summary by name.
pub fn figure(s: &Summary, name: &str) -> f64 {
    match name {
        "impacts_per_rev" => s.n_impacts as f64 / s.revs,
        "peak_accel_mps2" => s.peak_accel_mps2,
        "peak_contact_force_n" => s.peak_contact_force_n,
        "disp_dev_mean_mm" => s.disp_dev_mean_mm,
        "disp_dev_max_mm" => s.disp_dev_max_mm,
        "vel_dev_mean_mps" => s.vel_dev_mean_mps,
        "vel_dev_max_mps" => s.vel_dev_max_mps,
        "peak_torque_nm" => s.peak_torque_nm.unwrap_or(f64::NAN),
        "torque_dev_rms_nm" => s.torque_dev_rms_nm.unwrap_or(f64::NAN),
        "stroke_min_mm" => s.stroke_min_mm,
        "stroke_max_mm" => s.stroke_max_mm,
        "peak_process_force_n" => s.peak_process_force_n.unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// One named figure's statistics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NamedStats {
    pub figure: String,
    #[serde(flatten)]
    pub stats: FigureStats,
}

/// How far ahead a single trajectory means something.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Horizon {
    /// Revolutions from the start until two realisations `perturbation_m`
    /// apart differ by `threshold_mm` in the journal's eccentricity; None if
    /// they never did within `span_revs`.
    pub revs: Option<f64>,
    pub threshold_mm: f64,
    pub perturbation_m: f64,
    pub span_revs: f64,
    pub rtol: f64,
}

/// An ensemble's result.
#[derive(Debug, Clone, Serialize)]
pub struct EnsembleResult {
    pub realisations: usize,
    pub perturbation_m: f64,
    pub figures: Vec<NamedStats>,
    pub runs: Vec<Summary>,
    pub horizon: Option<Horizon>,
    /// Total work over the realisations.
    pub rhs_evals: u64,
    pub steps: u64,
    pub wall_ms: f64,
}

impl EnsembleResult {
    pub fn stats(&self, name: &str) -> Option<&FigureStats> {
        self.figures
            .iter()
            .find(|f| f.figure == name)
            .map(|f| &f.stats)
    }
}

/// Runs `n` realisations in parallel (rayon), realisation k with the pin bar
/// offset by k·dx (m); with `horizon`, also estimates the prediction horizon
/// from realisations 0 and 1.
pub fn run_ensemble(
    p: &Params,
    opts: &SimOptions,
    n: usize,
    dx: f64,
    horizon: bool,
    progress: &Arc<Progress>,
) -> Result<EnsembleResult, SimError> {
    if n == 0 {
        return Err(SimError::Options("ensemble size must be at least 1".into()));
    }
    let start = std::time::Instant::now();
    progress.set_total(n as u64 + u64::from(horizon));
    progress.set_done(0);
    let results: Vec<Result<SimResult, SimError>> = (0..n)
        .into_par_iter()
        .map(|k| {
            if progress.is_cancelled() {
                return Err(SimError::Cancelled);
            }
            let o = SimOptions {
                perturb_x4: opts.perturb_x4 + k as f64 * dx,
                grid_deg: None,
                record_events: false,
                ..opts.clone()
            };
            let r = simulate(p, &o, &Progress::hidden());
            progress.inc(1);
            r
        })
        .collect();
    let mut runs = Vec::with_capacity(n);
    for r in results {
        runs.push(r?.summary);
    }
    let figures = FIGURES
        .iter()
        .map(|name| {
            let v: Vec<f64> = runs.iter().map(|s| figure(s, name)).collect();
            NamedStats {
                figure: (*name).to_string(),
                stats: FigureStats::of(&v),
            }
        })
        .collect();
    let horizon = if horizon {
        let h = prediction_horizon(p, opts, dx.max(1e-12))?;
        progress.inc(1);
        Some(h)
    } else {
        None
    };
    Ok(EnsembleResult {
        realisations: n,
        perturbation_m: dx,
        figures,
        rhs_evals: runs.iter().map(|s| s.rhs_evals).sum(),
        steps: runs.iter().map(|s| s.steps).sum(),
        runs,
        horizon,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

/// Revolutions until two realisations `dx` apart (at the tolerance of
/// `opts`) differ by a tenth of the clearance in the journal's
/// eccentricity, sampled every 0.5° from the start over warm-up + reported
/// revolutions.
pub fn prediction_horizon(p: &Params, opts: &SimOptions, dx: f64) -> Result<Horizon, SimError> {
    let span = opts.warmup + opts.revs;
    let threshold_mm = 0.1 * p.clearance * 1e3;
    let run = |k: f64| {
        let o = SimOptions {
            warmup: 0.0,
            revs: span,
            grid_deg: Some(0.5),
            perturb_x4: opts.perturb_x4 + k * dx,
            record_events: false,
            ..opts.clone()
        };
        simulate(p, &o, &Progress::hidden())
    };
    let (a, b) = rayon::join(|| run(0.0), || run(1.0));
    let (a, b) = (a?, b?);
    let revs = match (a.curves, b.curves) {
        (Some(ca), Some(cb)) => {
            let n = ca.len().min(cb.len());
            (0..n)
                .find(|&i| {
                    let dx = ca.ecc_x_mm[i] - cb.ecc_x_mm[i];
                    let dy = ca.ecc_y_mm[i] - cb.ecc_y_mm[i];
                    dx.hypot(dy) > threshold_mm
                })
                .map(|i| ca.t_s[i] / p.period())
        }
        _ => None,
    };
    Ok(Horizon {
        revs,
        threshold_mm,
        perturbation_m: dx,
        span_revs: span,
        rtol: opts.rtol,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_values() {
        let s = FigureStats::of(&[1.0, 2.0, 3.0, f64::NAN]);
        assert_eq!(s.mean, 2.0);
        assert!((s.std - 1.0).abs() < 1e-15);
        assert_eq!((s.min, s.max), (1.0, 3.0));
        assert!(FigureStats::of(&[]).mean.is_nan());
        assert_eq!(FigureStats::of(&[5.0]).std, 0.0);
    }

    /// Realisations 1 nm apart separate within a few revolutions, and the
    /// horizon is found inside the span.
    #[test]
    fn horizon_is_finite_for_the_flores_scene() {
        let p = Params::flores();
        let opts = SimOptions {
            warmup: 0.0,
            revs: 6.0,
            rtol: 1e-9,
            ..SimOptions::default()
        };
        let h = prediction_horizon(&p, &opts, 1e-9).unwrap();
        let revs = h.revs.expect("the realisations must separate");
        assert!(revs > 0.3 && revs < 6.0, "horizon {revs} revolutions");
    }
}
