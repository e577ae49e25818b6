//! Integrators for small ODE systems with dense output, written for event
//! location and work accounting.
//!
//! Why our own and not a crate: the contact-impact joint needs events located
//! on each step's dense output with the integration restarted on the correct
//! side, a free-flight step limit, per-component error scales (the journal's
//! position at the scale of the clearance) and exact work counters. Among the
//! Rust crates looked at, `ode_solvers` (DOPRI5/DOP853) has no event location
//! and hands dense output only at fixed output times, `russell_ode` and
//! `diffsol` bring large dependency trees (BLAS/SUNDIALS-style machinery)
//! for what is here a 7-dimensional system. `ode_solvers` is used as the
//! outside reference in the methods lab.
//!
//! The methods (Hairer–Nørsett–Wanner I and II; coefficients are the
//! published ones):
//! - [`Method::Rk4`]: classic fixed-step Runge–Kutta, cubic Hermite dense output;
//! - [`Method::Dopri5`]: Dormand–Prince 5(4), FSAL, 4th-order dense output;
//! - [`Method::Dop853`]: Dormand–Prince 8(5,3), 7th-order dense output;
//! - [`Method::Radau5`]: Radau IIA of order 5 (3-stage implicit collocation)
//!   with simplified Newton iterations and its collocation polynomial as dense
//!   output — for stiff contact.
//!
//! Like Hairer's codes, every run counts accepted and rejected steps and
//! right-hand-side evaluations (and Jacobians / LU decompositions for the
//! implicit method), and fails with a reason instead of hanging.

// Numerical kernels index several arrays in step; `!(h > 0.0)` is meant to catch NaN.
#![allow(
    clippy::needless_range_loop,
    clippy::neg_cmp_op_on_partial_ord,
    clippy::too_many_arguments
)]

use serde::{Deserialize, Serialize};

mod control;
pub use control::Position;
pub mod dop853;
mod dop853_coef;
pub mod dopri5;
pub mod radau5;
pub mod rk4;
pub mod roots;

/// A first-order ODE system y' = f(t, y) with N components.
pub trait System<const N: usize> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);

    /// The evaluation at the end of a step (the derivative the next step
    /// starts from): a model may keep what it computed there, so that the
    /// step's outputs need no second evaluation.
    #[inline]
    fn rhs_step_end(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        self.rhs(t, y, dy)
    }
}

/// How a component enters the error norm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Scale {
    /// sc = atol + rtol · max(|y_old|, |y_new|) (the usual relative error).
    Relative,
    /// sc = atol + rtol · reference: the error is judged against a fixed
    /// magnitude (e.g. the clearance for a position).
    Fixed(f64),
    /// Not error-controlled (quadrature components that do not feed back).
    Ignore,
}

/// Tolerances: one rtol, per-component atol and scale kinds.
#[derive(Debug, Clone, Copy)]
pub struct Tolerance<const N: usize> {
    pub rtol: f64,
    pub atol: [f64; N],
    pub scale: [Scale; N],
}

impl<const N: usize> Tolerance<N> {
    pub fn uniform(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol: [atol; N],
            scale: [Scale::Relative; N],
        }
    }

    /// Weights 1/sc_i for the error norm (0 for ignored components).
    #[inline]
    pub fn weights(&self, y0: &[f64; N], y1: &[f64; N]) -> [f64; N] {
        let mut w = [0.0; N];
        for i in 0..N {
            w[i] = match self.scale[i] {
                Scale::Relative => 1.0 / (self.atol[i] + self.rtol * y0[i].abs().max(y1[i].abs())),
                Scale::Fixed(r) => 1.0 / (self.atol[i] + self.rtol * r),
                Scale::Ignore => 0.0,
            };
        }
        w
    }

    /// Number of error-controlled components.
    pub fn n_controlled(&self) -> usize {
        self.scale
            .iter()
            .filter(|s| !matches!(s, Scale::Ignore))
            .count()
            .max(1)
    }
}

