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
//! The file reads best whole: `run_model` is one state machine over one
//! stepper and one state (the step, the event search and its location, the
//! mode switches of contact, stick and stall, the grid samples and the peak
//! refinement), and the helpers above it exist only for that loop. Split,
//! the loop's state would travel back and forth between files.

use super::summary::{
    NQ, PeakTracker, Q_ACC, Q_DS, Q_DV, Q_FN, Q_M12, Q_PEN, Q_PROC, Q_SMAX, Q_SMIN, quantities,
};
use super::{ContactEvent, Curves, SimError, SimOptions, SimResult, Summary, wrap_deg};
use crate::model::clearance::{ClearanceModel, Mode};
use crate::model::contact::ProcessMode;
use crate::model::joint_model::{InMode, JointModel};
use crate::model::params::Params;
use crate::progress::Progress;
use crate::solver::roots::{bracket_root, maximize};
use crate::solver::{Method, StepError, Stepper, StepperConfig};
use std::time::Instant;

/// Points per free-flight step at which δ and δ̇ are sampled on the dense
/// output to catch contacts entered and left inside the step.
const FREE_SAMPLES: usize = 8;

/// Default RK4 step: this many steps per crank revolution.
pub const RK4_STEPS_PER_REV: f64 = 20_000.0;

/// One integration segment kept for peak refinement.
#[derive(Clone)]
struct Segment<const N: usize> {
    st: Stepper<N>,
    ta: f64,
    tb: f64,
    mode: Mode,
}

/// Whether f, going from fa to fb with slopes dfa, dfb, may have a zero
/// inside: a sign change, or an extremum turning back towards zero.
fn may_have_zero(fa: f64, fb: f64, dfa: f64, dfb: f64) -> bool {
    if fa * fb < 0.0 {
        return true;
    }
    let sg = fa.signum();
    fa != 0.0 && fb != 0.0 && sg * dfa < 0.0 && sg * dfb > 0.0
}

/// ∫|f| dt assembled from a smooth primitive F between the zeros of f.
#[derive(Debug, Clone, Copy, Default)]
struct AbsIntegral {
    total: f64,
    /// F at the start of the current piece (last zero of f).
    piece_start: f64,
}

impl AbsIntegral {
    /// Accounts for the segment [ta, tb] on which f goes from fa to fb with
    /// slopes dfa, dfb: finds the zeros of f (one sign change, or two around
    /// an interior extremum) on the dense output and closes a piece at each.
    #[allow(clippy::too_many_arguments)]
    fn segment<Fz: Fn(f64) -> f64, Fp: Fn(f64) -> f64>(
        &mut self,
        ta: f64,
        tb: f64,
        (fa, fb): (f64, f64),
        (dfa, dfb): (f64, f64),
        f: Fz,
        prim: Fp,
        evals: &mut u64,
    ) {
        let t_tol = (tb - ta) * 1e-9;
        let close = |z: f64, this: &mut Self, evals: &mut u64| {
            let fz = prim(z);
            *evals += 1;
            this.total += (fz - this.piece_start).abs();
            this.piece_start = fz;
        };
        if !may_have_zero(fa, fb, dfa, dfb) {
            return;
        }
        if fa * fb < 0.0 {
            let (z, _, n) = bracket_root(&f, ta, fa, tb, fb, t_tol, |_| false);
            *evals += n as u64;
            close(z, self, evals);
        } else if fa != 0.0 && fb != 0.0 {
            let sg = fa.signum();
            if sg * dfa < 0.0 && sg * dfb > 0.0 {
                let (tm, vm, n) = maximize(|t| -sg * f(t), ta, tb, -sg * fa, -sg * fb, t_tol);
                *evals += n as u64;
                if vm > 0.0 {
                    let fm = -sg * vm;
                    let (z1, _, n1) = bracket_root(&f, ta, fa, tm, fm, t_tol, |_| false);
                    let (z2, _, n2) = bracket_root(&f, tm, fm, tb, fb, t_tol, |_| false);
                    *evals += (n1 + n2) as u64;
                    close(z1, self, evals);
                    close(z2, self, evals);
                }
            }
        }
    }

