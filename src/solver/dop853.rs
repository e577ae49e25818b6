//! Dormand–Prince 8(5,3) (Hairer's DOP853): 12 stages + FSAL, the combined
//! 5th/3rd-order error estimate, stiffness detection, and the 7th-order
//! continuous extension. The three extra stages of the continuous extension
//! are computed only when a step's dense output is asked for
//! ([`Dop853::prepare_dense`]), so steps that need no interpolation cost 12
//! evaluations, not 15.

use super::control::{NextStep, StiffnessMonitor, derivative_at_end, trial_step};
use super::control::{PiControl, Position};
use super::dop853_coef::*;
use super::{Stats, StepError, StepperConfig, System, all_finite};

/// DOP853's controller: safety 0.9, ratios 1/3–6, err^(1/8), no β.
const CONTROL: PiControl = PiControl::new(0.9, 0.333, 6.0, 1.0 / 8.0, 0.0);
/// h·|λ| where DOP853's stability region ends on the negative real axis.
const STIFF_BOUNDARY: f64 = 6.1;

#[derive(Debug, Clone)]
pub struct Dop853<const N: usize> {
    pub(crate) cfg: StepperConfig<N>,
    pub pos: Position<N>,
    /// Stages k1..k16 of the last accepted step (k13 = f(t, y)).
    k: [[f64; N]; 16],
    pub next: NextStep,
    h_used: f64,
    ctl: PiControl,
    dense_ready: bool,
    rcont: [[f64; N]; 8],
    stiffness: StiffnessMonitor,
    pub stats: Stats,
}

#[inline(always)]
fn comb<const N: usize, const M: usize>(
    y: &[f64; N],
    h: f64,
    a: &[f64; M],
    k: &[[f64; N]; 16],
) -> [f64; N] {
    let mut out = *y;
    for (j, &aj) in a.iter().enumerate() {
        if aj != 0.0 {
            let ha = h * aj;
            for i in 0..N {
                out[i] += ha * k[j][i];
            }
        }
    }
    out
}

impl<const N: usize> Dop853<N> {
    pub fn new(cfg: StepperConfig<N>) -> Self {
        Self {
            cfg,
            pos: Position::new(),
            k: [[0.0; N]; 16],
            next: NextStep::new(cfg.h, true),
            h_used: 0.0,
            ctl: CONTROL,
            dense_ready: true,
            rcont: [[0.0; N]; 8],
            stiffness: StiffnessMonitor::default(),
            stats: Stats::default(),
        }
    }

    pub fn reset<S: System<N>>(&mut self, sys: &S, t: f64, y: [f64; N], fresh_step: bool) {
        self.pos.restart(sys, t, y, &mut self.stats);
        self.ctl.restart();
        self.next.restart(fresh_step);
        self.h_used = 0.0;
        self.dense_ready = true;
        self.rcont = [[0.0; N]; 8];
        self.rcont[0] = y;
    }