/// RMS norm of `e` weighted by `w` over the controlled components.
#[inline]
pub fn wrms<const N: usize>(e: &[f64; N], w: &[f64; N], n_controlled: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..N {
        let x = e[i] * w[i];
        s += x * x;
    }
    (s / n_controlled as f64).sqrt()
}

/// Work done by an integrator.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (error test or, implicit, Newton failure).
    pub rejected: u64,
    /// Right-hand-side evaluations (including those for Jacobians and dense output).
    pub rhs_evals: u64,
    /// Jacobian evaluations (implicit method).
    pub jacobians: u64,
    /// LU decompositions (implicit method).
    pub lu_decompositions: u64,
    /// Newton iterations that failed to converge (implicit method).
    pub newton_failures: u64,
    /// Accepted steps at which the explicit method's stiffness test fired.
    pub stiff_steps: u64,
}

impl Stats {
    pub fn add(&mut self, o: &Stats) {
        self.steps += o.steps;
        self.rejected += o.rejected;
        self.rhs_evals += o.rhs_evals;
        self.jacobians += o.jacobians;
        self.lu_decompositions += o.lu_decompositions;
        self.newton_failures += o.newton_failures;
        self.stiff_steps += o.stiff_steps;
    }
}

/// Why a step could not be taken.
#[derive(Debug, Clone, PartialEq, thiserror::Error, Serialize)]
pub enum StepError {
    #[error("step size underflow at t = {t:.9e} s (h = {h:.3e} s)")]
    StepSizeUnderflow { t: f64, h: f64 },
    #[error("too many steps ({steps}) before t = {t:.9e} s")]
    TooManySteps { t: f64, steps: u64 },
    #[error("non-finite state at t = {t:.9e} s")]
    NonFinite { t: f64 },
    #[error("Newton iteration failed repeatedly at t = {t:.9e} s (h = {h:.3e} s)")]
    NewtonFailure { t: f64, h: f64 },
}

/// The integration methods offered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    Rk4,
    Dopri5,
    Dop853,
    Radau5,
}

impl Method {
    pub const ALL: [Method; 4] = [Method::Rk4, Method::Dopri5, Method::Dop853, Method::Radau5];

    pub fn name(self) -> &'static str {
        match self {
            Method::Rk4 => "rk4",
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Radau5 => "radau5",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "rk4" => Some(Method::Rk4),
            "dopri5" | "dopri54" | "rk45" => Some(Method::Dopri5),
            "dop853" | "dopri853" => Some(Method::Dop853),
            "radau5" | "radau" | "radau_iia" => Some(Method::Radau5),
            _ => None,
        }
    }

    /// Classical order of the method (of the propagated solution).
    pub fn order(self) -> u32 {
        match self {
            Method::Rk4 => 4,
            Method::Dopri5 => 5,
            Method::Dop853 => 8,
            Method::Radau5 => 5,
        }
    }

    /// True for fixed-step methods (step size given, no error control).
    pub fn is_fixed_step(self) -> bool {
        matches!(self, Method::Rk4)
    }

    pub fn is_implicit(self) -> bool {
        matches!(self, Method::Radau5)
    }
}

/// Settings shared by all steppers.
#[derive(Debug, Clone, Copy)]
pub struct StepperConfig<const N: usize> {
    pub tol: Tolerance<N>,
    /// Fixed step for RK4; initial-step hint (0 = automatic) for the others.
    pub h: f64,
    /// Largest step allowed.
    pub h_max: f64,
    /// Maximum number of steps (accepted + rejected) before giving up.
    pub max_steps: u64,
    /// Take exactly `h` every step, without error control (to measure a
    /// formula's order and its stability limit; RK4 is always fixed-step).
    pub fixed: bool,
}