    /// Closes the last piece at the window's end, where the primitive is `f_end`.
    fn finish(&mut self, f_end: f64) -> f64 {
        self.total + (f_end - self.piece_start).abs()
    }
}

struct Runner<'a, M: JointModel<N>, const N: usize> {
    model: M,
    st: Stepper<N>,
    opts: &'a SimOptions,
    t_rep: f64,
    t_end: f64,
    aux_evals: u64,
    tracker: PeakTracker,
    prev_seg: Option<Segment<N>>,
    curves: Option<Curves>,
    grid_dt: f64,
    grid_next: usize,
    grid_last: usize,
    events: Vec<ContactEvent>,
    n_impacts: u64,
    n_events: u64,
    double_crossings: u64,
    /// ∫|Δs| dt (primitive Q_s) and ∫|Δv| dt (primitive Δs).
    abs_s: AbsIntegral,
    abs_v: AbsIntegral,
    /// (Δs, Δv, Δa) at the last segment boundary.
    last_dev: (f64, f64, f64),
    /// Time and state where the reported window began.
    window_start: (f64, [f64; N]),
    /// The stick law's phases.
    stick: StickCount,
}

/// Phases in which the part held the pin bar (stick law), and the steps
/// each took (a chattering law would need ever more).
#[derive(Debug, Clone, Copy, Default)]
struct StickCount {
    phases: u64,
    events: u64,
    held_steps: u64,
    current: u64,
    max_phase_steps: u64,
}

impl StickCount {
    fn event(&mut self, was_held: bool, now_held: bool) {
        self.events += 1;
        if now_held && !was_held {
            self.phases += 1;
            self.current = 0;
        }
    }
    fn held_step(&mut self) {
        self.held_steps += 1;
        self.current += 1;
        self.max_phase_steps = self.max_phase_steps.max(self.current);
    }
}

