//! Level `clearance`: event-located integration of the contact-impact model.
//!
//! The loop (model.md, "Integration"):
//! 1. take one step in the current mode (free flight: the step is limited so
//!    the journal cannot cross the clearance and come back unseen);
//! 2. look for the mode's event on the step — a sign change of δ at the step
//!    ends, or (double crossing) an interior extremum of δ on the dense output
//!    past zero when δ̇ changes sign over the step;
//! 3. locate it with Brent's method on the dense output to |δ| ≤ event_tol·c,
//!    on the NEW side of δ = 0, and restart the integration there in the
//!    new mode (keeping the onset's approach velocity for the hysteresis);
//! 4. in the reported window, sample the curves on the crank-angle grid and
//!    track continuous-time peaks (refined with Brent on the dense output
//!    around every discrete local maximum that may beat the record).
//!
//! Here the loop itself (`run_model`: the step, the located event and the
//! mode switches of contact, stick and stall); its rooms: `runner` (the
//! loop's state and what it does with each finished segment: curves,
//! peaks, time averages, events), `events` (the event search on a step),
//! `abs_integral` (∫|Δs| dt and ∫|Δv| dt between located zeros) and
//! `report` (the summary at the end).

mod abs_integral;
mod events;
mod report;
mod runner;

use super::summary::{NQ, PeakTracker};
use super::{Curves, SimError, SimOptions, SimResult, wrap_deg};
use crate::model::clearance::{ClearanceModel, Mode};
use crate::model::contact::ProcessMode;
use crate::model::joint_model::JointModel;
use crate::model::params::Params;
use crate::progress::Progress;
use crate::solver::roots::bracket_root;
use crate::solver::{Method, Stepper, StepperConfig};
use abs_integral::AbsIntegral;
use report::LoopEnd;
use runner::{Runner, StickCount, start_window};
use std::time::Instant;

/// Default RK4 step: this many steps per crank revolution.
pub const RK4_STEPS_PER_REV: f64 = 20_000.0;

pub fn run(p: &Params, opts: &SimOptions, progress: &Progress) -> Result<SimResult, SimError> {
    let model = ClearanceModel::new(p);
    let how = RunSetup {
        ideal: p,
        period: p.period(),
        omega: p.omega(),
        level: "clearance",
    };
    run_model(p, opts, model, &how, progress).map(|f| f.result)
}

/// What differs between the levels that run through [`run_model`].
pub(crate) struct RunSetup<'a> {
    /// The parameters of the ideal mechanism the figures compare with.
    pub ideal: &'a Params,
    /// The crank period (s) and speed (rad/s) that set the protocol's
    /// window and the curves' grid.
    pub period: f64,
    pub omega: f64,
    /// The level's name in the summary.
    pub level: &'static str,
}

/// A finished run with the states at the window's ends (for the figures a
/// level adds from its own quadratures).
pub(crate) struct Finished<const N: usize> {
    pub result: SimResult,
    /// Time and state at the start of the reported window.
    pub window_start: (f64, [f64; N]),
    /// Time and state at the end.
    pub end: (f64, [f64; N]),
    /// The continuous-time maxima of the tracked quantities.
    pub best: [f64; NQ],
}

