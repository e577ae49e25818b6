//! Level `motor` with an ideal joint (c = 0): one degree of freedom, the
//! crank angle θ2, driven by the motor through the gear. The mechanism is
//! the ideal kinetostatics at (θ2, ω2, α2), with α2 from the crank's
//! balance J_d α2 = M_drive − M12(θ2, ω2, α2) (model/motor.rs).
//!
//! State: [Q_s, Q_M] (zero: the ideal mechanism is the model itself; kept
//! so the event loop sees the same layout as every model), then the
//! drive's part (θ2, ω2, PI integrator, quadratures).

use super::clearance::{Mode, Outputs};
use super::joint_model::JointModel;
use super::kinematics::Geometry;
use super::kinetostatics::Kinetostatics;
use super::motor::*;
use super::params::Params;
use crate::solver::{Scale, System, Tolerance};

/// Base index of the drive's part.
pub const BASE: usize = 2;
/// Dimension of the state.
pub const DIM: usize = BASE + D_LEN;
pub const THETA2: usize = BASE + D_THETA2;
pub const OMEGA2: usize = BASE + D_OMEGA2;

/// The motor-driven ideal mechanism.
#[derive(Debug, Clone)]
pub struct RigidMotorModel {
    pub ks: Kinetostatics,
    pub drive: MotorDrive,
    pub geom: Geometry,
    pub theta0: f64,
    pub x4_tdc: f64,
    sc2: super::sincos::SinCos,
}

impl RigidMotorModel {
    pub fn new(p: &Params) -> Self {
        let geom = Geometry::of(p);
        Self {
            ks: Kinetostatics::of(p),
            drive: MotorDrive::of(p),
            geom,
            theta0: geom.tdc_angle(),
            x4_tdc: geom.x4_tdc(),
            sc2: super::sincos::SinCos::new(),
        }
    }

    /// Derivatives and outputs.
    #[inline(always)]
    pub fn evaluate(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) -> Outputs {
        let theta2 = y[THETA2];
        let w = y[OMEGA2];
        let (s2, c2) = self.sc2.get(theta2);
        let (t_motor, di) = self.drive.torque(w, y[BASE + D_PI]);
        let m_drive = self.drive.at_crank(t_motor);
        let (alpha2, f) = solve_alpha2(&self.ks, theta2, s2, c2, w, self.drive.inertia, m_drive);
        let v4 = f.pose.v4;
        dy[0] = 0.0;
        dy[1] = 0.0;
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
            (-f.guide_friction * v4, -f.process_force * v4, 0.0),
        );
        let s = f.pose.x4 - self.x4_tdc;
        Outputs::rigid(t, (theta2, w, alpha2), t_motor, s, &f)
    }
}

impl System<DIM> for RigidMotorModel {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate(t, y, dy);
    }
}

impl JointModel<DIM> for RigidMotorModel {
    const Q_S: usize = 0;
    const Q_DM2: usize = 1;
    fn has_joint(&self) -> bool {
        false
    }
    fn mode(&self) -> Mode {
        Mode::default()
    }
    fn set_mode(&mut self, _mode: Mode) {}
    fn set_quadratures(&mut self, _on: bool) {}
    fn clearance(&self) -> f64 {
        0.0
    }
    fn rb(&self) -> f64 {
        f64::INFINITY
    }
    fn x4_tdc(&self) -> f64 {
        self.x4_tdc
    }
    fn tolerance(&self, rtol: f64, atol: f64) -> Tolerance<DIM> {
        let r = self.geom.r;
        let mut scale = [Scale::Ignore; DIM];
        let mut at = [0.0; DIM];
        self.drive
            .fill_tolerance(BASE, Scale::Relative, atol, r, &mut scale, &mut at);
        Tolerance {
            rtol,
            atol: at,
            scale,
        }
    }
    fn initial_state(&self, _dx4: f64) -> [f64; DIM] {
        let mut y = [0.0; DIM];
        y[THETA2] = self.theta0;
        y[OMEGA2] = self.drive.operating.omega;
        y[BASE + D_PI] = self.drive.integrator_start();
        y
    }
    #[inline]
    fn theta2(&self, _t: f64, y: &[f64; DIM]) -> f64 {
        y[THETA2]
    }
    fn penetration(&self, _t: f64, _y: &[f64; DIM]) -> (f64, f64) {
        (-1.0, 0.0)
    }
    fn relative_speed(&self, _t: f64, _y: &[f64; DIM]) -> f64 {
        0.0
    }
    fn deviation(&self, _t: f64, _y: &[f64; DIM]) -> (f64, f64) {
        (0.0, 0.0)
    }
    fn onset_step(&self, _approach: f64, _tol_pos: f64) -> f64 {
        f64::INFINITY
    }
    fn accel_scale(&self) -> f64 {
        let w = self.drive.operating.omega;
        self.geom.r * w * w
    }
    fn outputs_in(&self, _mode: Mode, t: f64, y: &[f64; DIM]) -> Outputs {
        let mut dy = [0.0; DIM];
        self.evaluate(t, y, &mut dy)
    }
    #[inline]
    fn rhs_in(&self, _mode: Mode, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate(t, y, dy);
    }
    fn stall_margin(&self, y: &[f64; DIM]) -> Option<f64> {
        Some(y[OMEGA2] - self.drive.stall_speed())
    }
    /// A degree of crank at the operating speed: the step ends are where
    /// the peak search starts (Brent within two steps must see one peak;
    /// the ideal level scans at 0.5°).
    fn max_step(&self) -> f64 {
        1f64.to_radians() / self.drive.operating.omega
    }
}