/// One of the steppers, dispatched statically.
#[derive(Debug, Clone)]
pub enum Stepper<const N: usize> {
    Rk4(rk4::Rk4<N>),
    Dopri5(dopri5::Dopri5<N>),
    Dop853(dop853::Dop853<N>),
    Radau5(Box<radau5::Radau5<N>>),
}

macro_rules! dispatch {
    ($self:expr, $s:ident => $e:expr) => {
        match $self {
            Stepper::Rk4($s) => $e,
            Stepper::Dopri5($s) => $e,
            Stepper::Dop853($s) => $e,
            Stepper::Radau5($s) => $e,
        }
    };
}

impl<const N: usize> Stepper<N> {
    pub fn new(method: Method, cfg: StepperConfig<N>) -> Self {
        match method {
            Method::Rk4 => Stepper::Rk4(rk4::Rk4::new(cfg)),
            Method::Dopri5 => Stepper::Dopri5(dopri5::Dopri5::new(cfg)),
            Method::Dop853 => Stepper::Dop853(dop853::Dop853::new(cfg)),
            Method::Radau5 => Stepper::Radau5(Box::new(radau5::Radau5::new(cfg))),
        }
    }

    /// (Re)starts at (t, y). History that assumed a smooth right-hand side
    /// (FSAL derivative, Jacobian) is dropped; the step size is kept as a hint
    /// unless `fresh_step` asks for a new initial step estimate.
    pub fn reset<S: System<N>>(&mut self, sys: &S, t: f64, y: [f64; N], fresh_step: bool) {
        dispatch!(self, s => s.reset(sys, t, y, fresh_step))
    }

    /// Proposes the size of the next step (after a reset: instead of the
    /// automatic initial-step estimate). Ignored by fixed-step runs.
    pub fn set_next_step(&mut self, h: f64) {
        if h > 0.0 && h.is_finite() {
            dispatch!(self, s => if !s.cfg.fixed { s.next.propose(h) })
        }
    }

    /// Takes one accepted step ending at most at `t_end`, no longer than `h_max`.
    pub fn step<S: System<N>>(&mut self, sys: &S, t_end: f64, h_max: f64) -> Result<(), StepError> {
        dispatch!(self, s => s.step(sys, t_end, h_max))
    }

    /// Current time (end of the last accepted step).
    pub fn t(&self) -> f64 {
        dispatch!(self, s => s.pos.t)
    }

    /// Start of the last accepted step.
    pub fn t_prev(&self) -> f64 {
        dispatch!(self, s => s.pos.t_prev)
    }

    pub fn y(&self) -> &[f64; N] {
        dispatch!(self, s => &s.pos.y)
    }

    /// Makes the last step's dense output available (DOP853 computes its
    /// three extra stages lazily; the others have it already).
    pub fn prepare_dense<S: System<N>>(&mut self, sys: &S) {
        if let Stepper::Dop853(s) = self {
            s.prepare_dense(sys)
        }
    }

    /// Dense output on [t_prev, t] (after [`Stepper::prepare_dense`]).
    pub fn dense(&self, t: f64) -> [f64; N] {
        dispatch!(self, s => s.dense(t))
    }

    pub fn stats(&self) -> &Stats {
        dispatch!(self, s => &s.stats)
    }

    /// Step size proposed for the next step.
    pub fn h_next(&self) -> f64 {
        dispatch!(self, s => s.next.h)
    }
}

#[inline]
pub(crate) fn all_finite<const N: usize>(y: &[f64; N]) -> bool {
    y.iter().all(|v| v.is_finite())
}

#[cfg(test)]
pub(crate) mod test_systems {
    use super::*;

