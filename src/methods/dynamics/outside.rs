//! An outside reference: the `ode_solvers` crate's DOP853 and DOPRI5 on
//! the same right-hand side (smooth scene; Hertz contact without events).

use super::*;
use crate::methods::Effort;
use crate::model::clearance::{ClearanceModel, DIM, Mode, OMEGA3};
use crate::model::params::{ContactModel, Params};
use crate::progress::Progress;
use crate::sim::simulate;
use crate::solver::{Method, Stepper, StepperConfig, Tolerance};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One run of the outside-reference comparison.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OutsidePoint {
    /// "smooth free flight" or "hertz contact, no events".
    pub scene: String,
    /// e.g. "pinsight dop853", "ode_solvers dop853".
    pub solver: String,
    pub rtol: f64,
    pub rhs_evals: u64,
    pub wall_ms: f64,
    /// Error measure of the scene (see `error_kind`).
    pub error: f64,
    pub error_kind: String,
    /// Contact onsets seen (contact scene; ode_solvers: upward zero
    /// crossings of δ on its 0.05° dense output).
    pub impacts: Option<u64>,
    pub failed: Option<String>,
}

/// The clearance model for `ode_solvers`: contact whenever δ > 0 (a
/// stateless right-hand side; with the Hertz law the onset velocity is not
/// needed), no event location. Time is carried as an extra state component
/// (autonomous form): `ode_solvers` 0.6.2's DOP853 evaluates its 12th stage
/// at t instead of t + h (c12 = 0 in its tableau) and fails on
/// non-autonomous systems — it reports "stiffness detected" on y' = cos t.
/// Its dense outputs (DOP853 and DOPRI5) are also off by far more than the
/// tolerance, so only per-step (sparse) output is used.
pub(super) struct OdeSolversRhs {
    model: ClearanceModel,
    /// Use the solver's time argument instead of the time state (to show the failure).
    use_time_argument: bool,
}

pub(super) const OS_DIM: usize = DIM + 1;
pub(super) type OsState = ode_solvers::SVector<f64, OS_DIM>;

impl ode_solvers::System<f64, OsState> for OdeSolversRhs {
    fn system(&self, t: f64, y: &OsState, dy: &mut OsState) {
        let ya: [f64; DIM] = std::array::from_fn(|i| y[i]);
        let tt = if self.use_time_argument { t } else { y[DIM] };
        let (d, _) = self.model.penetration(tt, &ya);
        let mode = Mode {
            in_contact: d > 0.0,
            approach: 1.0,
            ..Mode::default()
        };
        let mut out = [0.0; DIM];
        self.model.evaluate_in(mode, tt, &ya, &mut out);
        for i in 0..DIM {
            dy[i] = out[i];
        }
        dy[DIM] = 1.0;
    }
}

/// Runs an `ode_solvers` method over [0, t_end] with per-step output.
/// Returns (step times, states, evaluations, wall ms) or the error.
pub(super) fn run_ode_solvers(
    model: &ClearanceModel,
    dop853: bool,
    use_time_argument: bool,
    t_end: f64,
    rtol: f64,
    atol: f64,
) -> Result<(Vec<f64>, Vec<OsState>, u64, f64), String> {
    let y0 = model.initial_state(0.0);
    let ys = OsState::from_fn(|i, _| if i < DIM { y0[i] } else { 0.0 });
    let sys = OdeSolversRhs {
        model: model.clone(),
        use_time_argument,
    };
    let start = Instant::now();
    // The crate's two methods are different types with the same calls.
    macro_rules! run {
        ($method:ty) => {{
            let mut s = <$method>::new(sys, 0.0, t_end, t_end, ys, rtol, atol);
            s.set_output(ode_solvers::OutputType::Sparse);
            let st = s.integrate().map_err(|e| format!("{e:?}"))?;
            Ok((
                s.x_out().clone(),
                s.y_out().clone(),
                u64::from(st.num_eval),
                start.elapsed().as_secs_f64() * 1e3,
            ))
        }};
    }
    if dop853 {
        run!(ode_solvers::Dop853<_, _, _>)
    } else {
        run!(ode_solvers::Dopri5<_, _, _>)
    }
}

/// The smooth scene of the convergence test (free flight, 6 ms).
pub(super) fn smooth_scene() -> Params {
    let mut p = Params::flores();
    p.motor_rpm = 500.0;
    p.clearance = 5e-3;
    p.gravity = [9.81, -3.0];
    p
}

