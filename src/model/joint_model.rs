//! What the event-located integration loop (`sim::clearance_run`) needs of
//! a model: one trait for the constant-speed clearance model (level
//! `clearance`) and the motor-driven models (level `motor`, with or without
//! clearance), so that contact events, the double-crossing guard, peaks,
//! curves, budgets and the stall event are written once.
//!
//! The state's layout is the model's own; the loop reaches into it only
//! through these methods and the two quadrature indices. The mode and the
//! outputs every such model reports live here (below the models).

use super::contact::ProcessMode;
use crate::solver::Tolerance;
use serde::Serialize;
use std::cell::Cell;

/// Free flight or contact, and what the part does to the pin bar (stick
/// law), as set by the event logic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Mode {
    pub in_contact: bool,
    /// δ̇ at the onset of the current contact (m/s).
    pub approach: f64,
    /// Stick law: resisting down or up, or holding (regularized: unused).
    pub process: ProcessMode,
}

/// Everything the model knows at one instant (for outputs and figures).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Outputs {
    pub t: f64,
    pub theta2: f64,
    /// Crank speed ω2 (rad/s) and acceleration α2 (rad/s²).
    pub omega2: f64,
    pub alpha2: f64,
    /// Torque of the motor at its shaft (N·m); NaN without a motor.
    pub motor_torque: f64,
    /// Stroke s = x4 − x4_TDC (m), velocity (m/s), acceleration (m/s²).
    pub s: f64,
    pub v4: f64,
    pub a4: f64,
    pub alpha3: f64,
    /// Contact normal force (N) and friction (N, on the pin bar along t).
    pub f_n: f64,
    pub f_t: f64,
    /// Tangential slip speed at the contact point (m/s), v_t of model.md:
    /// (v_P − v_B)·t − ω3·R_B, whether or not in contact (Archard wear
    /// integrates F_N·|v_t|).
    pub v_slip: f64,
    /// Drive torque (N·m).
    pub m12: f64,
    /// Penetration δ = e − c (m) and its rate (m/s).
    pub delta: f64,
    pub delta_dot: f64,
    /// Eccentricity e = P − B (m).
    pub ecc: [f64; 2],
    /// Process force on the pin bar along x (N); the load cell reads −this.
    pub process_force: f64,
    /// The ideal mechanism at the same crank angle.
    pub ideal_s: f64,
    pub ideal_v: f64,
    pub ideal_a: f64,
    pub ideal_m12: f64,
    pub ideal_process_force: f64,
}

impl Outputs {
    /// A rigid mechanism's outputs (no clearance: the joint force is the
    /// ideal one, no penetration, and the "ideal" columns equal the actual
    /// ones): the closed-form levels and the motor level with c = 0.
    pub fn rigid(
        t: f64,
        (theta2, omega2, alpha2): (f64, f64, f64),
        motor_torque: f64,
        s: f64,
        f: &super::kinetostatics::IdealForces,
    ) -> Self {
        Self {
            t,
            theta2,
            omega2,
            alpha2,
            motor_torque,
            s,
            v4: f.pose.v4,
            a4: f.pose.a4,
            alpha3: f.pose.alpha3,
            f_n: f.joint_force_b(),
            f_t: 0.0,
            v_slip: f64::NAN,
            m12: f.m12,
            delta: 0.0,
            delta_dot: 0.0,
            ecc: [0.0, 0.0],
            process_force: f.process_force,
            ideal_s: s,
            ideal_v: f.pose.v4,
            ideal_a: f.pose.a4,
            ideal_m12: f.m12,
            ideal_process_force: f.process_force,
        }
    }
}

/// A mechanism model integrated by the event loop.
pub trait JointModel<const N: usize>: crate::solver::System<N> + Clone {
    /// Index of the quadrature Q_s = ∫(s − s_ideal) dt in the state.
    const Q_S: usize;
    /// Index of the quadrature Q_M = ∫(M12 − M12_ideal)² dt.
    const Q_DM2: usize;