/// The event-located integration of any [`JointModel`] over the protocol.
pub(crate) fn run_model<M: JointModel<N>, const N: usize>(
    p: &Params,
    opts: &SimOptions,
    model: M,
    how: &RunSetup,
    progress: &Progress,
) -> Result<Finished<N>, SimError> {
    let start = Instant::now();
    let period = how.period;
    let c = model.clearance();
    let t_rep = opts.warmup * period;
    let t_end = (opts.warmup + opts.revs) * period;
    let fixed_step = match (opts.step, opts.method) {
        (Some(h), _) => Some(h),
        (None, Method::Rk4) => Some(period / RK4_STEPS_PER_REV),
        _ => None,
    };
    let cfg = StepperConfig {
        tol: model.tolerance(opts.rtol, opts.atol),
        h: fixed_step.unwrap_or(0.0),
        h_max: f64::INFINITY,
        max_steps: opts.max_steps,
        fixed: fixed_step.is_some(),
    };
    let st = Stepper::new(opts.method, cfg);
    let grid = opts.grid_deg.map(|g| {
        let n = (opts.revs * 360.0 / g + 1e-9).floor() as usize;
        (g.to_radians() / how.omega, n)
    });
    let mut r = Runner {
        model,
        st,
        opts,
        t_rep,
        t_end,
        aux_evals: 0,
        tracker: PeakTracker::new(),
        prev_seg: None,
        curves: grid.map(|(_, n)| Curves::with_capacity(n + 1)),
        grid_dt: grid.map(|g| g.0).unwrap_or(0.0),
        grid_next: 0,
        grid_last: grid.map(|g| g.1).unwrap_or(0),
        events: Vec::new(),
        n_impacts: 0,
        n_events: 0,
        double_crossings: 0,
        abs_s: AbsIntegral::default(),
        abs_v: AbsIntegral::default(),
        last_dev: (0.0, 0.0, 0.0),
        window_start: (0.0, [0.0; N]),
        stick: StickCount::default(),
    };
    // Rounding noise of δ = |P − B| − c evaluated from a (dense) state: a few
    // ulps of the positions. Events are placed at δ = ±2·floor on the new
    // side, so that noise cannot put the restart point back on the old one,
    // and never further than the spec's 1e-5·c.
    let noise_floor = 8.0 * f64::EPSILON * (p.l + p.r + r.model.x4_tdc());
    let ev_tol = (opts.event_tol * c).max(4.0 * noise_floor).min(1e-5 * c);
    let ev_target = (2.0 * noise_floor).min(0.5 * ev_tol);
    let a_ref = r.model.accel_scale();
    let free_limit_acc = (4.0 * c / a_ref).sqrt();

    let mut t = 0.0;
    let mut y = r.model.initial_state(opts.perturb_x4);
    let theta_start = r.model.theta2(t, &y);
    r.model.set_quadratures(t_rep == 0.0);
    r.st.reset(&r.model, t, y, true);
    let mut pen = r.model.penetration(t, &y);
    let mut pg = r.model.process_event(r.model.mode(), t, &y);
    let mut q_start = 0.0;
    if t_rep == 0.0 {
        q_start = start_window(&mut r, t, &y);
    }
    progress.set_total(1000);
    let mut iter: u64 = 0;
    let (mut contact_steps, mut free_steps) = (0u64, 0u64);
    let budget = |t: f64, theta2: f64, what: String| SimError::Budget {
        t,
        crank_deg: wrap_deg(theta2),
        what,
    };
    // Projected work: free flight never steps further than
    // `free_limit_acc`, so a clearance far below any real joint needs more
    // steps than the budget allows; say so now rather than after minutes.
    let min_free_steps = (t_end - t) / free_limit_acc;
    if r.model.has_joint() && !(min_free_steps <= opts.max_steps as f64) {
        return Err(budget(
            t,
            theta_start,
            format!(
                "the free-flight step limit √(4c/a) = {:.3e} s needs ≥ {:.3e} steps for {:.3} revolutions (budget {})",
                free_limit_acc,
                min_free_steps,
                opts.warmup + opts.revs,
                opts.max_steps
            ),
        ));
    }
    while t < t_end {
        iter += 1;
        if iter.is_multiple_of(512) {
            if progress.is_cancelled() {
                return Err(SimError::Cancelled);
            }
            progress.set_done((t / t_end * 1000.0) as u64);
            let wall = start.elapsed().as_secs_f64();
            if wall > opts.max_wall_s {
                return Err(budget(
                    t,
                    r.model.theta2(t, &y),
                    format!("{wall:.1} s of wall time (budget {} s)", opts.max_wall_s),
                ));
            }
            if super::process_deadline().is_some_and(|d| std::time::Instant::now() > d) {
                return Err(budget(
                    t,
                    r.model.theta2(t, &y),
                    "the process's wall time (PINSIGHT_MAX_WALL_S)".to_string(),
                ));
            }
        }
        // Every pass (a step, or a restart at an event) counts: restarts
        // that make no step must not loop for ever either.
        if iter > opts.max_steps {
            return Err(budget(
                t,
                r.model.theta2(t, &y),
                format!(
                    "{iter} steps and event restarts (budget {})",
                    opts.max_steps
                ),
            ));
        }
        let stop = if t < t_rep { t_rep } else { t_end };
        let in_contact = r.model.mode().in_contact;
        let h_max = if !r.model.has_joint() {
            r.model.max_step()
        } else if in_contact {
            // Separating: do not reach far past the linearly predicted loss
            // of contact (the force vanishes like δ^1.5 there).
            // Floored at the step the contact law itself allows, so a grazing
            // contact (δ ≈ 0) cannot shrink the steps to nothing.
            let (d, dd) = pen;
            if dd < 0.0 && d > 0.0 {
                (1.2 * d / -dd).max(0.5 * r.model.onset_step(-dd, opts.rtol * c + opts.atol))
            } else {
                f64::INFINITY
            }
        } else {
            let v = r.model.relative_speed(t, &y).max(1e-12);
            (2.0 * c / v).min(free_limit_acc)
        };
        if let Err(e) = r.st.step(&r.model, stop, h_max) {
            return Err(r.fail(e));
        }
        let (t0, t1) = (r.st.t_prev(), r.st.t());
        if !(t1 > t0) {
            return Err(budget(
                t0,
                r.model.theta2(t0, &y),
                "no progress: the step fell below the resolution of time (h ≤ 1 ulp of t)".into(),
            ));
        }
        if in_contact {
            contact_steps += 1;
        } else {
            free_steps += 1;
        }
        let y1 = *r.st.y();
        if let Some(w1) = r.model.stall_margin(&y1)
            && !(w1 > 0.0)
        {
            return Err(r.stall(t0, t1, theta_start));
        }
        // δ and δ̇ at the step's end: the step's last evaluation computed
        // them (the same δ; δ̇ to rounding), else the cheap evaluation.
        let pen1 = match r.model.cached_end(r.model.mode(), t1, &y1) {
            Some(o) => (o.delta, o.delta_dot),
            None => r.model.penetration(t1, &y1),
        };
        let (d0, dd0) = pen;
        let (d1, dd1) = pen1;
        if !(d1 < r.model.rb()) {
            // Deeper than the journal itself (or NaN): not physics any more.
            return Err(SimError::BlowUp {
                t: t1,
                crank_deg: wrap_deg(r.model.theta2(t1, &y1)),
                penetration_um: d1 * 1e6,
            });
        }
        let crossing = events::contact_crossing(&mut r, in_contact, (t0, d0, dd0), (t1, d1, dd1));
        // The stick law's event on [t0, t1] (a sign change of its event
        // function), located; it wins over a contact event only if earlier.
        let mode_now = r.model.mode();
        let process_at = events::process_crossing(&mut r, (t0, pg), (t1, &y1), period);
        let contact_first = match (crossing, process_at) {
            (Some(_), None) => true,
            (Some((ta, ..)), Some(tp)) => ta < tp,
            _ => false,
        };
        if let (Some(tp), false) = (process_at, contact_first) {
            let mode = mode_now;
            let mut yp = if tp == t1 { y1 } else { r.st.dense(tp) };
            r.finish_segment(t0, tp, &yp, mode);
            let was_held = mode.process == ProcessMode::Held;
            let next = r.model.process_switch(mode, tp, &mut yp);
            r.model.set_mode(Mode {
                process: next,
                ..mode
            });
            r.stick.event(was_held, next == ProcessMode::Held);
            r.n_events += 1;
            if r.n_events > 10_000 * (tp / period + 1.0) as u64 {
                return Err(SimError::EventStorm(r.n_events));
            }
            t = tp;
            y = yp;
            pen = r.model.penetration(t, &y);
            r.st.reset(&r.model, t, y, true);
        } else if let Some((ta, ga, tb, gb)) = crossing {
            let mode = r.model.mode();
            r.dense_in(mode);
            // The old side's value, kept strictly on its side.
            let ga = if in_contact {
                ga.max(f64::MIN_POSITIVE)
            } else {
                ga.min(-f64::MIN_POSITIVE)
            };
            // Root of δ − target, target = ±2·floor on the new side.
            let target = if in_contact { -ev_target } else { ev_target };
            let (te, ge, n) = if gb.abs() <= ev_tol {
                // The crossing end itself is within tolerance on the new side.
                (tb, gb - target, 0)
            } else {
                let st = &r.st;
                let m = &r.model;
                bracket_root(
                    |tt| m.penetration(tt, &st.dense(tt)).0 - target,
                    ta,
                    ga - target,
                    tb,
                    gb - target,
                    4.0 * f64::EPSILON * tb.abs().max(period),
                    |g| (g + target).abs() <= ev_tol && g.abs() <= 0.5 * ev_target,
                )
            };
            r.aux_evals += n as u64;
            let ye = if te == t1 { y1 } else { r.st.dense(te) };
            let _ = ge;
            let (de, dde) = r.model.penetration(te, &ye);
            let _ = ge;
            r.finish_segment(t0, te, &ye, mode);
            if in_contact {
                r.model.set_mode(Mode {
                    in_contact: false,
                    approach: 0.0,
                    ..mode
                });
                r.record_event(false, te, &ye, dde, de);
            } else {
                r.model.set_mode(Mode {
                    in_contact: true,
                    approach: dde,
                    ..mode
                });
                r.record_event(true, te, &ye, dde, de);
            }
            if r.n_events > 10_000 * (te / period + 1.0) as u64 {
                return Err(SimError::EventStorm(r.n_events));
            }
            t = te;
            y = ye;
            pen = (de, dde);
            r.st.reset(&r.model, t, y, true);
            if !in_contact && fixed_step.is_none() {
                r.st.set_next_step(0.5 * r.model.onset_step(dde, opts.rtol * c + opts.atol));
            }
        } else {
            let mode = r.model.mode();
            r.finish_segment(t0, t1, &y1, mode);
            t = t1;
            y = y1;
            pen = pen1;
        }
        if r.model.mode().process == ProcessMode::Held {
            r.stick.held_step();
        }
        pg = r.model.process_event(r.model.mode(), t, &y);
        if t == t_rep && !r.tracker.started() {
            // Reported window: turn the quadratures on and restart the
            // stepper so its first-stage derivative includes them.
            r.model.set_quadratures(true);
            r.st.reset(&r.model, t, y, false);
            q_start = start_window(&mut r, t, &y);
        }
    }
    progress.set_done(1000);
    Ok(report::finish(
        r,
        LoopEnd {
            p,
            opts,
            how,
            start,
            fixed_step,
            contact_steps,
            free_steps,
            t,
            y,
            q_start,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A clearance far below any real joint (validation refuses it; a
    /// struct can still be built in code) ends with a budget error at once
    /// instead of spinning: every free-flight step would be ~1e-300 s.
    #[test]
    fn a_vanishing_clearance_stops_with_a_budget_error_instead_of_spinning() {
        for c in [1e-43, 1e-300] {
            let mut p = Params::paper();
            p.clearance = c;
            let opts = SimOptions {
                warmup: 0.0,
                revs: 0.5,
                ..SimOptions::default()
            };
            let t0 = Instant::now();
            let r = run(&p, &opts, &Progress::hidden());
            let elapsed = t0.elapsed().as_secs_f64();
            match r {
                Err(SimError::Budget { what, .. }) => assert!(what.contains("steps"), "{what}"),
                Err(e) => panic!("c = {c}: expected a budget error, got {e}"),
                Ok(_) => panic!("c = {c}: a run with this clearance cannot succeed"),
            }
            assert!(elapsed < 5.0, "c = {c}: took {elapsed} s");
        }
    }

    /// Without the figures the trajectory and its curves are the same to
    /// the bit (only the summary's refined peaks and averages are left
    /// out, and read NaN); the steps taken are the same.
    #[test]
    fn a_run_without_figures_has_the_same_curves_and_steps() {
        let mut p = Params::paper();
        p.clearance = 0.3e-3;
        let on = SimOptions {
            warmup: 1.0,
            revs: 3.0,
            rtol: 1e-4,
            grid_deg: Some(0.5),
            ..SimOptions::default()
        };
        let off = SimOptions {
            figures: false,
            ..on.clone()
        };
        let a = run(&p, &on, &Progress::hidden()).unwrap();
        let b = run(&p, &off, &Progress::hidden()).unwrap();
        let (ca, cb) = (a.curves.unwrap(), b.curves.unwrap());
        assert!(!ca.stroke_mm.is_empty());
        assert_eq!(ca.stroke_mm, cb.stroke_mm);
        assert_eq!(ca.contact_force_n, cb.contact_force_n);
        assert_eq!(ca.process_force_n, cb.process_force_n);
        assert_eq!(a.summary.steps, b.summary.steps);
        assert_eq!(a.summary.rejected_steps, b.summary.rejected_steps);
        assert_eq!(a.summary.n_impacts, b.summary.n_impacts);
        assert!(a.summary.peak_accel_mps2.is_finite());
        assert!(b.summary.peak_accel_mps2.is_nan());
        assert!(b.summary.disp_dev_mean_mm.is_nan());
        // And `simulate` accepts such a run (its check is on the curves).
        assert!(crate::sim::simulate(&p, &off, &Progress::hidden()).is_ok());
    }

    /// The wall-clock budget stops a run that would take longer.
    #[test]
    fn the_wall_clock_budget_stops_a_long_run() {
        let opts = SimOptions {
            warmup: 0.0,
            revs: 1000.0,
            max_wall_s: 0.05,
            ..SimOptions::default()
        };
        let r = run(&Params::paper(), &opts, &Progress::hidden());
        match r {
            Err(SimError::Budget {
                what, crank_deg, ..
            }) => {
                assert!(what.contains("wall time"), "{what}");
                assert!((0.0..=360.0).contains(&crank_deg));
            }
            other => panic!("expected the wall-clock budget to stop the run: {other:?}"),
        }
    }
}
