//! Stability of the fixed-step explicit methods against contact stiffness
//! and speed, beside the linear-stability prediction.

use crate::methods::Effort;
use crate::methods::stability::imaginary_axis_limit;
use crate::model::params::Params;
use crate::progress::Progress;
use crate::sim::{SimOptions, SimResult, simulate};
use crate::solver::Method;
use serde::{Deserialize, Serialize};

/// How a fixed-step run turned out against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Impacts exact, peak force within 1 %, stroke within 1 µm.
    Accurate,
    /// Finite and bounded but not accurate.
    Inaccurate,
    /// Impacts lost (steps jump over contacts).
    MissedImpacts,
    /// The journal went deeper than the clearance (the contact spring no
    /// longer holds it: energy growth).
    PenetrationBeyondClearance,
    /// Non-finite state (blow-up) or a reported failure.
    BlowUp,
}

/// One scene variant of the stability study.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StabilityRow {
    pub variant: String,
    pub method: String,
    /// Contact frequency at the reference's peak penetration, rad/s.
    pub omega_contact: f64,
    /// Linear-stability prediction: (imaginary-axis limit) / ω, s.
    pub predicted_stable_step_s: f64,
    /// Largest step tried that stayed stable (not blow-up, not beyond the clearance), s.
    pub measured_stable_step_s: Option<f64>,
    /// Largest step tried that stayed accurate, s.
    pub measured_accurate_step_s: Option<f64>,
    /// What happens just beyond the stable step.
    pub failure_beyond: Option<Outcome>,
    /// Every step tried with its outcome.
    pub trials: Vec<(f64, Outcome)>,
}

/// Stability of the fixed-step explicit methods as stiffness and speed vary.
pub fn stability_study(effort: Effort, progress: &Progress) -> Vec<StabilityRow> {
    let mut variants: Vec<(String, Params)> = Vec::new();
    let base = Params::paper();
    let push = |v: &mut Vec<(String, Params)>, name: String, f: &dyn Fn(&mut Params)| {
        let mut p = base.clone();
        f(&mut p);
        v.push((name, p));
    };
    match effort {
        Effort::Quick => {
            push(&mut variants, "alloy_steel 1200 rpm".into(), &|_| {});
            push(&mut variants, "aluminium 1200 rpm".into(), &|p| {
                let _ = p.set_str("material", "aluminium");
            });
        }
        Effort::Full => {
            for m in [
                "aluminium",
                "copper",
                "stainless_steel",
                "alloy_steel",
                "tungsten_carbide",
            ] {
                push(&mut variants, format!("{m} 1200 rpm"), &|p| {
                    let _ = p.set_str("material", m);
                });
            }
            for rj in [1.5, 6.0] {
                push(&mut variants, format!("alloy_steel R_J {rj} mm"), &|p| {
                    p.rj = rj * 1e-3
                });
            }
            for c in [0.03, 0.8] {
                push(&mut variants, format!("alloy_steel c {c} mm"), &|p| {
                    p.clearance = c * 1e-3
                });
            }
            for rpm in [1000.0, 2000.0] {
                push(&mut variants, format!("alloy_steel {rpm} rpm"), &|p| {
                    p.motor_rpm = rpm
                });
            }
        }
    }
    let factors: Vec<f64> = match effort {
        Effort::Quick => vec![0.25, 0.5, 1.0, 2.0, 4.0],
        Effort::Full => vec![0.125, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 8.0],
    };
    let mut rows = Vec::new();
    for (name, p) in &variants {
        if progress.is_cancelled() {
            break;
        }
        progress.set_message(format!("stability: {name}"));
        // A short window with several impacts: 0.1 revolution from the start.
        let win = |method: Method, step: Option<f64>| SimOptions {
            method,
            step,
            rtol: 1e-12,
            atol: 1e-16,
            warmup: 0.0,
            revs: 0.1,
            grid_deg: Some(0.5),
            record_events: true,
            max_steps: 2_000_000,
            ..SimOptions::default()
        };
        let Ok(reference) = simulate(p, &win(Method::Dop853, None), &Progress::hidden()) else {
            continue;
        };
        let law = crate::model::contact::ContactLaw::of(p);
        let delta_max = reference.summary.peak_penetration_um.max(1e-3) * 1e-6;
        let omega_c = law.frequency(delta_max, p.m4);
        for method in [Method::Rk4, Method::Dopri5, Method::Dop853] {
            let Some(limit) = imaginary_axis_limit(method) else {
                continue;
            };
            let predicted = limit / omega_c;
            let mut trials = Vec::new();
            for &f in &factors {
                let h = predicted * f;
                let outcome = match simulate(p, &win(method, Some(h)), &Progress::hidden()) {
                    Err(_) => Outcome::BlowUp,
                    Ok(r) => classify(&r, &reference, p.clearance),
                };
                trials.push((h, outcome));
            }
            let stable =
                |o: Outcome| !matches!(o, Outcome::BlowUp | Outcome::PenetrationBeyondClearance);
            // Largest step such that it and every smaller step tried are stable / accurate.
            let mut measured_stable = None;
            let mut failure_beyond = None;
            for &(h, o) in &trials {
                if stable(o) {
                    measured_stable = Some(h);
                } else {
                    failure_beyond = Some(o);
                    break;
                }
            }
            let measured_accurate = trials
                .iter()
                .take_while(|(_, o)| *o == Outcome::Accurate)
                .last()
                .map(|(h, _)| *h);
            rows.push(StabilityRow {
                variant: name.clone(),
                method: method.name().into(),
                omega_contact: omega_c,
                predicted_stable_step_s: predicted,
                measured_stable_step_s: measured_stable,
                measured_accurate_step_s: measured_accurate,
                failure_beyond,
                trials,
            });
        }
        progress.inc(1);
    }
    rows
}

pub(super) fn classify(r: &SimResult, reference: &SimResult, clearance: f64) -> Outcome {
    let s = &r.summary;
    let rs = &reference.summary;
    if !s.peak_accel_mps2.is_finite() {
        return Outcome::BlowUp;
    }
    if s.peak_penetration_um * 1e-6 > clearance {
        return Outcome::PenetrationBeyondClearance;
    }
    if s.n_impacts < rs.n_impacts {
        return Outcome::MissedImpacts;
    }
    let stroke_err =
        super::work_precision::max_stroke_diff_mm(r, reference).unwrap_or(f64::INFINITY);
    let force_err = (s.peak_contact_force_n - rs.peak_contact_force_n).abs()
        / rs.peak_contact_force_n.max(1e-300);
    if s.n_impacts == rs.n_impacts && force_err < 0.01 && stroke_err < 1e-3 {
        Outcome::Accurate
    } else {
        Outcome::Inaccurate
    }
}
