//! The step-size scaffolding the steppers share, as in Hairer's codes: the
//! starting step (HINIT), the guards before every trial step (the work
//! budget, a step too small for the clock, the last step clipped onto
//! `t_end`) and the stiffness monitor of the explicit methods. Each stepper
//! keeps its own stages, error estimate and controller constants; what is
//! here is the same logic in all of them, written once.

use super::{Stats, StepError, StepperConfig, System, Tolerance, wrms};

/// The step-size controller of Hairer's explicit codes (DOPRI5, DOP853):
/// the new step from the error norm with Lund's stabilisation (β; 0 for
/// DOP853's plain controller), the ratio bounds, the last accepted error,
/// and no growth right after a rejection.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PiControl {
    safe: f64,
    /// Smallest and largest step ratio hnew/h.
    fac1: f64,
    fac2: f64,
    /// Exponent of the error (1/(q+1) − 0.75 β).
    expo1: f64,
    beta: f64,
    facold: f64,
    rejected_last: bool,
}

impl PiControl {
    pub(crate) const fn new(safe: f64, fac1: f64, fac2: f64, expo1: f64, beta: f64) -> Self {
        Self {
            safe,
            fac1,
            fac2,
            expo1,
            beta,
            facold: 1e-4,
            rejected_last: false,
        }
    }

    /// Forgets the history (a restart: no last error, no rejection).
    pub(crate) fn restart(&mut self) {
        self.facold = 1e-4;
        self.rejected_last = false;
    }

    /// err^expo1 and the step it proposes after a step of `h` (`fixed`:
    /// the fixed step of a non-adaptive run).
    pub(crate) fn propose(&self, err: f64, h: f64, fixed: Option<f64>) -> (f64, f64) {
        let fac11 = err.powf(self.expo1);
        // facold^0 is exactly 1: DOP853 skips the power (one per step).
        let lund = if self.beta == 0.0 {
            1.0
        } else {
            self.facold.powf(self.beta)
        };
        let fac = (fac11 / lund / self.safe).clamp(1.0 / self.fac2, 1.0 / self.fac1);
        (fac11, fixed.unwrap_or(h / fac))
    }

    /// The step after an accepted one with error `err`: `hnew` from
    /// [`propose`](Self::propose), not larger than `h` after a rejection.
    pub(crate) fn accept(&mut self, err: f64, h: f64, hnew: f64) -> f64 {
        self.facold = err.max(1e-4);
        let hnew = if self.rejected_last {
            hnew.min(h)
        } else {
            hnew
        };
        self.rejected_last = false;
        hnew
    }

    /// The retry after a step rejected for its error (`fac11` from
    /// [`propose`](Self::propose)).
    pub(crate) fn reject(&mut self, h: f64, fac11: f64) -> f64 {
        self.rejected_last = true;
        h / (1.0 / self.fac1).min(fac11 / self.safe)
    }

    /// The retry after a step at `t` that left the finite numbers: as
    /// small as the controller allows; `NonFinite` once that step is lost
    /// in the round-off of `t`.
    pub(crate) fn reject_non_finite(&mut self, h: f64, t: f64) -> Result<f64, StepError> {
        self.rejected_last = true;
        let h = h * self.fac1;
        if h <= t.abs() * f64::EPSILON * 10.0 {
            return Err(StepError::NonFinite { t });
        }
        Ok(h)
    }
}

/// Where a stepper is: the current point and its derivative, and the start
/// of the last step (the interval its dense output covers).
#[derive(Debug, Clone)]
pub struct Position<const N: usize> {
    pub t: f64,
    pub t_prev: f64,
    pub y: [f64; N],
    pub y_prev: [f64; N],
    /// f(t, y).
    pub f: [f64; N],
}

impl<const N: usize> Position<N> {
    pub(crate) fn new() -> Self {
        Position {
            t: 0.0,
            t_prev: 0.0,
            y: [0.0; N],
            y_prev: [0.0; N],
            f: [0.0; N],
        }
    }

    /// Moves to the end of an accepted step from (`from`, `y`): the step's
    /// start becomes the dense output's left end.
    pub(crate) fn advance(&mut self, from: (f64, [f64; N]), t: f64, y: [f64; N], f: [f64; N]) {
        self.t_prev = from.0;
        self.y_prev = from.1;
        self.t = t;
        self.y = y;
        self.f = f;
    }

    /// Restarts at (t, y) with no last step; f(t, y) is evaluated and
    /// counted.
    pub(crate) fn restart<S: System<N>>(
        &mut self,
        sys: &S,
        t: f64,
        y: [f64; N],
        stats: &mut Stats,
    ) {
        self.t = t;
        self.t_prev = t;
        self.y = y;
        self.y_prev = y;
        sys.rhs(t, &y, &mut self.f);
        stats.rhs_evals += 1;
    }
}

/// The size of the next step, and whether it must first be estimated
/// (after a start, or a restart that asks for it or has no size to go on).
/// The adaptive steppers keep it alike: the accepted step's controller
/// sets `h`, a restart keeps it as a hint, and the first step of a run is
/// the configured one or Hairer's estimate.
#[derive(Debug, Clone, Copy)]
pub struct NextStep {
    pub h: f64,
    pub(crate) fresh: bool,
}

impl NextStep {
    /// Before a run: `h` (the configured step, 0 for none) is estimated
    /// afresh unless `fresh` is false (a fixed-step method).
    pub(crate) fn new(h: f64, fresh: bool) -> Self {
        NextStep { h, fresh }
    }

    /// A restart keeps the last size as a hint unless `fresh_step` asks for
    /// a new estimate or there is none.
    pub(crate) fn restart(&mut self, fresh_step: bool) {
        if fresh_step || !(self.h > 0.0) {
            self.fresh = true;
        }
    }

