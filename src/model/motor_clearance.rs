//! Level `motor` with a clearance joint (c > 0): the clearance ODE of
//! model.md with the crank free — θ2 and ω2 join the state, and the crank
//! pin's acceleration carries α2: a_A = −r ω2² (cos θ2, sin θ2) + r α2
//! (−sin θ2, cos θ2).
//!
//! α2 couples the crank and the rod through the pin A. The contact force
//! depends on positions and velocities only, so with α2 unknown the rod's
//! equation gives α3 = α3⁰ + k3 α2 and the drive torque M12 = M12⁰ + S α2
//! (S: the crank's I_O plus the rod's reaction to the crank pin's
//! tangential acceleration), and the crank's balance J_d α2 = M_drive − M12
//! gives α2 = (M_drive − M12⁰) / (J_d + S). The pin bar's equation does not
//! see α2 (it feels the rod only through the contact).
//!
//! The summary's deviations compare with the ideal mechanism at the same
//! crank angle, speed and acceleration: what the clearance adds, the ripple
//! being reported on its own.
//!
//! State: (θ3, ω3, x4, v4, Q_s, Q_M) as the clearance level, then the
//! drive's part (model/motor.rs).

use super::clearance::{
    ClearanceModel, Mode, OMEGA3, Outputs, Q_DM2, Q_S, RodAndBar, THETA3, V4, X4, joint_outputs,
    stick_event, stick_switch,
};
use super::contact::ProcessMode;
use super::joint_model::{EndCache, JointModel};
use super::kinetostatics::{Inertia, cross};
use super::motor::*;
use super::params::Params;
use crate::solver::{Scale, System, Tolerance};

/// Base index of the drive's part.
pub const BASE: usize = 6;
/// Dimension of the state.
pub const DIM: usize = BASE + D_LEN;
pub const THETA2: usize = BASE + D_THETA2;
pub const OMEGA2: usize = BASE + D_OMEGA2;

/// The motor-driven clearance mechanism.
#[derive(Debug, Clone)]
pub struct MotorClearanceModel {
    /// The constant-speed model: geometry, contact law, loads (its own
    /// ω and θ0 are not used).
    pub inner: ClearanceModel,
    pub drive: MotorDrive,
    end: EndCache<DIM>,
}

impl MotorClearanceModel {
    pub fn new(p: &Params) -> Self {
        Self {
            inner: ClearanceModel::new(p),
            drive: MotorDrive::of(p),
            end: EndCache::default(),
        }
    }

    #[inline(always)]
    fn joint_state(y: &[f64; DIM]) -> [f64; 4] {
        [y[THETA3], y[OMEGA3], y[X4], y[V4]]
    }

    /// Derivatives and outputs in a contact mode.
    #[inline(always)]
    pub fn evaluate_in(&self, mode: Mode, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) -> Outputs {
        let m = &self.inner;
        let theta2 = y[THETA2];
        let w = y[OMEGA2];
        let (s2, c2) = m.sc2.get(theta2);
        let r = m.geom.r;
        let Inertia { m3, lc3, .. } = m.inertia;
        let (theta3, omega3, x4, v4) = (y[THETA3], y[OMEGA3], y[X4], y[V4]);
        let (s3, c3) = m.sc3.get(theta3);
        // Crank pin A; its acceleration without α2, and per unit α2.
        let a = [r * c2, r * s2];
        let va = [-r * w * s2, r * w * c2];
        let aa0 = [-r * w * w * c2, -r * w * w * s2];
        let e2 = [-r * s2, r * c2];
        let joint = m.joint(mode, a, va, s3, c3, omega3, x4, v4);
        // Rod, pin bar and M12 without α2: α3 = α3⁰ + k3 α2, M12 = M12⁰ + S α2.
        let rb0 = m.rod_and_bar(mode, &joint, a, aa0, (s2, c2), (s3, c3), omega3, x4, v4);
        let u3 = [c3, s3];
        let k3 = -m3 * lc3 * cross(u3, e2) * m.inv_j_a;
        let da_g3 = [e2[0] - lc3 * k3 * s3, e2[1] + lc3 * k3 * c3];
        let s_inertia = m.inertia.i_o() + m3 * cross(a, da_g3);
        // The crank's balance.
        let (t_motor, di) = self.drive.torque(w, y[BASE + D_PI]);
        let m_drive = self.drive.at_crank(t_motor);
        let alpha2 = (m_drive - rb0.m12) / (self.drive.inertia + s_inertia);
        let rb = RodAndBar {
            alpha3: rb0.alpha3 + k3 * alpha2,
            m12: rb0.m12 + s_inertia * alpha2,
            ..rb0
        };
        dy[THETA3] = omega3;
        dy[OMEGA3] = rb.alpha3;
        dy[X4] = v4;
        dy[V4] = rb.a4;
        drive_derivatives(
            dy,
            BASE,
            &self.drive,
            w,
            alpha2,
            s2,
            c2,
            t_motor,
            m_drive,
            di,
            (
                -rb.f_guide * v4,
                -rb.f_proc * v4,
                joint.f_n * joint.delta_dot - joint.f_t * joint.v_t,
            ),
        );
        // The ideal mechanism at the same angle, speed and acceleration.
        let ideal = m.beside_ideal(theta2, (s2, c2), w, alpha2, rb.s, rb.m12);
        dy[Q_S] = ideal.q_s;
        dy[Q_DM2] = ideal.q_dm2;
        joint_outputs(t, (theta2, w, alpha2, t_motor), &joint, &rb, v4, &ideal)
    }
}