impl<M: JointModel<N>, const N: usize> Runner<'_, M, N> {
    fn in_report(&self, t: f64) -> bool {
        t >= self.t_rep
    }

    /// Handles the finished segment [ta, tb] of the current step, run in `mode`.
    fn finish_segment(&mut self, ta: f64, tb: f64, y_b: &[f64; N], mode: Mode) {
        if !self.in_report(ta) || tb <= ta {
            return;
        }
        // Curves on the crank-angle grid.
        if self.curves.is_some() {
            let mut prepared = false;
            while self.grid_next <= self.grid_last {
                let tg = (self.t_rep + self.grid_dt * self.grid_next as f64).min(self.t_end);
                if tg > tb {
                    break;
                }
                if !prepared {
                    self.st.prepare_dense(&InMode {
                        model: &self.model,
                        mode,
                    });
                    prepared = true;
                }
                let y = if tg == tb { *y_b } else { self.st.dense(tg) };
                let o = self.model.outputs_in(mode, tg, &y);
                self.aux_evals += 1;
                if let Some(c) = self.curves.as_mut() {
                    c.push(&o, true);
                }
                self.grid_next += 1;
            }
        }
        // Peaks (the step's last evaluation computed them when the segment
        // ends where the step did).
        let o_b = match self.model.cached_end(mode, tb, y_b) {
            Some(o) => o,
            None => {
                self.aux_evals += 1;
                self.model.outputs_in(mode, tb, y_b)
            }
        };
        // Time averages of |Δs| and |Δv|, split at the zeros.
        let dev_b = (
            o_b.s - o_b.ideal_s,
            o_b.v4 - o_b.ideal_v,
            o_b.a4 - o_b.ideal_a,
        );
        let dev_a = self.last_dev;
        let needs_dense = may_have_zero(dev_a.0, dev_b.0, dev_a.1, dev_b.1)
            || may_have_zero(dev_a.1, dev_b.1, dev_a.2, dev_b.2);
        if needs_dense {
            self.st.prepare_dense(&InMode {
                model: &self.model,
                mode,
            });
        }
        {
            let st = &self.st;
            let m = &self.model;
            let ds = |t: f64| {
                let y = st.dense(t);
                m.deviation(t, &y).0
            };
            let dv = |t: f64| {
                let y = st.dense(t);
                m.deviation(t, &y).1
            };
            let qs = |t: f64| st.dense(t)[M::Q_S];
            self.abs_s.segment(
                ta,
                tb,
                (dev_a.0, dev_b.0),
                (dev_a.1, dev_b.1),
                ds,
                qs,
                &mut self.aux_evals,
            );
            self.abs_v.segment(
                ta,
                tb,
                (dev_a.1, dev_b.1),
                (dev_a.2, dev_b.2),
                dv,
                ds,
                &mut self.aux_evals,
            );
        }
        self.last_dev = dev_b;
        let refine = self.tracker.push(tb, quantities(&o_b));
        let seg = Segment {
            st: self.st.clone(),
            ta,
            tb,
            mode,
        };
        if refine.iter().any(|&r| r) {
            let mut cur = seg;
            for q in 0..NQ {
                if !refine[q] {
                    continue;
                }
                if let Some(prev) = self.prev_seg.as_mut() {
                    let v = refine_in(&self.model, prev, q, &mut self.aux_evals);
                    self.tracker.offer(q, v);
                }
                let v = refine_in(&self.model, &mut cur, q, &mut self.aux_evals);
                self.tracker.offer(q, v);
            }
            self.prev_seg = Some(cur);
        } else {
            self.prev_seg = Some(seg);
        }
    }

    fn record_event(&mut self, onset: bool, t: f64, y: &[f64; N], dd: f64, delta: f64) {
        self.n_events += 1;
        let in_report = self.in_report(t);
        if onset && in_report {
            self.n_impacts += 1;
        }
        if self.opts.record_events {
            self.events.push(ContactEvent {
                onset,
                t_s: t,
                crank_deg: wrap_deg(self.model.theta2(t, y)),
                delta_dot_mps: dd,
                residual_rel: delta.abs() / self.model.clearance(),
                in_report,
            });
        }
    }

    /// The crank stalled on the last step [t0, t1] (its speed above the
    /// stall speed at t0, not at t1): the moment located on the dense
    /// output, said as a crank angle after top dead centre and a revolution.
    fn stall(&mut self, t0: f64, t1: f64, theta_start: f64) -> SimError {
        let mode = self.model.mode();
        self.st.prepare_dense(&InMode {
            model: &self.model,
            mode,
        });
        let st = &self.st;
        let m = &self.model;
        let w = |t: f64| m.stall_margin(&st.dense(t)).unwrap_or(0.0);
        let (w0, w1) = (w(t0), w(t1));
        let (ts, _, _) = if w0 > 0.0 && w1 <= 0.0 {
            bracket_root(w, t0, w0, t1, w1, (t1 - t0) * 1e-9, |_| false)
        } else {
            (t1, w1, 0)
        };
        let ys = self.st.dense(ts);
        let o = self.model.outputs(ts, &ys);
        let turned = (self.model.theta2(ts, &ys) - theta_start).max(0.0);
        let tau = std::f64::consts::TAU;
        SimError::Stall {
            t: ts,
            crank_deg: (turned.rem_euclid(tau)).to_degrees(),
            revolution: (turned / tau).floor() as u64 + 1,
            motor_torque_nm: o.motor_torque,
            demand_nm: o.m12,
            fraction_pct: crate::model::motor::STALL_FRACTION * 100.0,
        }
    }

    fn fail(&self, source: StepError) -> SimError {
        let t = self.st.t();
        let (delta, _) = self.model.penetration(t, self.st.y());
        SimError::Integration {
            source,
            t,
            crank_deg: wrap_deg(self.model.theta2(t, self.st.y())),
            penetration_um: delta * 1e6,
            mode: if self.model.mode().in_contact {
                "in contact"
            } else {
                "in free flight"
            },
        }
    }
}

/// Starts the reported window at (t, y): peak tracker, |Δ| integrals;
/// returns the ΔM² quadrature's value there.
fn start_window<M: JointModel<N>, const N: usize>(
    r: &mut Runner<M, N>,
    t: f64,
    y: &[f64; N],
) -> f64 {
    let o = r.model.outputs(t, y);
    r.aux_evals += 1;
    r.tracker.start(t, quantities(&o));
    r.window_start = (t, *y);
    r.last_dev = (o.s - o.ideal_s, o.v4 - o.ideal_v, o.a4 - o.ideal_a);
    r.abs_s = AbsIntegral {
        total: 0.0,
        piece_start: y[M::Q_S],
    };
    r.abs_v = AbsIntegral {
        total: 0.0,
        piece_start: o.s - o.ideal_s,
    };
    y[M::Q_DM2]
}

