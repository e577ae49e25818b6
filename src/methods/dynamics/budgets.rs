//! Where the steps go (contact vs free flight) and how methods fail
//! (step underflow, too many steps, blow-up): reported, never hung.

use super::*;
use crate::methods::stability::imaginary_axis_limit;
use crate::model::params::Params;
use crate::progress::Progress;
use crate::sim::{SimOptions, simulate};
use crate::solver::Method;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Where an adaptive method spends its steps, and how methods fail.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StepBudget {
    pub scene: String,
    pub method: String,
    pub rtol: f64,
    pub contact_steps: u64,
    pub free_steps: u64,
    pub rejected: u64,
    pub rhs_evals: u64,
    pub aux_evals: u64,
    pub jacobians: u64,
    pub stiff_steps: u64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FailureCase {
    pub what: String,
    pub method: String,
    pub outcome: String,
    pub wall_ms: f64,
}

pub fn budgets_and_failures(scenes: &[Scene]) -> (Vec<StepBudget>, Vec<FailureCase>) {
    let mut budgets = Vec::new();
    for sc in scenes {
        for m in [Method::Dop853, Method::Dopri5, Method::Radau5] {
            if let Ok(r) = simulate(&sc.params, &window_opts(m, 1e-8, None), &Progress::hidden()) {
                let s = &r.summary;
                budgets.push(StepBudget {
                    scene: sc.name.clone(),
                    method: m.name().into(),
                    rtol: 1e-8,
                    contact_steps: s.contact_steps,
                    free_steps: s.free_steps,
                    rejected: s.rejected_steps,
                    rhs_evals: s.rhs_evals,
                    aux_evals: s.aux_evals,
                    jacobians: s.jacobians,
                    stiff_steps: r.stats.stiff_steps,
                });
            }
        }
    }
    let mut failures = Vec::new();
    let mut run = |what: &str, p: &Params, o: SimOptions| {
        let start = Instant::now();
        let outcome = match simulate(p, &o, &Progress::hidden()) {
            Ok(r) => format!(
                "finished: {} impacts, peak F_N {:.1} N{}",
                r.summary.n_impacts,
                r.summary.peak_contact_force_n,
                if r.notes.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", r.notes.join("; "))
                }
            ),
            Err(e) => format!("failed: {e}"),
        };
        failures.push(FailureCase {
            what: what.into(),
            method: o.method.name().into(),
            outcome,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
        });
    };
    let p = Params::paper();
    // RK4 at 4× its linear stability limit for the contact frequency.
    if let (Ok(r), Some(limit)) = (
        simulate(
            &p,
            &SimOptions::deterministic_window(1e-10),
            &Progress::hidden(),
        ),
        imaginary_axis_limit(Method::Rk4),
    ) {
        let law = crate::model::contact::ContactLaw::of(&p);
        let omega = law.frequency(r.summary.peak_penetration_um.max(1e-3) * 1e-6, p.m4);
        let h = 4.0 * limit / omega;
        run(
            &format!(
                "RK4 at 4× its predicted contact stability limit (h = {h:.2e} s; reference: {} impacts, peak F_N {:.1} N)",
                r.summary.n_impacts, r.summary.peak_contact_force_n
            ),
            &p,
            SimOptions {
                method: Method::Rk4,
                step: Some(h),
                ..SimOptions::deterministic_window(1e-8)
            },
        );
    }
    run(
        "DOPRI5 capped at 2000 steps (too many steps)",
        &p,
        SimOptions {
            method: Method::Dopri5,
            max_steps: 2000,
            ..SimOptions::deterministic_window(1e-12)
        },
    );
    let mut stiff = Params::paper();
    let _ = stiff.set_str("material", "tungsten_carbide");
    stiff.clearance = 0.01e-3;
    run(
        "DOPRI5 on a stiff scene (tungsten carbide, c = 10 µm): stiffness detection",
        &stiff,
        SimOptions {
            method: Method::Dopri5,
            ..SimOptions::deterministic_window(1e-6)
        },
    );
    run(
        "Radau5 on the same stiff scene",
        &stiff,
        SimOptions {
            method: Method::Radau5,
            ..SimOptions::deterministic_window(1e-6)
        },
    );
    (budgets, failures)
}
