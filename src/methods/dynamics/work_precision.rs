//! Work–precision in the deterministic window: every method over
//! tolerances (fixed-step methods: step sizes) against a tight reference.

use super::*;
use crate::methods::Effort;
use crate::progress::Progress;
use crate::sim::{SimOptions, SimResult, simulate};
use crate::solver::Method;
use serde::{Deserialize, Serialize};

/// One point of a work–precision diagram.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WpPoint {
    pub scene: String,
    pub method: String,
    /// "rtol" or "step_s".
    pub setting_kind: String,
    pub setting: f64,
    pub wall_ms: f64,
    pub rhs_evals: u64,
    pub aux_evals: u64,
    pub steps: u64,
    pub rejected: u64,
    pub impacts: u64,
    /// Impacts minus the reference's.
    pub impact_count_error: i64,
    /// max |s − s_ref| on the 0.5° grid, mm.
    pub stroke_err_mm: f64,
    /// Largest |onset time − reference| over the onsets both have, s.
    pub event_time_err_s: f64,
    /// |peak F_N − reference| / reference.
    pub peak_force_rel_err: f64,
    /// Set when the run failed (the message says where).
    pub failed: Option<String>,
}

/// The reference run of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Reference {
    pub scene: String,
    pub method: String,
    pub rtol: f64,
    pub impacts: u64,
    pub peak_contact_force_n: f64,
    pub wall_ms: f64,
}

pub(super) fn window_opts(method: Method, rtol: f64, step: Option<f64>) -> SimOptions {
    SimOptions {
        method,
        rtol,
        atol: 1e-16,
        step,
        grid_deg: Some(0.5),
        ..SimOptions::deterministic_window(rtol)
    }
}

/// The largest stroke difference (mm) between two runs' curves on the
/// same output grid; `None` when either run has no curves.
pub(super) fn max_stroke_diff_mm(a: &SimResult, b: &SimResult) -> Option<f64> {
    let (a, b) = (a.curves.as_ref()?, b.curves.as_ref()?);
    Some(
        a.stroke_mm
            .iter()
            .zip(&b.stroke_mm)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max),
    )
}

pub(super) fn compare(
    scene: &str,
    r: &SimResult,
    reference: &SimResult,
    kind: &str,
    setting: f64,
) -> WpPoint {
    let s = &r.summary;
    let rs = &reference.summary;
    let stroke_err = max_stroke_diff_mm(r, reference).unwrap_or(f64::NAN);
    let on = |r: &SimResult| -> Vec<f64> {
        r.events.iter().filter(|e| e.onset).map(|e| e.t_s).collect()
    };
    let (a, b) = (on(r), on(reference));
    let ev_err = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(f64::NAN, |m: f64, v| if m.is_nan() { v } else { m.max(v) });
    WpPoint {
        scene: scene.into(),
        method: s.method.clone(),
        setting_kind: kind.into(),
        setting,
        wall_ms: s.wall_ms,
        rhs_evals: s.rhs_evals,
        aux_evals: s.aux_evals,
        steps: s.steps,
        rejected: s.rejected_steps,
        impacts: s.n_impacts,
        impact_count_error: s.n_impacts as i64 - rs.n_impacts as i64,
        stroke_err_mm: stroke_err,
        event_time_err_s: ev_err,
        peak_force_rel_err: (s.peak_contact_force_n - rs.peak_contact_force_n).abs()
            / rs.peak_contact_force_n,
        failed: None,
    }
}

pub(super) fn failed_point(
    scene: &str,
    method: Method,
    kind: &str,
    setting: f64,
    msg: String,
) -> WpPoint {
    WpPoint {
        scene: scene.into(),
        method: method.name().into(),
        setting_kind: kind.into(),
        setting,
        wall_ms: f64::NAN,
        rhs_evals: 0,
        aux_evals: 0,
        steps: 0,
        rejected: 0,
        impacts: 0,
        impact_count_error: 0,
        stroke_err_mm: f64::NAN,
        event_time_err_s: f64::NAN,
        peak_force_rel_err: f64::NAN,
        failed: Some(msg),
    }
}

/// Tolerances (adaptive) and steps per revolution (RK4) for an effort.
pub(super) fn settings(effort: Effort) -> (Vec<f64>, Vec<f64>) {
    match effort {
        Effort::Quick => (vec![1e-4, 1e-6, 1e-8, 1e-10], vec![5e3, 2e4, 8e4]),
        Effort::Full => (
            vec![
                1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
            ],
            vec![2e3, 5e3, 1e4, 2e4, 5e4, 1e5, 2e5, 5e5],
        ),
    }
}

/// Work–precision of every method on every scene.
pub fn work_precision(
    effort: Effort,
    scenes: &[Scene],
    progress: &Progress,
) -> (Vec<Reference>, Vec<WpPoint>) {
    let (rtols, per_rev) = settings(effort);
    let mut refs = Vec::new();
    let mut points = Vec::new();
    for sc in scenes {
        if progress.is_cancelled() {
            break;
        }
        progress.set_message(format!("work–precision: {}", sc.name));
        let reference = match simulate(
            &sc.params,
            &window_opts(Method::Dop853, 1e-13, None),
            &Progress::hidden(),
        ) {
            Ok(r) => r,
            Err(e) => {
                points.push(failed_point(
                    &sc.name,
                    Method::Dop853,
                    "rtol",
                    1e-13,
                    e.to_string(),
                ));
                continue;
            }
        };
        refs.push(Reference {
            scene: sc.name.clone(),
            method: "dop853".into(),
            rtol: 1e-13,
            impacts: reference.summary.n_impacts,
            peak_contact_force_n: reference.summary.peak_contact_force_n,
            wall_ms: reference.summary.wall_ms,
        });
        for m in [Method::Dop853, Method::Dopri5, Method::Radau5] {
            for &rtol in &rtols {
                let pt =
                    match simulate(&sc.params, &window_opts(m, rtol, None), &Progress::hidden()) {
                        Ok(r) => compare(&sc.name, &r, &reference, "rtol", rtol),
                        Err(e) => failed_point(&sc.name, m, "rtol", rtol, e.to_string()),
                    };
                points.push(pt);
            }
        }
        for &n in &per_rev {
            let h = sc.params.period() / n;
            let pt = match simulate(
                &sc.params,
                &window_opts(Method::Rk4, 1e-8, Some(h)),
                &Progress::hidden(),
            ) {
                Ok(r) => compare(&sc.name, &r, &reference, "step_s", h),
                Err(e) => failed_point(&sc.name, Method::Rk4, "step_s", h, e.to_string()),
            };
            points.push(pt);
        }
        progress.inc(1);
    }
    (refs, points)
}