    /// The caller's proposal replaces the estimate.
    pub(crate) fn propose(&mut self, h: f64) {
        self.h = h;
        self.fresh = false;
    }

    /// The step to try from `at`, at most `h_max`: estimated first when
    /// fresh (the configured step, always for a fixed step, else Hairer's
    /// estimate for a method of order `order`; its evaluation counted).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn size<const N: usize, S: System<N>>(
        &mut self,
        cfg: &StepperConfig<N>,
        tol: &Tolerance<N>,
        sys: &S,
        at: &Position<N>,
        order: u32,
        h_max: f64,
        stats: &mut Stats,
    ) -> f64 {
        if self.fresh {
            self.h = if cfg.h > 0.0 || cfg.fixed {
                cfg.h
            } else {
                initial_step(
                    sys,
                    at.t,
                    &at.y,
                    &at.f,
                    tol,
                    order,
                    h_max,
                    &mut stats.rhs_evals,
                )
            };
            self.fresh = false;
        }
        self.h.min(h_max)
    }
}

/// Fails once the run has used its step budget (accepted + rejected):
/// a run reports where it stopped instead of spinning.
pub(crate) fn check_budget(stats: &Stats, max_steps: u64, t: f64) -> Result<(), StepError> {
    if stats.steps + stats.rejected >= max_steps {
        return Err(StepError::TooManySteps {
            t,
            steps: stats.steps,
        });
    }
    Ok(())
}

/// The guards before a trial step of an error-controlled method from `t`
/// with step `h`: the budget, a step below the clock's resolution (or not
/// a positive number), and the step stretched or cut to land on `t_end`
/// when it comes within 1 % of it. Returns the step to try and whether it
/// is the last.
pub(crate) fn trial_step(
    stats: &Stats,
    max_steps: u64,
    t: f64,
    h: f64,
    t_end: f64,
) -> Result<(f64, bool), StepError> {
    check_budget(stats, max_steps, t)?;
    if 0.1 * h.abs() <= t.abs() * f64::EPSILON || !(h > 0.0) {
        return Err(StepError::StepSizeUnderflow { t, h });
    }
    if t + 1.01 * h >= t_end {
        Ok((t_end - t, true))
    } else {
        Ok((h, false))
    }
}

/// f(t, y) at the end of an accepted step, counted; a derivative that is
/// not finite there fails the run at `t`.
pub(crate) fn derivative_at_end<const N: usize, S: System<N>>(
    sys: &S,
    t: f64,
    y: &[f64; N],
    stats: &mut Stats,
) -> Result<[f64; N], StepError> {
    let mut f = [0.0; N];
    sys.rhs_step_end(t, y, &mut f);
    stats.rhs_evals += 1;
    if !super::all_finite(&f) {
        return Err(StepError::NonFinite { t });
    }
    Ok(f)
}

/// Hairer's stiffness detection for explicit methods: every 1000th
/// accepted step (and each step while stiffness is suspected) estimates
/// h·|λ| from two stages evaluated at the same time, and counts a step
/// as stiff after 15 estimates in a row beyond the method's stability
/// boundary (6 below it clear the suspicion).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StiffnessMonitor {
    suspected: u32,
    clear: u32,
}

impl StiffnessMonitor {
    const EVERY: u64 = 1000;

    /// Observes the accepted step `h`: `f_pair` two right-hand sides and
    /// `y_pair` the states they were evaluated at; `boundary` is the
    /// method's h·|λ| stability limit along the negative real axis.
    pub(crate) fn observe<const N: usize>(
        &mut self,
        h: f64,
        f_pair: (&[f64; N], &[f64; N]),
        y_pair: (&[f64; N], &[f64; N]),
        boundary: f64,
        stats: &mut Stats,
    ) {
        if !stats.steps.is_multiple_of(Self::EVERY) && self.suspected == 0 {
            return;
        }
        let mut num = 0.0;
        let mut den = 0.0;
        for i in 0..N {
            num += (f_pair.0[i] - f_pair.1[i]).powi(2);
            den += (y_pair.0[i] - y_pair.1[i]).powi(2);
        }
        let hlamb = if den > 0.0 {
            h * (num / den).sqrt()
        } else {
            0.0
        };
        if hlamb > boundary {
            self.clear = 0;
            self.suspected += 1;
            if self.suspected >= 15 {
                stats.stiff_steps += 1;
            }
        } else {
            self.clear += 1;
            if self.clear >= 6 {
                self.suspected = 0;
            }
        }
    }
}

/// Initial step size (Hairer's HINIT) for a method of order `p`.
pub(crate) fn initial_step<const N: usize, S: System<N>>(
    sys: &S,
    t: f64,
    y: &[f64; N],
    f0: &[f64; N],
    tol: &Tolerance<N>,
    p: u32,
    h_max: f64,
    evals: &mut u64,
) -> f64 {
    let w = tol.weights(y, y);
    let n = tol.n_controlled();
    let d0 = wrms(y, &w, n);
    let d1 = wrms(f0, &w, n);
    let mut h0 = if d0 < 1e-10 || d1 < 1e-10 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(h_max);
    let mut y1 = [0.0; N];
    for i in 0..N {
        y1[i] = y[i] + h0 * f0[i];
    }
    let mut f1 = [0.0; N];
    sys.rhs(t + h0, &y1, &mut f1);
    *evals += 1;
    let mut df = [0.0; N];
    for i in 0..N {
        df[i] = f1[i] - f0[i];
    }
    let d2 = wrms(&df, &w, n) / h0;
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / dm).powf(1.0 / (p as f64 + 1.0))
    };
    (100.0 * h0).min(h1).min(h_max)
}