    /// Whether the rod–pin-bar joint has a clearance (contact events). A
    /// model without one never leaves free flight and takes no step limit.
    fn has_joint(&self) -> bool;
    fn mode(&self) -> Mode;
    fn set_mode(&mut self, mode: Mode);
    /// Turns the quadratures (and the ideal mechanism they compare with) on
    /// or off (off during warm-up, where nothing is reported).
    fn set_quadratures(&mut self, on: bool);
    /// Radial clearance c (m) and bearing radius R_B (m).
    fn clearance(&self) -> f64;
    fn rb(&self) -> f64;
    /// x4 at top dead centre (m).
    fn x4_tdc(&self) -> f64;
    /// The integrator's tolerance: positions at the scale of the clearance.
    fn tolerance(&self, rtol: f64, atol: f64) -> Tolerance<N>;
    /// Start state: journal centred, ideal velocities, the pin bar moved by `dx4`.
    fn initial_state(&self, dx4: f64) -> [f64; N];
    /// Crank angle θ2 (rad) at (t, y).
    fn theta2(&self, t: f64, y: &[f64; N]) -> f64;
    /// Penetration δ and its rate (m, m/s); cheap (no forces).
    fn penetration(&self, t: f64, y: &[f64; N]) -> (f64, f64);
    /// |v_P − v_B| (m/s), for the free-flight step limit.
    fn relative_speed(&self, t: f64, y: &[f64; N]) -> f64;
    /// Stroke and speed deviations from the ideal mechanism at the same
    /// crank angle (and crank speed): (s − s_ideal, v4 − v_ideal).
    fn deviation(&self, t: f64, y: &[f64; N]) -> (f64, f64);
    /// A first step after a contact onset (see `ClearanceModel::onset_step`).
    fn onset_step(&self, approach: f64, tol_pos: f64) -> f64;
    /// Scale of the crank-driven relative acceleration (m/s²).
    fn accel_scale(&self) -> f64;
    /// Everything at one instant in a given contact mode.
    fn outputs_in(&self, mode: Mode, t: f64, y: &[f64; N]) -> Outputs;
    /// The stroke s (m from top dead centre) and the process force (N) at
    /// one instant in a given contact mode: the [`Outputs::s`] and
    /// [`Outputs::process_force`] of [`JointModel::outputs_in`], which a
    /// model may compute without the rest.
    fn stroke_and_process_in(&self, mode: Mode, t: f64, y: &[f64; N]) -> (f64, f64) {
        let o = self.outputs_in(mode, t, y);
        (o.s, o.process_force)
    }
    /// The right-hand side in a given contact mode.
    fn rhs_in(&self, mode: Mode, t: f64, y: &[f64; N], dy: &mut [f64; N]);
    /// When the crank is free (a motor drives it): its speed ω2 less the
    /// stall speed (rad/s); the run stops with a stall when this reaches
    /// zero. None at constant speed.
    fn stall_margin(&self, y: &[f64; N]) -> Option<f64>;
    /// Longest step (s): a model whose steps are not limited by contact
    /// (no joint) keeps them short enough for the peak search.
    fn max_step(&self) -> f64 {
        f64::INFINITY
    }

    fn outputs(&self, t: f64, y: &[f64; N]) -> Outputs {
        self.outputs_in(self.mode(), t, y)
    }

    /// The stick law's event function in `mode` at (t, y): the run switches
    /// the process mode where it goes from positive to ≤ 0 (None: the
    /// regularized law, no such events).
    fn process_event(&self, _mode: Mode, _t: f64, _y: &[f64; N]) -> Option<f64> {
        None
    }
    /// The process mode after such an event at (t, y); may set the pin
    /// bar's speed to exactly 0 in `y`.
    fn process_switch(&self, mode: Mode, _t: f64, _y: &mut [f64; N]) -> ProcessMode {
        mode.process
    }
    /// The outputs at (t, y) in `mode` if the stepper's last end-of-step
    /// evaluation computed them (see [`EndCache`]).
    fn cached_end(&self, _mode: Mode, _t: f64, _y: &[f64; N]) -> Option<Outputs> {
        None
    }
}

/// The outputs a model computed in its last end-of-step evaluation
/// (`System::rhs_step_end`), kept for the step's figures: one evaluation
/// per step less.
#[derive(Debug, Clone, Default)]
pub struct EndCache<const N: usize> {
    last: Cell<Option<EndOfStep<N>>>,
}

/// (t, y, mode, outputs) of an end-of-step evaluation.
type EndOfStep<const N: usize> = (f64, [f64; N], Mode, Outputs);

impl<const N: usize> EndCache<N> {
    #[inline]
    pub fn store(&self, t: f64, y: &[f64; N], mode: Mode, o: Outputs) {
        self.last.set(Some((t, *y, mode, o)));
    }

    /// The kept outputs if they are those of (t, y) in `mode`.
    #[inline]
    pub fn get(&self, t: f64, y: &[f64; N], mode: Mode) -> Option<Outputs> {
        match self.last.get() {
            Some((tc, yc, mc, o)) if tc == t && yc == *y && mc == mode => Some(o),
            _ => None,
        }
    }
}

/// A model frozen in one contact mode (to rebuild a past step's dense
/// output after the mode has changed).
pub struct InMode<'a, M> {
    pub model: &'a M,
    pub mode: Mode,
}

impl<M: JointModel<N>, const N: usize> crate::solver::System<N> for InMode<'_, M> {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        self.model.rhs_in(self.mode, t, y, dy);
    }
}