/// Our DOP853/DOPRI5 against `ode_solvers`' on the same right-hand side.
pub fn outside_reference(effort: Effort) -> Vec<OutsidePoint> {
    let rtols: Vec<f64> = match effort {
        Effort::Quick => vec![1e-6, 1e-9],
        Effort::Full => vec![1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
    };
    let mut out = Vec::new();
    // (a) Smooth free flight: error of ω3 at the end against DOP853 at 1e-14.
    let p = smooth_scene();
    let m = ClearanceModel::new(&p);
    let y0 = m.initial_state(0.0);
    let t_end = 6e-3;
    let ours = |method: Method, rtol: f64| {
        let cfg = StepperConfig {
            tol: Tolerance::<DIM>::uniform(rtol, rtol * 1e-3),
            h: 0.0,
            h_max: f64::INFINITY,
            max_steps: 10_000_000,
            fixed: false,
        };
        let mut st = Stepper::new(method, cfg);
        let start = Instant::now();
        st.reset(&m, 0.0, y0, true);
        while st.t() < t_end {
            if st.step(&m, t_end, f64::INFINITY).is_err() {
                break;
            }
        }
        (
            *st.y(),
            st.stats().rhs_evals,
            start.elapsed().as_secs_f64() * 1e3,
        )
    };
    let (yref, _, _) = ours(Method::Dop853, 1e-14);
    let kind = "|ω3 − ω3_ref| at 6 ms (rad/s)";
    for &rtol in &rtols {
        for method in [Method::Dop853, Method::Dopri5] {
            let (y, n, ms) = ours(method, rtol);
            out.push(OutsidePoint {
                scene: "smooth free flight".into(),
                solver: format!("pinsight {}", method.name()),
                rtol,
                rhs_evals: n,
                wall_ms: ms,
                error: (y[OMEGA3] - yref[OMEGA3]).abs(),
                error_kind: kind.into(),
                impacts: None,
                failed: None,
            });
        }
        // The crate's DOP853 and DOPRI5, and its DOP853 with time as its
        // argument (non-autonomous): that one fails.
        for (dop853, time_arg, name) in [
            (true, false, "ode_solvers dop853"),
            (false, false, "ode_solvers dopri5"),
            (true, true, "ode_solvers dop853 (time as argument)"),
        ] {
            let scene = "smooth free flight";
            out.push(
                match run_ode_solvers(&m, dop853, time_arg, t_end, rtol, rtol * 1e-3) {
                    Ok((_, ys, n, ms)) => OutsidePoint {
                        scene: scene.into(),
                        solver: name.into(),
                        rtol,
                        rhs_evals: n,
                        wall_ms: ms,
                        error: ys
                            .last()
                            .map_or(f64::NAN, |y| (y[OMEGA3] - yref[OMEGA3]).abs()),
                        error_kind: kind.into(),
                        impacts: None,
                        failed: None,
                    },
                    Err(e) => outside_failed(scene, name, rtol, e),
                },
            );
        }
    }
    // (b) Hertz contact (paper preset, no hysteresis, so the right-hand side
    // needs no event state): our event-located run against ode_solvers
    // without events. Error: |s − s_ref| at the window's end, mm; impacts
    // counted from the sign of δ at ode_solvers' step ends (contacts shorter
    // than a step are not seen — which is the point).
    let mut p = Params::paper();
    p.contact_model = ContactModel::Hertz;
    let Ok(reference) = simulate(
        &p,
        &window_opts(Method::Dop853, 1e-13, None),
        &Progress::hidden(),
    ) else {
        return out;
    };
    let Some(s_ref_end) = reference
        .curves
        .as_ref()
        .and_then(|c| c.stroke_mm.last().copied())
    else {
        return out;
    };
    let m = ClearanceModel::new(&p);
    let t_end = 0.5 * p.period();
    let kind = "|s − s_ref| at the window's end (mm)";
    for &rtol in &rtols {
        match simulate(
            &p,
            &window_opts(Method::Dop853, rtol, None),
            &Progress::hidden(),
        ) {
            Ok(r) => {
                let s_end = r
                    .curves
                    .as_ref()
                    .and_then(|c| c.stroke_mm.last().copied())
                    .unwrap_or(f64::NAN);
                out.push(OutsidePoint {
                    scene: "hertz contact".into(),
                    solver: "pinsight dop853 (events)".into(),
                    rtol,
                    rhs_evals: r.summary.rhs_evals + r.summary.aux_evals,
                    wall_ms: r.summary.wall_ms,
                    error: (s_end - s_ref_end).abs(),
                    error_kind: kind.into(),
                    impacts: Some(r.summary.n_impacts),
                    failed: None,
                });
            }
            Err(e) => out.push(outside_failed(
                "hertz contact",
                "pinsight dop853 (events)",
                rtol,
                e.to_string(),
            )),
        }
        out.push(match run_ode_solvers(&m, true, false, t_end, rtol, 1e-16) {
            Ok((ts, ys, n, ms)) => {
                let mut impacts = 0u64;
                let mut prev_d = -1.0;
                for (t, y) in ts.iter().zip(&ys) {
                    let ya: [f64; DIM] = std::array::from_fn(|i| y[i]);
                    let (d, _) = m.penetration(*t, &ya);
                    if prev_d <= 0.0 && d > 0.0 {
                        impacts += 1;
                    }
                    prev_d = d;
                }
                let s_end = ys.last().map_or(f64::NAN, |y| (y[2] - m.x4_tdc) * 1e3);
                OutsidePoint {
                    scene: "hertz contact".into(),
                    solver: "ode_solvers dop853 (no events)".into(),
                    rtol,
                    rhs_evals: n,
                    wall_ms: ms,
                    error: (s_end - s_ref_end).abs(),
                    error_kind: kind.into(),
                    impacts: Some(impacts),
                    failed: None,
                }
            }
            Err(e) => outside_failed("hertz contact", "ode_solvers dop853 (no events)", rtol, e),
        });
    }
    out
}

pub(super) fn outside_failed(scene: &str, solver: &str, rtol: f64, msg: String) -> OutsidePoint {
    OutsidePoint {
        scene: scene.into(),
        solver: solver.into(),
        rtol,
        rhs_evals: 0,
        wall_ms: f64::NAN,
        error: f64::NAN,
        error_kind: String::new(),
        impacts: None,
        failed: Some(msg),
    }
}
