//! The dynamics part of the methods lab.
//!
//! Everything here is measured on the real clearance model:
//! - **work–precision** in the deterministic window (model.md: figures
//!   converge with the tolerance there), every method over tolerances
//!   (fixed-step methods: step sizes), against a reference — DOP853 at
//!   rtol 1e-13, the best method at the tightest tolerance it reaches;
//! - **an outside reference**: the `ode_solvers` crate's DOP853 and DOPRI5
//!   on the same right-hand side, on a smooth free-flight scene (pure
//!   integrator comparison) and on a Hertz-contact scene run without event
//!   location (what events buy);
//! - **stability** of the fixed-step explicit methods: the largest step
//!   that stays stable and the largest that stays accurate as the contact
//!   stiffness and speed vary, beside the linear-stability prediction
//!   (the method's imaginary-axis limit / the contact frequency);
//! - **the long run**: prediction horizon against tolerance, and how the
//!   ensemble statistics converge with tolerance compared with their spread
//!   (the cheapest tolerance as good as the tightest is what sweeps use);
//! - **where the steps go** (contact vs free flight) and **how methods
//!   fail** (step underflow, too many steps, blow-up), reported, never hung;
//! - **fidelity** across the study grid (`sim::fidelity`).

use super::Effort;
use super::stability::imaginary_axis_limit;
use crate::model::clearance::{ClearanceModel, DIM, Mode, OMEGA3};
use crate::model::params::{ContactModel, Params};
use crate::plot::{BarChart, LineChart, Panel, Series, SeriesStyle};
use crate::progress::Progress;
use crate::sim::ensemble::{FIGURES, prediction_horizon, run_ensemble};
use crate::sim::fidelity::{SceneResolution, assess};
use crate::sim::{Level, SimOptions, SimResult, simulate};
use crate::solver::{Method, Stepper, StepperConfig, Tolerance};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A named parameter set.
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    pub name: String,
    #[serde(skip)]
    pub params: Params,
}

fn paper_scene(c_mm: f64, rpm: f64, material: &str) -> Scene {
    let mut p = Params::paper();
    p.clearance = c_mm * 1e-3;
    p.motor_rpm = rpm;
    let _ = p.set_str("material", material);
    Scene {
        name: format!("paper c={c_mm} mm {rpm} rpm {material}"),
        params: p,
    }
}

/// The scenes of the issue: the paper preset at c = 0.1 and 0.8 mm, 1000
/// and 2000 rpm, alloy steel and tungsten carbide, and the flores preset.
pub fn scenes(effort: Effort) -> Vec<Scene> {
    let flores = Scene {
        name: "flores c=0.5 mm 5000 rpm".into(),
        params: Params::flores(),
    };
    match effort {
        Effort::Quick => vec![paper_scene(0.1, 1000.0, "alloy_steel"), flores],
        Effort::Full => {
            let mut v = Vec::new();
            for c in [0.1, 0.8] {
                for rpm in [1000.0, 2000.0] {
                    for m in ["alloy_steel", "tungsten_carbide"] {
                        v.push(paper_scene(c, rpm, m));
                    }
                }
            }
            v.push(flores);
            v
        }
    }
}

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

fn window_opts(method: Method, rtol: f64, step: Option<f64>) -> SimOptions {
    SimOptions {
        method,
        rtol,
        atol: 1e-16,
        step,
        grid_deg: Some(0.5),
        ..SimOptions::deterministic_window(rtol)
    }
}

fn compare(scene: &str, r: &SimResult, reference: &SimResult, kind: &str, setting: f64) -> WpPoint {
    let s = &r.summary;
    let rs = &reference.summary;
    let stroke_err = match (&r.curves, &reference.curves) {
        (Some(a), Some(b)) => a
            .stroke_mm
            .iter()
            .zip(&b.stroke_mm)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max),
        _ => f64::NAN,
    };
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