    pub fn step<S: System<N>>(&mut self, sys: &S, t_end: f64, h_max: f64) -> Result<(), StepError> {
        let h_max = h_max.min(self.cfg.h_max);
        let ncon = self.cfg.tol.n_controlled() as f64;
        let (t, y) = (self.pos.t, self.pos.y);
        // The stages are computed in place: a rejected try overwrites
        // them, the accepted one stays for the dense output.
        let k = &mut self.k;
        k[0] = self.pos.f;
        let (cfg, pos) = (&self.cfg, &self.pos);
        let mut h = self
            .next
            .size(cfg, &cfg.tol, sys, pos, 8, h_max, &mut self.stats);
        loop {
            let (h_try, last) = trial_step(&self.stats, self.cfg.max_steps, t, h, t_end)?;
            h = h_try;
            let tph = if last { t_end } else { t + h };
            // The stages written out, so that each row's constant
            // coefficients (zeros dropped) compile to straight-line code;
            // the same sums in the same order as a loop over the rows.
            macro_rules! stage {
                ($s:expr, $row:expr) => {{
                    let yt = comb(&y, h, &$row, k);
                    sys.rhs(t + C[$s] * h, &yt, &mut k[$s]);
                }};
            }
            stage!(1, A2);
            stage!(2, A3);
            stage!(3, A4);
            stage!(4, A5);
            stage!(5, A6);
            stage!(6, A7);
            stage!(7, A8);
            stage!(8, A9);
            stage!(9, A10);
            stage!(10, A11);
            let y12 = comb(&y, h, &A12, k);
            sys.rhs(tph, &y12, &mut k[11]);
            self.stats.rhs_evals += 11;
            // 8th-order solution.
            let mut ynew = y;
            let mut k4 = [0.0; N];
            for i in 0..N {
                let mut acc = 0.0;
                for j in 0..12 {
                    acc += B[j] * k[j][i];
                }
                k4[i] = acc;
                ynew[i] = y[i] + h * acc;
            }
            // Error estimate (5th and 3rd order combination).
            let w = self.cfg.tol.weights(&y, &ynew);
            let mut err = 0.0;
            let mut err2 = 0.0;
            for i in 0..N {
                if w[i] == 0.0 {
                    continue;
                }
                let e3 = k4[i] - BHH[0] * k[0][i] - BHH[1] * k[8][i] - BHH[2] * k[11][i];
                err2 += (e3 * w[i]).powi(2);
                let mut e5 = 0.0;
                for j in 0..12 {
                    e5 += ER[j] * k[j][i];
                }
                err += (e5 * w[i]).powi(2);
            }
            let mut deno = err + 0.01 * err2;
            if deno <= 0.0 {
                deno = 1.0;
            }
            let err = if self.cfg.fixed {
                0.0
            } else {
                h.abs() * err * (1.0 / (ncon * deno)).sqrt()
            };
            if self.cfg.fixed && !all_finite(&ynew) {
                return Err(StepError::NonFinite { t });
            }
            if !err.is_finite() || !all_finite(&ynew) {
                self.stats.rejected += 1;
                h = self.ctl.reject_non_finite(h, t)?;
                continue;
            }
            let (fac11, hnew) = self
                .ctl
                .propose(err, h, self.cfg.fixed.then_some(self.cfg.h));
            if err <= 1.0 {
                let fnew = derivative_at_end(sys, tph, &ynew, &mut self.stats)?;
                self.stats.steps += 1;
                self.stiffness.observe(
                    h,
                    (&fnew, &k[11]),
                    (&ynew, &y12),
                    STIFF_BOUNDARY,
                    &mut self.stats,
                );
                k[12] = fnew;
                let hnew = self.ctl.accept(err, h, hnew);
                self.pos.advance((t, y), tph, ynew, fnew);
                self.h_used = h;
                self.next.h = hnew.min(self.cfg.h_max);
                self.dense_ready = false;
                return Ok(());
            }
            self.stats.rejected += 1;
            h = self.ctl.reject(h, fac11);
        }
    }

    /// Computes the continuous extension of the last step (three extra
    /// stages); a no-op when already done.
    pub fn prepare_dense<S: System<N>>(&mut self, sys: &S) {
        if self.dense_ready {
            return;
        }
        let h = self.h_used;
        let (t, y) = (self.pos.t_prev, self.pos.y_prev);
        let k = &mut self.k;
        let yt = comb(&y, h, &A14, k);
        let mut out = [0.0; N];
        sys.rhs(t + C[13] * h, &yt, &mut out);
        k[13] = out;
        let yt = comb(&y, h, &A15, k);
        sys.rhs(t + C[14] * h, &yt, &mut out);
        k[14] = out;
        let yt = comb(&y, h, &A16, k);
        sys.rhs(t + C[15] * h, &yt, &mut out);
        k[15] = out;
        self.stats.rhs_evals += 3;
        let mut r = [[0.0; N]; 8];
        for i in 0..N {
            let ydiff = self.pos.y[i] - y[i];
            let bspl = h * k[0][i] - ydiff;
            r[0][i] = y[i];
            r[1][i] = ydiff;
            r[2][i] = bspl;
            r[3][i] = ydiff - h * k[12][i] - bspl;
        }
        for (m, d) in [&D4, &D5, &D6, &D7].iter().enumerate() {
            for i in 0..N {
                let mut acc = 0.0;
                for j in 0..16 {
                    acc += d[j] * k[j][i];
                }
                r[4 + m][i] = h * acc;
            }
        }
        self.rcont = r;
        self.dense_ready = true;
    }

    /// 7th-order continuous extension on [t_prev, t]. Call
    /// [`Dop853::prepare_dense`] first (the stepper dispatcher does).
    pub fn dense(&self, t: f64) -> [f64; N] {
        let h = self.pos.t - self.pos.t_prev;
        if h <= 0.0 {
            return self.pos.y;
        }
        debug_assert!(self.dense_ready, "prepare_dense not called");
        let s = (t - self.pos.t_prev) / h;
        let s1 = 1.0 - s;
        let r = &self.rcont;
        let mut out = [0.0; N];
        for i in 0..N {
            let conpar = r[4][i] + s * (r[5][i] + s1 * (r[6][i] + s * r[7][i]));
            out[i] = r[0][i] + s * (r[1][i] + s1 * (r[2][i] + s * (r[3][i] + s1 * conpar)));
        }
        out
    }
}
