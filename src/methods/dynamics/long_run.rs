//! The long run: prediction horizon and ensemble statistics against
//! tolerance.

use crate::methods::Effort;
use crate::model::params::Params;
use crate::progress::Progress;
use crate::sim::ensemble::{prediction_horizon, run_ensemble};
use crate::sim::{SimOptions, simulate};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Prediction horizon and ensemble statistics against tolerance.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LongRunRow {
    pub rtol: f64,
    /// Revolutions until two realisations 1 nm apart at this tolerance
    /// differ by c/10 (the spec's prediction horizon).
    pub horizon_revs: Option<f64>,
    /// Revolutions until this tolerance's trajectory departs by c/10 from
    /// the tightest tolerance's (same start): how far the integration error
    /// alone lets a trajectory be trusted.
    pub tolerance_horizon_revs: Option<f64>,
    /// (figure, ensemble mean, ensemble std) for the robust figures.
    pub figures: Vec<(String, f64, f64)>,
    pub wall_ms: f64,
    pub rhs_evals: u64,
    /// Whether every figure's mean agrees with the tightest tolerance's
    /// within two standard errors of the difference.
    pub as_good_as_tightest: bool,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LongRun {
    pub scene: String,
    pub realisations: usize,
    pub revs: f64,
    pub rows: Vec<LongRunRow>,
    /// The cheapest tolerance whose statistics are as good as the tightest's.
    pub recommended_rtol: Option<f64>,
}

pub(super) const LONG_RUN_FIGURES: [&str; 4] = [
    "disp_dev_mean_mm",
    "vel_dev_mean_mps",
    "torque_dev_rms_nm",
    "impacts_per_rev",
];

pub fn long_run(effort: Effort, progress: &Progress) -> LongRun {
    let (rtols, n, revs) = match effort {
        Effort::Quick => (vec![1e-5, 1e-7, 1e-9], 4, 4.0),
        Effort::Full => (
            vec![1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
            8,
            30.0,
        ),
    };
    let p = Params::paper();
    let span = 8.0;
    let trajectory = |rtol: f64| {
        let o = SimOptions {
            rtol,
            warmup: 0.0,
            revs: span,
            grid_deg: Some(0.5),
            ..SimOptions::default()
        };
        simulate(&p, &o, &Progress::hidden())
            .ok()
            .and_then(|r| r.curves)
    };
    let tightest = rtols.iter().copied().fold(f64::INFINITY, f64::min);
    let reference = trajectory(tightest * 1e-2);
    let threshold_mm = 0.1 * p.clearance * 1e3;
    let mut rows = Vec::new();
    for &rtol in &rtols {
        if progress.is_cancelled() {
            break;
        }
        progress.set_message(format!("long run: rtol {rtol:.0e}"));
        let tolerance_horizon = match (&reference, trajectory(rtol)) {
            (Some(a), Some(b)) => (0..a.len().min(b.len()))
                .find(|&i| {
                    (a.ecc_x_mm[i] - b.ecc_x_mm[i]).hypot(a.ecc_y_mm[i] - b.ecc_y_mm[i])
                        > threshold_mm
                })
                .map(|i| a.t_s[i] / p.period()),
            _ => None,
        };
        let o = SimOptions {
            rtol,
            warmup: 2.0,
            revs,
            ..SimOptions::default()
        };
        let start = Instant::now();
        let e = run_ensemble(&p, &o, n, 1e-9, false, &Progress::hidden());
        let h = prediction_horizon(
            &p,
            &SimOptions {
                warmup: 0.0,
                revs: span,
                ..o.clone()
            },
            1e-9,
        );
        let (figures, evals) = match &e {
            Ok(e) => (
                LONG_RUN_FIGURES
                    .iter()
                    .filter_map(|f| e.stats(f).map(|s| ((*f).to_string(), s.mean, s.std)))
                    .collect(),
                e.rhs_evals,
            ),
            Err(_) => (Vec::new(), 0),
        };
        rows.push(LongRunRow {
            rtol,
            horizon_revs: h.ok().and_then(|h| h.revs),
            tolerance_horizon_revs: tolerance_horizon,
            figures,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
            rhs_evals: evals,
            as_good_as_tightest: false,
        });
        progress.inc(1);
    }
    // Compare each tolerance's means with the tightest's.
    if let Some(tight) = rows.last().cloned() {
        for r in rows.iter_mut() {
            r.as_good_as_tightest = !r.figures.is_empty()
                && r.figures
                    .iter()
                    .zip(&tight.figures)
                    .all(|((_, m, s), (_, mt, st))| {
                        let se = (s * s / n as f64 + st * st / n as f64).sqrt();
                        (m - mt).abs() <= 2.0 * se.max(1e-12 * mt.abs())
                    });
        }
    }
    let recommended = rows.iter().find(|r| r.as_good_as_tightest).map(|r| r.rtol);
    LongRun {
        scene: "paper c=0.1 mm 1200 rpm alloy_steel".into(),
        realisations: n,
        revs,
        rows,
        recommended_rtol: recommended,
    }
}