fn failed_point(scene: &str, method: Method, kind: &str, setting: f64, msg: String) -> WpPoint {
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
fn settings(effort: Effort) -> (Vec<f64>, Vec<f64>) {
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

/// Reads scenes from TOML: `[[scene]]` tables with `name`, an optional
/// `preset` and an optional `set = ["key=value", …]` list.
pub fn scenes_from_toml(text: &str) -> Result<Vec<Scene>, String> {
    let t: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
    let list = t
        .get("scene")
        .and_then(|v| v.as_array())
        .ok_or("expected [[scene]] tables")?;
    let mut out = Vec::new();
    for (i, v) in list.iter().enumerate() {
        let tab = v.as_table().ok_or(format!("scene {i} is not a table"))?;
        let name = tab
            .get("name")
            .and_then(|x| x.as_str())
            .map(str::to_string)
            .unwrap_or_else(|| format!("scene {i}"));
        let preset = tab
            .get("preset")
            .and_then(|x| x.as_str())
            .unwrap_or("paper");
        let mut p = Params::preset(preset).map_err(|e| format!("scene `{name}`: {e}"))?;
        let sets: Vec<String> = tab
            .get("set")
            .and_then(|x| x.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        p.apply_overrides(&sets)
            .map_err(|e| format!("scene `{name}`: {e}"))?;
        out.push(Scene { name, params: p });
    }
    if out.is_empty() {
        return Err("no scenes".into());
    }
    Ok(out)
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
struct OdeSolversRhs {
    model: ClearanceModel,
    /// Use the solver's time argument instead of the time state (to show the failure).
    use_time_argument: bool,
}

const OS_DIM: usize = DIM + 1;
type OsState = ode_solvers::SVector<f64, OS_DIM>;

impl ode_solvers::System<f64, OsState> for OdeSolversRhs {
    fn system(&self, t: f64, y: &OsState, dy: &mut OsState) {
        let ya: [f64; DIM] = std::array::from_fn(|i| y[i]);
        let tt = if self.use_time_argument { t } else { y[DIM] };
        let (d, _) = self.model.penetration(tt, &ya);
        let mode = Mode {
            in_contact: d > 0.0,
            approach: 1.0,
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
fn run_ode_solvers(
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
    if dop853 {
        let mut s = ode_solvers::Dop853::new(sys, 0.0, t_end, t_end, ys, rtol, atol);
        s.set_output(ode_solvers::OutputType::Sparse);
        let st = s.integrate().map_err(|e| format!("{e:?}"))?;
        Ok((
            s.x_out().clone(),
            s.y_out().clone(),
            u64::from(st.num_eval),
            start.elapsed().as_secs_f64() * 1e3,
        ))
    } else {
        let mut s = ode_solvers::Dopri5::new(sys, 0.0, t_end, t_end, ys, rtol, atol);
        s.set_output(ode_solvers::OutputType::Sparse);
        let st = s.integrate().map_err(|e| format!("{e:?}"))?;
        Ok((
            s.x_out().clone(),
            s.y_out().clone(),
            u64::from(st.num_eval),
            start.elapsed().as_secs_f64() * 1e3,
        ))
    }
}

/// The smooth scene of the convergence test (free flight, 6 ms).
fn smooth_scene() -> Params {
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
        for (dop853, name) in [(true, "ode_solvers dop853"), (false, "ode_solvers dopri5")] {
            out.push(
                match run_ode_solvers(&m, dop853, false, t_end, rtol, rtol * 1e-3) {
                    Ok((_, ys, n, ms)) => OutsidePoint {
                        scene: "smooth free flight".into(),
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
                    Err(e) => outside_failed("smooth free flight", name, rtol, e),
                },
            );
        }
        // The crate's DOP853 with time as its argument (non-autonomous): fails.
        out.push(
            match run_ode_solvers(&m, true, true, t_end, rtol, rtol * 1e-3) {
                Ok((_, ys, n, ms)) => OutsidePoint {
                    scene: "smooth free flight".into(),
                    solver: "ode_solvers dop853 (time as argument)".into(),
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
                Err(e) => outside_failed(
                    "smooth free flight",
                    "ode_solvers dop853 (time as argument)",
                    rtol,
                    e,
                ),
            },
        );
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

fn outside_failed(scene: &str, solver: &str, rtol: f64, msg: String) -> OutsidePoint {
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

fn classify(r: &SimResult, reference: &SimResult, clearance: f64) -> Outcome {
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
    let stroke_err = match (&r.curves, &reference.curves) {
        (Some(a), Some(b)) => a
            .stroke_mm
            .iter()
            .zip(&b.stroke_mm)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max),
        _ => f64::INFINITY,
    };
    let force_err = (s.peak_contact_force_n - rs.peak_contact_force_n).abs()
        / rs.peak_contact_force_n.max(1e-300);
    if s.n_impacts == rs.n_impacts && force_err < 0.01 && stroke_err < 1e-3 {
        Outcome::Accurate
    } else {
        Outcome::Inaccurate
    }
}

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

const LONG_RUN_FIGURES: [&str; 4] = [
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

/// Fidelity chosen across a clearance × speed grid (nominal material).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FidelityCell {
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub chosen: Level,
    pub stroke_diff_mm: Option<f64>,
    pub force_diff_n: Option<f64>,
    pub reason: String,
}

pub fn fidelity_map(effort: Effort) -> Vec<FidelityCell> {
    let (cs, speeds): (Vec<f64>, Vec<f64>) = match effort {
        Effort::Quick => (vec![0.0005, 0.1], vec![1200.0]),
        Effort::Full => (
            vec![0.0001, 0.001, 0.01, 0.1, 0.3, 0.8],
            vec![1000.0, 1500.0, 2000.0],
        ),
    };
    let mut out = Vec::new();
    for &c in &cs {
        for &rpm in &speeds {
            let mut p = Params::paper();
            p.clearance = c * 1e-3;
            p.motor_rpm = rpm;
            if let Ok(r) = assess(&p, SceneResolution::default(), Method::Dop853) {
                out.push(FidelityCell {
                    clearance_mm: c,
                    motor_rpm: rpm,
                    chosen: r.chosen,
                    stroke_diff_mm: r.steps.get(1).and_then(|s| s.stroke_diff_mm),
                    force_diff_n: r.steps.get(1).and_then(|s| s.force_diff_n),
                    reason: r.reason,
                });
            }
        }
    }
    out
}

/// The whole dynamics lab.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicsLab {
    pub effort: Effort,
    pub references: Vec<Reference>,
    pub work_precision: Vec<WpPoint>,
    pub outside_reference: Vec<OutsidePoint>,
    pub stability: Vec<StabilityRow>,
    /// Imaginary-axis stability limits h·ω of the fixed-step formulas.
    pub imaginary_axis_limits: Vec<(String, Option<f64>)>,
    pub long_run: LongRun,
    pub step_budgets: Vec<StepBudget>,
    pub failures: Vec<FailureCase>,
    pub fidelity: Vec<FidelityCell>,
    pub wall_ms: f64,
}

/// Runs the whole lab; `custom` scenes replace the default ones in the
/// work–precision and step-budget studies.
pub fn run_dynamics_lab(
    effort: Effort,
    custom: Option<Vec<Scene>>,
    progress: &Progress,
) -> DynamicsLab {
    let start = Instant::now();
    let scene_list = custom.unwrap_or_else(|| scenes(effort));
    let n_scenes = scene_list.len() as u64;
    progress.set_total(n_scenes + if effort == Effort::Quick { 2 } else { 11 } + 8 + 3);
    progress.set_done(0);
    let (references, work_precision) = work_precision(effort, &scene_list, progress);
    progress.set_message("outside reference (ode_solvers)");
    let outside_reference = outside_reference(effort);
    progress.inc(1);
    let stability = stability_study(effort, progress);
    let long_run = long_run(effort, progress);
    progress.set_message("step budgets and failure modes");
    let (step_budgets, failures) = budgets_and_failures(&scene_list);
    progress.inc(1);
    progress.set_message("fidelity map");
    let fidelity = fidelity_map(effort);
    progress.inc(1);
    DynamicsLab {
        effort,
        references,
        work_precision,
        outside_reference,
        stability,
        imaginary_axis_limits: [Method::Rk4, Method::Dopri5, Method::Dop853, Method::Radau5]
            .iter()
            .map(|m| (m.name().to_string(), imaginary_axis_limit(*m)))
            .collect(),
        long_run,
        step_budgets,
        failures,
        fidelity,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

fn method_color(m: &str) -> usize {
    match m {
        "dop853" => 0,
        "dopri5" => 1,
        "radau5" => 2,
        "rk4" => 3,
        _ => 4,
    }
}

impl DynamicsLab {
    /// Log–log work–precision panels per scene: stroke error against
    /// right-hand-side evaluations (one series per method).
    pub fn work_precision_panels(&self) -> Vec<Panel> {
        let mut scenes: Vec<&str> = self
            .work_precision
            .iter()
            .map(|p| p.scene.as_str())
            .collect();
        scenes.dedup();
        scenes
            .iter()
            .map(|sc| {
                let mut series = Vec::new();
                for m in ["dop853", "dopri5", "radau5", "rk4"] {
                    let pts: Vec<(f64, f64)> = self
                        .work_precision
                        .iter()
                        .filter(|p| p.scene == *sc && p.method == m && p.failed.is_none())
                        .map(|p| {
                            (
                                (p.rhs_evals + p.aux_evals) as f64,
                                p.stroke_err_mm.max(1e-16),
                            )
                        })
                        .collect();
                    if !pts.is_empty() {
                        series.push(
                            Series::line(m, pts)
                                .with_style(SeriesStyle::LinePoints)
                                .with_color(method_color(m)),
                        );
                    }
                }
                Panel::Line(LineChart {
                    title: format!("work–precision: {sc}"),
                    x_label: "evaluations (rhs + aux)".into(),
                    y_label: "max stroke error (mm)".into(),
                    series,
                    log_x: true,
                    log_y: true,
                    ..Default::default()
                })
            })
            .collect()
    }

    /// Stability: measured stable and accurate steps against the prediction.
    pub fn stability_panels(&self) -> Vec<Panel> {
        let mut series = Vec::new();
        for m in ["rk4", "dopri5", "dop853"] {
            let rows: Vec<&StabilityRow> =
                self.stability.iter().filter(|r| r.method == m).collect();
            let pred: Vec<(f64, f64)> = rows
                .iter()
                .map(|r| (r.omega_contact, r.predicted_stable_step_s))
                .collect();
            let meas: Vec<(f64, f64)> = rows
                .iter()
                .filter_map(|r| r.measured_stable_step_s.map(|h| (r.omega_contact, h)))
                .collect();
            let acc: Vec<(f64, f64)> = rows
                .iter()
                .filter_map(|r| r.measured_accurate_step_s.map(|h| (r.omega_contact, h)))
                .collect();
            let c = method_color(m);
            series.push(
                Series::line(format!("{m} predicted"), pred)
                    .with_style(SeriesStyle::Dashed)
                    .with_color(c),
            );
            series.push(
                Series::line(format!("{m} stable"), meas)
                    .with_style(SeriesStyle::Points)
                    .with_color(c),
            );
            series.push(
                Series::line(format!("{m} accurate"), acc)
                    .with_style(SeriesStyle::LinePoints)
                    .with_color(c),
            );
        }
        vec![Panel::Line(LineChart {
            title: "fixed-step limits against contact frequency".into(),
            x_label: "contact frequency ω (rad/s)".into(),
            y_label: "step (s)".into(),
            series,
            log_x: true,
            log_y: true,
            ..Default::default()
        })]
    }

    /// Horizon and statistics against tolerance.
    pub fn long_run_panels(&self) -> Vec<Panel> {
        let rows = &self.long_run.rows;
        let horizon: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| r.horizon_revs.map(|h| (r.rtol, h)))
            .collect();
        let tol_h: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| r.tolerance_horizon_revs.map(|h| (r.rtol, h)))
            .collect();
        let mut panels = vec![Panel::Line(LineChart {
            title: "prediction horizon against tolerance".into(),
            x_label: "rtol".into(),
            y_label: "revolutions until c/10 apart".into(),
            series: vec![
                Series::line("realisations 1 nm apart", horizon)
                    .with_style(SeriesStyle::LinePoints),
                Series::line("vs tightest tolerance", tol_h).with_style(SeriesStyle::LinePoints),
            ],
            log_x: true,
            ..Default::default()
        })];
        let cats: Vec<String> = rows.iter().map(|r| format!("{:.0e}", r.rtol)).collect();
        let mean: Vec<f64> = rows
            .iter()
            .map(|r| {
                r.figures
                    .iter()
                    .find(|f| f.0 == "disp_dev_mean_mm")
                    .map_or(f64::NAN, |f| f.1)
            })
            .collect();
        let std: Vec<f64> = rows
            .iter()
            .map(|r| {
                r.figures
                    .iter()
                    .find(|f| f.0 == "disp_dev_mean_mm")
                    .map_or(f64::NAN, |f| f.2)
            })
            .collect();
        panels.push(Panel::Bar(BarChart {
            title: format!(
                "ensemble mean |Δs| against tolerance ({} realisations, ±1 std)",
                self.long_run.realisations
            ),
            x_label: "rtol".into(),
            y_label: "mean |Δs| (mm)".into(),
            categories: cats,
            series: vec![("mean |Δs|".into(), mean)],
            errors: Some(vec![std]),
        }));
        panels
    }

    /// Where the steps go, per scene and method.
    pub fn budget_panels(&self) -> Vec<Panel> {
        let cats: Vec<String> = self
            .step_budgets
            .iter()
            .map(|b| {
                format!(
                    "{} {}",
                    b.method,
                    b.scene
                        .split_whitespace()
                        .take(2)
                        .collect::<Vec<_>>()
                        .join(" ")
                )
            })
            .collect();
        vec![Panel::Bar(BarChart {
            title: "where the steps go (rtol 1e-8, deterministic window)".into(),
            x_label: "method, scene".into(),
            y_label: "steps".into(),
            categories: cats,
            series: vec![
                (
                    "contact".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.contact_steps as f64)
                        .collect(),
                ),
                (
                    "free flight".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.free_steps as f64)
                        .collect(),
                ),
                (
                    "rejected".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.rejected as f64)
                        .collect(),
                ),
            ],
            errors: None,
        })]
    }

    /// The figure names used for the long-run table.
    pub fn long_run_figures() -> &'static [&'static str] {
        &LONG_RUN_FIGURES
    }
}

/// Figures of the ensemble, for completeness of the JSON.
pub fn all_figures() -> &'static [&'static str] {
    &FIGURES
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_file() {
        let s = scenes_from_toml(
            "[[scene]]\nname = \"a\"\nset = [\"clearance_mm=0.2\"]\n[[scene]]\npreset = \"flores\"\n",
        )
        .unwrap();
        assert_eq!(s.len(), 2);
        assert!((s[0].params.clearance - 0.2e-3).abs() < 1e-15);
        assert_eq!(s[1].params.preset, "flores");
        assert!(
            scenes_from_toml("[[scene]]\nset = [\"m4_kg=-1\"]")
                .unwrap_err()
                .contains("m4_kg")
        );
        assert!(scenes_from_toml("x = 1").is_err());
    }

    /// The quick work–precision: errors shrink as the tolerance tightens, the
    /// impact count is exact at tight tolerance, and every run reports work.
    #[test]
    fn quick_work_precision_is_consistent() {
        let (refs, pts) =
            work_precision(Effort::Quick, &scenes(Effort::Quick), &Progress::hidden());
        assert_eq!(refs.len(), 2);
        for sc in &refs {
            for m in ["dop853", "dopri5"] {
                let mine: Vec<&WpPoint> = pts
                    .iter()
                    .filter(|p| p.scene == sc.scene && p.method == m && p.failed.is_none())
                    .collect();
                assert!(mine.len() >= 4, "{m} on {}", sc.scene);
                let loose = mine.first().unwrap();
                let tight = mine.last().unwrap();
                assert!(
                    tight.stroke_err_mm < loose.stroke_err_mm,
                    "{m} {}: {loose:?} {tight:?}",
                    sc.scene
                );
                assert_eq!(tight.impact_count_error, 0, "{m} {}", sc.scene);
                assert!(tight.rhs_evals > loose.rhs_evals);
            }
        }
    }

    /// Below the predicted stable step RK4 stays stable; far above it fails.
    #[test]
    fn rk4_stability_limit_brackets_the_prediction() {
        let rows = stability_study(Effort::Quick, &Progress::hidden());
        let rk4: Vec<&StabilityRow> = rows.iter().filter(|r| r.method == "rk4").collect();
        assert!(!rk4.is_empty());
        for r in rk4 {
            let stable = r.measured_stable_step_s.expect("some step must be stable");
            assert!(stable >= 0.5 * r.predicted_stable_step_s, "{r:?}");
            let last = r.trials.last().unwrap();
            assert_ne!(
                last.1,
                Outcome::Accurate,
                "4× the limit cannot be accurate: {r:?}"
            );
        }
    }

    /// The outside reference agrees with ours on the smooth scene.
    #[test]
    fn outside_reference_agrees_on_the_smooth_scene() {
        let pts = outside_reference(Effort::Quick);
        for rtol in [1e-6, 1e-9] {
            let ours = pts
                .iter()
                .find(|p| p.solver == "pinsight dop853" && p.rtol == rtol)
                .unwrap();
            let theirs = pts
                .iter()
                .find(|p| {
                    p.solver == "ode_solvers dop853"
                        && p.rtol == rtol
                        && p.scene == "smooth free flight"
                })
                .unwrap();
            assert!(theirs.failed.is_none(), "{theirs:?}");
            // Same formula, same tolerance: errors within two orders of magnitude.
            assert!(
                ours.error <= 100.0 * theirs.error.max(1e-14),
                "{ours:?} vs {theirs:?}"
            );
            assert!(
                theirs.error <= 100.0 * ours.error.max(1e-14),
                "{ours:?} vs {theirs:?}"
            );
        }
        // The crate's DOP853 with time as its argument does not give the
        // right answer (its 12th stage sits at t, not t + h).
        let broken = pts
            .iter()
            .find(|p| p.solver == "ode_solvers dop853 (time as argument)")
            .unwrap();
        assert!(broken.failed.is_some() || broken.error > 1e-3, "{broken:?}");
    }
}