    /// y'' = −y (harmonic oscillator): y = cos t.
    pub struct Harmonic;
    impl System<2> for Harmonic {
        fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = y[1];
            dy[1] = -y[0];
        }
    }

    /// A nonlinear, non-autonomous scalar problem with a known solution:
    /// y' = −2 t y² , y(0) = 1  ⇒  y = 1 / (1 + t²); plus the linear y2' = cos t ⇒ y2 = sin t.
    pub struct Rational;
    impl System<2> for Rational {
        fn rhs(&self, t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = -2.0 * t * y[0] * y[0];
            dy[1] = t.cos();
        }
    }

    /// Van der Pol with stiffness parameter mu.
    pub struct VanDerPol(pub f64);
    impl System<2> for VanDerPol {
        fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = y[1];
            dy[1] = self.0 * ((1.0 - y[0] * y[0]) * y[1]) - y[0];
        }
    }

    pub fn run<const N: usize, S: System<N>>(
        method: Method,
        sys: &S,
        y0: [f64; N],
        t_end: f64,
        rtol: f64,
        h: f64,
    ) -> (Stepper<N>, [f64; N]) {
        let cfg = StepperConfig {
            tol: Tolerance::uniform(rtol, rtol),
            h,
            h_max: f64::INFINITY,
            max_steps: 10_000_000,
            fixed: h > 0.0,
        };
        let mut st = Stepper::new(method, cfg);
        st.reset(sys, 0.0, y0, true);
        while st.t() < t_end {
            st.step(sys, t_end, f64::INFINITY).expect("step");
        }
        let y = *st.y();
        (st, y)
    }
}

#[cfg(test)]
mod tests {
    use super::test_systems::*;
    use super::*;

    /// Observed convergence order on a smooth problem with a closed-form
    /// solution: every formula run with fixed steps h = T/n, and the slope of
    /// log(error) against log(h) fitted by least squares. (The mechanism's
    /// own smooth scene is checked in tests/dynamics_convergence.rs.)
    fn observed_order(method: Method) -> f64 {
        // The harmonic oscillator over ten time units, y = cos t.
        let t_end: f64 = 10.0;
        let ns: &[usize] = match method {
            Method::Dop853 => &[10, 12, 14, 16, 20],
            Method::Rk4 => &[50, 100, 200, 400],
            _ => &[40, 60, 80, 100, 140],
        };
        let mut pts = Vec::new();
        for &n in ns {
            let h = t_end / n as f64;
            let (st, y) = run(method, &Harmonic, [1.0, 0.0], t_end, 1e-14, h);
            assert_eq!(st.stats().steps, n as u64);
            let err = (y[0] - t_end.cos()).abs().max((y[1] + t_end.sin()).abs());
            eprintln!("{method:?} n={n} err={err:.3e}");
            pts.push((h.ln(), err.ln()));
        }
        let n = pts.len() as f64;
        let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
        let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        sxy / sxx
    }

    /// Adaptive runs: the global error follows the tolerance.
    #[test]
    fn adaptive_error_follows_tolerance() {
        let t_end: f64 = 3.0;
        let exact = [1.0 / (1.0 + t_end * t_end), t_end.sin()];
        for m in [Method::Dopri5, Method::Dop853, Method::Radau5] {
            let mut prev_steps = 0;
            for rtol in [1e-4, 1e-6, 1e-8, 1e-10] {
                let (st, y) = run(m, &Rational, [1.0, 0.0], t_end, rtol, 0.0);
                let err = (y[0] - exact[0]).abs().max((y[1] - exact[1]).abs());
                assert!(err < 30.0 * rtol, "{m:?} rtol {rtol}: error {err}");
                assert!(
                    st.stats().steps >= prev_steps,
                    "{m:?}: fewer steps at tighter tolerance"
                );
                prev_steps = st.stats().steps;
            }
        }
    }

    #[test]
    fn rk4_order_is_four() {
        let p = observed_order(Method::Rk4);
        assert!((p - 4.0).abs() <= 0.3, "observed {p}");
    }

    #[test]
    fn dopri5_order_is_five() {
        let p = observed_order(Method::Dopri5);
        assert!((p - 5.0).abs() <= 0.3, "observed {p}");
    }

