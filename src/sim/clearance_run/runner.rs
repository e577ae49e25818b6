//! The event loop's state between steps (`Runner`) and what it does with
//! each finished segment of a step: the curves on the crank-angle grid, the
//! continuous-time peaks (refined with Brent on the dense output of this
//! segment and the one before), the time averages of |Δs| and |Δv|, the
//! contact events, the stick law's phases, and the errors that name where
//! the run stopped.

use super::abs_integral::{AbsIntegral, may_have_zero};
use crate::model::clearance::Mode;
use crate::model::joint_model::{InMode, JointModel};
use crate::sim::summary::{NQ, PeakTracker, quantities};
use crate::sim::{ContactEvent, Curves, SimError, SimOptions, wrap_deg};
use crate::solver::roots::{bracket_root, maximize};
use crate::solver::{StepError, Stepper};

/// One integration segment kept for peak refinement.
#[derive(Clone)]
pub(super) struct Segment<const N: usize> {
    st: Stepper<N>,
    ta: f64,
    tb: f64,
    mode: Mode,
}

pub(super) struct Runner<'a, M: JointModel<N>, const N: usize> {
    pub(super) model: M,
    pub(super) st: Stepper<N>,
    pub(super) opts: &'a SimOptions,
    pub(super) t_rep: f64,
    pub(super) t_end: f64,
    pub(super) aux_evals: u64,
    pub(super) tracker: PeakTracker,
    pub(super) prev_seg: Option<Segment<N>>,
    pub(super) curves: Option<Curves>,
    pub(super) grid_dt: f64,
    pub(super) grid_next: usize,
    pub(super) grid_last: usize,
    pub(super) events: Vec<ContactEvent>,
    pub(super) n_impacts: u64,
    pub(super) n_events: u64,
    pub(super) double_crossings: u64,
    /// ∫|Δs| dt (primitive Q_s) and ∫|Δv| dt (primitive Δs).
    pub(super) abs_s: AbsIntegral,
    pub(super) abs_v: AbsIntegral,
    /// (Δs, Δv, Δa) at the last segment boundary.
    pub(super) last_dev: (f64, f64, f64),
    /// Time and state where the reported window began.
    pub(super) window_start: (f64, [f64; N]),
    /// The stick law's phases.
    pub(super) stick: StickCount,
}

/// Phases in which the part held the pin bar (stick law), and the steps
/// each took (a chattering law would need ever more).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StickCount {
    pub(super) phases: u64,
    pub(super) events: u64,
    pub(super) held_steps: u64,
    pub(super) current: u64,
    pub(super) max_phase_steps: u64,
}

impl StickCount {
    pub(super) fn event(&mut self, was_held: bool, now_held: bool) {
        self.events += 1;
        if now_held && !was_held {
            self.phases += 1;
            self.current = 0;
        }
    }
    pub(super) fn held_step(&mut self) {
        self.held_steps += 1;
        self.current += 1;
        self.max_phase_steps = self.max_phase_steps.max(self.current);
    }
}

impl<M: JointModel<N>, const N: usize> Runner<'_, M, N> {
    pub(super) fn in_report(&self, t: f64) -> bool {
        t >= self.t_rep
    }

    /// Readies the dense output of the last step, the model run in `mode`
    /// over it; the stepper to read it from and the model to evaluate it.
    pub(super) fn dense_in(&mut self, mode: Mode) -> (&Stepper<N>, &M) {
        self.st.prepare_dense(&InMode {
            model: &self.model,
            mode,
        });
        (&self.st, &self.model)
    }

    /// Handles the finished segment [ta, tb] of the current step, run in `mode`.
    pub(super) fn finish_segment(&mut self, ta: f64, tb: f64, y_b: &[f64; N], mode: Mode) {
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
                    self.dense_in(mode);
                    prepared = true;
                }
                let y = if tg == tb { *y_b } else { self.st.dense(tg) };
                if self.opts.lean_curves {
                    let (s, f) = self.model.stroke_and_process_in(mode, tg, &y);
                    if let Some(c) = self.curves.as_mut() {
                        c.push_lean(s, f);
                    }
                } else {
                    let o = self.model.outputs_in(mode, tg, &y);
                    self.aux_evals += 1;
                    if let Some(c) = self.curves.as_mut() {
                        c.push(&o, true);
                    }
                }
                self.grid_next += 1;
            }
        }
        if !self.opts.figures {
            return;
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
            self.dense_in(mode);
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

    pub(super) fn record_event(&mut self, onset: bool, t: f64, y: &[f64; N], dd: f64, delta: f64) {
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
    pub(super) fn stall(&mut self, t0: f64, t1: f64, theta_start: f64) -> SimError {
        let (st, m) = self.dense_in(self.model.mode());
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

    pub(super) fn fail(&self, source: StepError) -> SimError {
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
pub(super) fn start_window<M: JointModel<N>, const N: usize>(
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