/// Brent's time tolerance for a peak, relative to the segment: at a smooth
/// maximum the value's error is second order in it. 1e-7 (before) cost
/// 2–3 % more instructions per run for the same Flores window figures
/// (within 1.7e-8 of the reference either way).
const PEAK_TOL: f64 = 1e-4;

/// Maximises quantity q over a stored segment with its dense output.
fn refine_in<M: JointModel<N>, const N: usize>(
    model: &M,
    seg: &mut Segment<N>,
    q: usize,
    evals: &mut u64,
) -> f64 {
    seg.st.prepare_dense(&InMode {
        model,
        mode: seg.mode,
    });
    let mode = seg.mode;
    let st = &seg.st;
    let (_, v, n) = maximize(
        |t| quantities(&model.outputs_in(mode, t, &st.dense(t)))[q],
        seg.ta,
        seg.tb,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        (seg.tb - seg.ta) * PEAK_TOL,
    );
    *evals += n as u64;
    v
}

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
        let pen1 = r.model.penetration(t1, &y1);
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
        // Look for this mode's event: onset (δ up through 0) in free
        // flight, loss (δ down through 0) in contact.
        // crossing = (ta, g(ta), tb, g(tb)) bracketing the event.
        let mut crossing: Option<(f64, f64, f64, f64)> = None;
        if !r.model.has_joint() {
            // No joint, no contact events.
        } else if in_contact {
            if d1 < 0.0 {
                crossing = Some((t0, d0, t1, d1));
            } else if dd0 < 0.0 && dd1 > 0.0 {
                // δ turned inside the step: did it dip below zero?
                let mode = r.model.mode();
                r.st.prepare_dense(&InMode {
                    model: &r.model,
                    mode,
                });
                let st = &r.st;
                let m = &r.model;
                let (tm, vm, n) = maximize(
                    |tt| -m.penetration(tt, &st.dense(tt)).0,
                    t0,
                    t1,
                    -d0,
                    -d1,
                    (t1 - t0) * 1e-9,
                );
                r.aux_evals += n as u64;
                if vm > 0.0 {
                    crossing = Some((t0, d0, tm, -vm));
                    r.double_crossings += 1;
                }
            }
        } else {
            // Free flight: δ and δ̇ at FREE_SAMPLES points of the dense
            // output, so that a contact entered and left inside the step
            // (a double crossing, possibly after a minimum and a maximum
            // of δ) is seen: a positive sample, or δ̇ turning from + to −
            // in a sub-interval whose maximum is positive.
            let mode = r.model.mode();
            r.st.prepare_dense(&InMode {
                model: &r.model,
                mode,
            });
            let mut prev = (t0, d0, dd0);
            for k in 1..=FREE_SAMPLES {
                let (tk, dk, ddk) = if k == FREE_SAMPLES {
                    (t1, d1, dd1)
                } else {
                    let tt = t0 + (t1 - t0) * k as f64 / FREE_SAMPLES as f64;
                    let (d, dd) = r.model.penetration(tt, &r.st.dense(tt));
                    r.aux_evals += 1;
                    (tt, d, dd)
                };
                if dk > 0.0 {
                    crossing = Some((prev.0, prev.1, tk, dk));
                    break;
                }
                if prev.2 > 0.0 && ddk < 0.0 {
                    let st = &r.st;
                    let m = &r.model;
                    let (tm, vm, n) = maximize(
                        |tt| m.penetration(tt, &st.dense(tt)).0,
                        prev.0,
                        tk,
                        prev.1,
                        dk,
                        (tk - prev.0) * 1e-9,
                    );
                    r.aux_evals += n as u64;
                    if vm > 0.0 {
                        crossing = Some((prev.0, prev.1, tm, vm));
                        break;
                    }
                }
                prev = (tk, dk, ddk);
            }
            if crossing.is_some() && d1 <= 0.0 {
                r.double_crossings += 1;
            }
        }
        // The stick law's event on [t0, t1] (a sign change of its event
        // function), located; it wins over a contact event only if earlier.
        let mode_now = r.model.mode();
        let pg1 = r.model.process_event(mode_now, t1, &y1);
        let mut process_at: Option<f64> = None;
        if let (Some(g0), Some(g1)) = (pg, pg1)
            && g0 > 0.0
            && !(g1 > 0.0)
        {
            r.st.prepare_dense(&InMode {
                model: &r.model,
                mode: mode_now,
            });
            let st = &r.st;
            let m = &r.model;
            let (tp, _, n) = bracket_root(
                |tt| m.process_event(mode_now, tt, &st.dense(tt)).unwrap_or(0.0),
                t0,
                g0,
                t1,
                g1,
                4.0 * f64::EPSILON * t1.abs().max(period),
                |_| false,
            );
            r.aux_evals += n as u64;
            process_at = Some(tp);
        }
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
            r.st.prepare_dense(&InMode {
                model: &r.model,
                mode,
            });
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
    let stats = *r.st.stats();
    let tw = t_end - t_rep;
    let best = r.tracker.best;
    let ideal = super::ideal_run::run(
        how.ideal,
        &SimOptions {
            level: super::Level::Ideal,
            grid_deg: None,
            ..opts.clone()
        },
    );
    let mut notes = Vec::new();
    if r.double_crossings > 0 {
        notes.push(format!(
            "the double-crossing guard caught {} contact(s) that a step would have skipped",
            r.double_crossings
        ));
    }
    if stats.stiff_steps > 0 {
        notes.push(format!(
            "stiffness detected on {} steps: an implicit method (radau5) may be cheaper",
            stats.stiff_steps
        ));
    }
    let summary = Summary {
        preset: p.preset.clone(),
        motor_rpm: p.motor_rpm,
        clearance_mm: c * 1e3,
        material: p.material_name(),
        contact_model: p.contact_model.name().into(),
        level: how.level.into(),
        method: opts.method.name().into(),
        rtol: opts.rtol,
        atol: opts.atol,
        step_s: fixed_step,
        warmup_revs: opts.warmup,
        revs: opts.revs,
        view: opts.view().into(),
        steps: stats.steps,
        rejected_steps: stats.rejected,
        rhs_evals: stats.rhs_evals,
        aux_evals: r.aux_evals,
        jacobians: stats.jacobians,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        n_impacts: r.n_impacts,
        peak_accel_mps2: best[Q_ACC],
        peak_contact_force_n: best[Q_FN],
        disp_dev_mean_mm: r.abs_s.finish(y[M::Q_S]) / tw * 1e3,
        disp_dev_max_mm: best[Q_DS] * 1e3,
        vel_dev_mean_mps: r.abs_v.finish(r.model.deviation(t, &y).0) / tw,
        vel_dev_max_mps: best[Q_DV],
        peak_torque_nm: Some(best[Q_M12]),
        torque_dev_rms_nm: Some(((y[M::Q_DM2] - q_start) / tw).max(0.0).sqrt()),
        stroke_min_mm: -best[Q_SMIN] * 1e3,
        stroke_max_mm: best[Q_SMAX] * 1e3,
        peak_process_force_n: Some(best[Q_PROC]),
        ideal_peak_accel_mps2: ideal.summary.peak_accel_mps2,
        ideal_peak_torque_nm: ideal.summary.peak_torque_nm,
        double_crossings_caught: r.double_crossings,
        peak_penetration_um: best[Q_PEN].max(0.0) * 1e6,
        contact_steps,
        free_steps,
        motor: None,
        stick: (r.stick.events > 0 || p.process_law == crate::model::params::ProcessLaw::Stick)
            .then_some(super::summary::StickSummary {
                events: r.stick.events,
                held_phases: r.stick.phases,
                held_steps: r.stick.held_steps,
                max_steps_per_phase: r.stick.max_phase_steps,
            }),
    };
    Ok(Finished {
        result: SimResult {
            summary,
            curves: r.curves,
            events: r.events,
            stats,
            notes,
        },
        window_start: r.window_start,
        end: (t, y),
        best,
    })
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