    #[test]
    fn dop853_order_is_eight() {
        let p = observed_order(Method::Dop853);
        assert!((p - 8.0).abs() <= 0.3, "observed {p}");
    }

    #[test]
    fn radau5_order_is_five() {
        let p = observed_order(Method::Radau5);
        assert!((p - 5.0).abs() <= 0.3, "observed {p}");
    }

    /// Dense output agrees with the exact solution inside steps.
    #[test]
    fn dense_output_accuracy() {
        for (method, tol) in [
            (Method::Rk4, 1e-6),
            (Method::Dopri5, 1e-7),
            (Method::Dop853, 1e-9),
            (Method::Radau5, 1e-6),
        ] {
            let cfg = StepperConfig {
                tol: Tolerance::uniform(1e-10, 1e-10),
                h: 0.01,
                h_max: f64::INFINITY,
                max_steps: 1_000_000,
                fixed: method == Method::Rk4,
            };
            let mut st = Stepper::new(method, cfg);
            st.reset(&Harmonic, 0.0, [1.0, 0.0], true);
            let mut worst: f64 = 0.0;
            while st.t() < 10.0 {
                st.step(&Harmonic, 10.0, f64::INFINITY).unwrap();
                st.prepare_dense(&Harmonic);
                for k in 1..4 {
                    let t = st.t_prev() + (st.t() - st.t_prev()) * k as f64 / 4.0;
                    let y = st.dense(t);
                    worst = worst.max((y[0] - t.cos()).abs());
                }
                let y = st.dense(st.t());
                assert!(
                    (y[0] - st.y()[0]).abs() < 1e-14,
                    "{method:?} dense at step end"
                );
            }
            assert!(worst < tol, "{method:?}: dense error {worst}");
        }
    }

    /// Radau IIA handles a stiff Van der Pol oscillator in few steps where an
    /// explicit method needs many.
    #[test]
    fn radau5_on_stiff_van_der_pol() {
        let sys = VanDerPol(1000.0);
        let (st, y) = run(Method::Radau5, &sys, [2.0, -0.66], 2.0, 1e-6, 0.0);
        let (_, y_ref) = run(Method::Dop853, &sys, [2.0, -0.66], 2.0, 1e-12, 0.0);
        assert!(
            (y[0] - y_ref[0]).abs() < 1e-5,
            "y = {y:?}, reference {y_ref:?}"
        );
        assert!(
            (y[1] - y_ref[1]).abs() < 1e-5 * (1.0 + y_ref[1].abs()),
            "y = {y:?}, reference {y_ref:?}"
        );
        assert!(st.stats().steps < 2000, "steps {}", st.stats().steps);
        let (sd, _) = run(Method::Dopri5, &sys, [2.0, -0.66], 2.0, 1e-6, 0.0);
        assert!(sd.stats().rhs_evals > 5 * st.stats().rhs_evals);
        assert!(
            sd.stats().stiff_steps > 0,
            "stiffness detection did not fire"
        );
    }

    /// Failures are reported, not hung on.
    #[test]
    fn failures_are_reported() {
        struct Blowup;
        impl System<1> for Blowup {
            fn rhs(&self, _t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
                dy[0] = y[0] * y[0];
            }
        }
        for m in Method::ALL {
            let cfg = StepperConfig {
                tol: Tolerance::uniform(1e-8, 1e-8),
                h: 1e-3,
                h_max: f64::INFINITY,
                max_steps: 100_000,
                fixed: false,
            };
            let mut st = Stepper::new(m, cfg);
            st.reset(&Blowup, 0.0, [1.0], true);
            let mut res = Ok(());
            while st.t() < 2.0 {
                res = st.step(&Blowup, 2.0, f64::INFINITY);
                if res.is_err() {
                    break;
                }
            }
            let err = res.expect_err("blow-up at t = 1 must fail");
            assert!(st.t() < 1.01, "{m:?} went past the singularity: {err}");
        }
    }
}