impl System<DIM> for MotorClearanceModel {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate_in(self.inner.mode, t, y, dy);
    }
    fn rhs_step_end(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        let o = self.evaluate_in(self.inner.mode, t, y, dy);
        self.end.store(t, y, self.inner.mode, o);
    }
}

impl JointModel<DIM> for MotorClearanceModel {
    const Q_S: usize = Q_S;
    const Q_DM2: usize = Q_DM2;
    fn has_joint(&self) -> bool {
        true
    }
    fn mode(&self) -> Mode {
        self.inner.mode
    }
    fn set_mode(&mut self, mode: Mode) {
        self.inner.mode = mode;
    }
    fn set_quadratures(&mut self, on: bool) {
        self.inner.quadratures = on;
    }
    fn clearance(&self) -> f64 {
        self.inner.clearance
    }
    fn rb(&self) -> f64 {
        self.inner.rb
    }
    fn x4_tdc(&self) -> f64 {
        self.inner.x4_tdc
    }
    fn tolerance(&self, rtol: f64, atol: f64) -> Tolerance<DIM> {
        let inner = self.inner.tolerance(rtol, atol);
        let r = self.inner.geom.r;
        let mut scale = [Scale::Ignore; DIM];
        let mut at = [0.0; DIM];
        scale[..6].copy_from_slice(&inner.scale);
        at[..6].copy_from_slice(&inner.atol);
        // θ2 at the clearance's scale through the crank length.
        let theta_scale = Scale::Fixed(self.inner.clearance.max(1e-9) / r);
        self.drive
            .fill_tolerance(BASE, theta_scale, atol, r, &mut scale, &mut at);
        Tolerance {
            rtol,
            atol: at,
            scale,
        }
    }
    fn initial_state(&self, dx4: f64) -> [f64; DIM] {
        let w = self.drive.operating.omega;
        let th = self.inner.theta0;
        let pose = self.inner.geom.pose(th, w, 0.0);
        let mut y = [0.0; DIM];
        y[THETA3] = pose.theta3();
        y[OMEGA3] = pose.omega3;
        y[X4] = pose.x4 + dx4;
        y[V4] = pose.v4;
        y[THETA2] = th;
        y[OMEGA2] = w;
        y[BASE + D_PI] = self.drive.integrator_start();
        y
    }
    #[inline]
    fn theta2(&self, _t: f64, y: &[f64; DIM]) -> f64 {
        y[THETA2]
    }
    #[inline]
    fn penetration(&self, _t: f64, y: &[f64; DIM]) -> (f64, f64) {
        let (s2, c2) = self.inner.sc2.get(y[THETA2]);
        self.inner
            .penetration_sc(s2, c2, y[OMEGA2], Self::joint_state(y))
    }
    fn relative_speed(&self, _t: f64, y: &[f64; DIM]) -> f64 {
        let (s2, c2) = self.inner.sc2.get(y[THETA2]);
        self.inner
            .relative_speed_sc(s2, c2, y[OMEGA2], Self::joint_state(y))
    }
    #[inline]
    fn deviation(&self, _t: f64, y: &[f64; DIM]) -> (f64, f64) {
        let p = self.inner.geom.pose(y[THETA2], y[OMEGA2], 0.0);
        (y[X4] - p.x4, y[V4] - p.v4)
    }
    fn onset_step(&self, approach: f64, tol_pos: f64) -> f64 {
        self.inner.onset_step(approach, tol_pos)
    }
    fn accel_scale(&self) -> f64 {
        self.inner.accel_scale()
    }
    #[inline]
    fn outputs_in(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Outputs {
        let mut dy = [0.0; DIM];
        self.evaluate_in(mode, t, y, &mut dy)
    }
    #[inline]
    fn rhs_in(&self, mode: Mode, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate_in(mode, t, y, dy);
    }
    fn cached_end(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Option<Outputs> {
        self.end.get(t, y, mode)
    }
    fn process_event(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Option<f64> {
        stick_event(&self.inner.process, mode, y[V4], || {
            self.outputs_in(mode, t, y)
        })
    }
    fn process_switch(&self, mode: Mode, t: f64, y: &mut [f64; DIM]) -> ProcessMode {
        stick_switch(&self.inner.process, y, V4, |y| {
            self.outputs_in(
                Mode {
                    process: ProcessMode::Held,
                    ..mode
                },
                t,
                y,
            )
        })
    }
    fn stall_margin(&self, y: &[f64; DIM]) -> Option<f64> {
        Some(y[OMEGA2] - self.drive.stall_speed())
    }
}
