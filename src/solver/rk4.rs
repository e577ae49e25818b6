//! Classic fourth-order Runge–Kutta with a fixed step and cubic Hermite
//! dense output (third order, from the values and derivatives at both ends).
//!
//! Fixed step means no error control: the step given is taken (shortened
//! only to land on `t_end`, on an event, or under `h_max`). A non-finite
//! state is reported as a failure — that is how an unstable step shows.

use super::control::check_budget;
use super::control::{NextStep, Position};
use super::{Stats, StepError, StepperConfig, System, all_finite};

#[derive(Debug, Clone)]
pub struct Rk4<const N: usize> {
    pub(crate) cfg: StepperConfig<N>,
    pub pos: Position<N>,
    pub(crate) f_prev: [f64; N],
    /// The configured step (never estimated).
    pub next: NextStep,
    pub stats: Stats,
}

impl<const N: usize> Rk4<N> {
    pub fn new(cfg: StepperConfig<N>) -> Self {
        Self {
            cfg,
            pos: Position::new(),
            f_prev: [0.0; N],
            next: NextStep::new(cfg.h, false),
            stats: Stats::default(),
        }
    }

    pub fn reset<S: System<N>>(&mut self, sys: &S, t: f64, y: [f64; N], _fresh: bool) {
        self.pos.restart(sys, t, y, &mut self.stats);
        self.f_prev = self.pos.f;
        self.next.h = self.cfg.h;
    }

    pub fn step<S: System<N>>(&mut self, sys: &S, t_end: f64, h_max: f64) -> Result<(), StepError> {
        check_budget(&self.stats, self.cfg.max_steps, self.pos.t)?;
        let mut h = self.cfg.h.min(h_max).min(self.cfg.h_max);
        if !(h > 0.0) {
            return Err(StepError::StepSizeUnderflow { t: self.pos.t, h });
        }
        let mut last = false;
        if self.pos.t + h * (1.0 + 1e-7) >= t_end {
            h = t_end - self.pos.t;
            last = true;
        }
        if h <= f64::EPSILON * self.pos.t.abs() {
            return Err(StepError::StepSizeUnderflow { t: self.pos.t, h });
        }
        let (t, y) = (self.pos.t, self.pos.y);
        let k1 = self.pos.f;
        let mut tmp = [0.0; N];
        let mut k2 = [0.0; N];
        let mut k3 = [0.0; N];
        let mut k4 = [0.0; N];
        for i in 0..N {
            tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        sys.rhs(t + 0.5 * h, &tmp, &mut k2);
        for i in 0..N {
            tmp[i] = y[i] + 0.5 * h * k2[i];
        }
        sys.rhs(t + 0.5 * h, &tmp, &mut k3);
        for i in 0..N {
            tmp[i] = y[i] + h * k3[i];
        }
        sys.rhs(t + h, &tmp, &mut k4);
        let mut ynew = [0.0; N];
        for i in 0..N {
            ynew[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        let tnew = if last { t_end } else { t + h };
        let mut fnew = [0.0; N];
        sys.rhs_step_end(tnew, &ynew, &mut fnew);
        self.stats.rhs_evals += 4;
        if !all_finite(&ynew) || !all_finite(&fnew) {
            return Err(StepError::NonFinite { t: self.pos.t });
        }
        self.stats.steps += 1;
        self.f_prev = k1;
        self.pos.advance((t, y), tnew, ynew, fnew);
        Ok(())
    }

    /// Cubic Hermite interpolation on [t_prev, t].
    pub fn dense(&self, t: f64) -> [f64; N] {
        let h = self.pos.t - self.pos.t_prev;
        if h <= 0.0 {
            return self.pos.y;
        }
        let s = (t - self.pos.t_prev) / h;
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s * s * (3.0 - 2.0 * s);
        let h11 = s * s * (s - 1.0);
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = h00 * self.pos.y_prev[i]
                + h10 * h * self.f_prev[i]
                + h01 * self.pos.y[i]
                + h11 * h * self.pos.f[i];
        }
        out
    }
}
