//! The clearance-joint mechanism as an ODE (level `clearance`, model.md
//! "Equations"): constant-speed crank, free rod angle and pin-bar position,
//! contact-impact force with friction in the rod–pin-bar joint.
//!
//! State y = (θ3, ω3, x4, v4, Q_s, Q_M): the last two are quadratures
//! Q_s = ∫(s − s_ideal) dt and Q_M = ∫(M12 − M12_ideal)² dt, so that the
//! time averages of the summary figures are integrated to the solver's
//! accuracy at no extra evaluations. They do not feed back and are excluded
//! from error control. The integrands are smooth: ∫|Δs| dt is assembled by
//! the driver from Q_s between the located zeros of Δs (a kink inside a
//! step would cost O(h²) per sign change), and ∫|Δv| dt from Δs itself
//! between the zeros of Δv.
//!
//! The contact *mode* (free flight or contact, and the approach velocity at
//! the onset) is set by the driver at located events, so that the right-hand
//! side is smooth within every step: in free flight no contact force acts
//! even if a step overshoots δ = 0 (the event is then located and the step
//! cut back), in contact the force is max(0, …) of the penetration.

use super::contact::{ContactLaw, ProcessLoad, ProcessMode, coulomb};
use super::joint_model::{EndCache, JointModel};
pub use super::joint_model::{Mode, Outputs};
use super::kinematics::Geometry;
use super::kinetostatics::{Inertia, Kinetostatics, cross};
use super::params::Params;
use super::sincos::SinCos;
use crate::solver::{Scale, System, Tolerance};

/// |(x, y)| without `hypot`'s overflow guard (glibc's `hypot` was 15 % of a
/// simulation's time; the magnitudes here are millimetres and m/s).
#[inline(always)]
fn norm2(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// Dimension of the state.
pub const DIM: usize = 6;
/// Index of each state component.
pub const THETA3: usize = 0;
pub const OMEGA3: usize = 1;
pub const X4: usize = 2;
pub const V4: usize = 3;
pub const Q_S: usize = 4;
pub const Q_DM2: usize = 5;

/// The rod–pin-bar joint at one instant: where the journal sits in the
/// bearing and the contact force (model.md, "Clearance joint contact").
#[derive(Debug, Clone, Copy)]
pub struct Joint {
    /// Eccentricity e = P − B (m), penetration δ = |e| − c and its rate.
    pub ecc: [f64; 2],
    pub delta: f64,
    pub delta_dot: f64,
    /// Normal n = e/|e| and tangent t (n turned +90°).
    pub n: [f64; 2],
    pub tt: [f64; 2],
    /// Normal force (N) and friction on the pin bar along t (N).
    pub f_n: f64,
    pub f_t: f64,
    /// Tangential slip at the contact point (m/s), v_t of model.md, in or
    /// out of contact (Archard wear integrates F_N·|v_t|).
    pub v_t: f64,
    /// The contact force on the rod (normal + friction), N.
    pub f_rod: [f64; 2],
}

/// What [`ClearanceModel::rod_and_bar`] gives: the rod's angular
/// acceleration, the stroke s, the guide friction, the process load, the
/// pin bar's acceleration and the crank torque M12.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RodAndBar {
    pub alpha3: f64,
    pub s: f64,
    pub f_guide: f64,
    pub f_proc: f64,
    pub a4: f64,
    pub m12: f64,
}

/// The ideal mechanism at the same crank state as a joint evaluation
/// (NaN when the quadratures do not run), and the quadratures' integrands:
/// the stroke deviation and the squared torque difference.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Beside {
    pub s: f64,
    pub v: f64,
    pub a: f64,
    pub m12: f64,
    pub process_force: f64,
    pub q_s: f64,
    pub q_dm2: f64,
}

/// The outputs of a joint evaluation: the crank's (θ2, ω2, α2, motor
/// torque), the joint, the rod and pin bar with the final α3 and M12, and
/// the ideal mechanism beside them. One place for the constant-speed and
/// the motor level alike.
#[inline(always)]
pub(crate) fn joint_outputs(
    t: f64,
    (theta2, omega2, alpha2, motor_torque): (f64, f64, f64, f64),
    joint: &Joint,
    rb: &RodAndBar,
    v4: f64,
    ideal: &Beside,
) -> Outputs {
    Outputs {
        t,
        theta2,
        omega2,
        alpha2,
        motor_torque,
        s: rb.s,
        v4,
        a4: rb.a4,
        alpha3: rb.alpha3,
        f_n: joint.f_n,
        f_t: joint.f_t,
        v_slip: joint.v_t,
        m12: rb.m12,
        delta: joint.delta,
        delta_dot: joint.delta_dot,
        ecc: joint.ecc,
        process_force: rb.f_proc,
        ideal_s: ideal.s,
        ideal_v: ideal.v,
        ideal_a: ideal.a,
        ideal_m12: ideal.m12,
        ideal_process_force: ideal.process_force,
    }
}

/// The clearance-joint model with its constants resolved.
#[derive(Debug, Clone)]
pub struct ClearanceModel {
    pub geom: Geometry,
    pub inertia: Inertia,
    pub law: ContactLaw,
    pub clearance: f64,
    pub rb: f64,
    pub c_f: f64,
    pub mu_g: f64,
    pub v0: f64,
    pub v1: f64,
    pub process: ProcessLoad,
    pub omega: f64,
    /// Crank angle at t = 0 (top dead centre).
    pub theta0: f64,
    pub x4_tdc: f64,
    pub ideal: Kinetostatics,
    /// Rod inertia about the crank pin, I3 + m3 Lc3².
    pub(crate) j_a: f64,
    pub(crate) inv_j_a: f64,
    pub(crate) inv_m4: f64,
    pub mode: Mode,
    /// Whether the quadratures (and the ideal mechanism they compare with)
    /// are evaluated. Off during warm-up, where nothing is reported: the
    /// ideal kinetostatics is a sixth of a right-hand side's cost. When it
    /// is off, the `ideal_*` outputs are NaN.
    pub quadratures: bool,
    /// sin/cos of θ2 and θ3, advanced by rotation from the last call.
    pub(crate) sc2: SinCos,
    pub(crate) sc3: SinCos,
    /// The outputs of the last end-of-step evaluation.
    pub(crate) end: EndCache<DIM>,
}

impl ClearanceModel {
    pub fn new(p: &Params) -> Self {
        let geom = Geometry::of(p);
        let inertia = Inertia::of(p);
        Self {
            geom,
            inertia,
            law: ContactLaw::of(p),
            clearance: p.clearance,
            rb: p.rb(),
            c_f: p.c_f,
            mu_g: p.mu_g,
            v0: p.v0,
            v1: p.v1,
            process: ProcessLoad::of(p),
            omega: p.omega(),
            theta0: geom.tdc_angle(),
            x4_tdc: geom.x4_tdc(),
            ideal: Kinetostatics::of(p),
            j_a: p.i3 + p.m3 * p.lc3 * p.lc3,
            inv_j_a: 1.0 / (p.i3 + p.m3 * p.lc3 * p.lc3),
            inv_m4: 1.0 / p.m4,
            mode: Mode::default(),
            quadratures: true,
            sc2: SinCos::new(),
            sc3: SinCos::new(),
            end: EndCache::default(),
        }
    }

    /// Journal centred, velocities of the ideal mechanism (model.md), the pin
    /// bar displaced by `dx4` (m) along x for ensemble realisations.
    pub fn initial_state(&self, dx4: f64) -> [f64; DIM] {
        let pose = self.geom.pose(self.theta0, self.omega, 0.0);
        [pose.theta3(), pose.omega3, pose.x4 + dx4, pose.v4, 0.0, 0.0]
    }

    /// Crank angle at time t.
    #[inline]
    pub fn theta2(&self, t: f64) -> f64 {
        self.theta0 + self.omega * t
    }

    /// Penetration δ and its rate from the state (cheap: no forces).
    #[inline]
    pub fn penetration(&self, t: f64, y: &[f64; DIM]) -> (f64, f64) {
        let (s2, c2) = self.sc2.get(self.theta2(t));
        self.penetration_sc(s2, c2, self.omega, [y[THETA3], y[OMEGA3], y[X4], y[V4]])
    }

    /// [`ClearanceModel::penetration`] for a crank at sin θ2, cos θ2 turning
    /// at ω2, and the joint's state (θ3, ω3, x4, v4).
    #[inline(always)]
    pub fn penetration_sc(&self, s2: f64, c2: f64, omega2: f64, q: [f64; 4]) -> (f64, f64) {
        let (s3, c3) = self.sc3.get(q[0]);
        let r = self.geom.r;
        let l = self.geom.l;
        let bx = r * c2 + l * c3;
        let by = r * s2 + l * s3;
        let ex = q[2] - bx;
        let ey = self.geom.offset - by;
        let e = norm2(ex, ey);
        let vbx = -r * omega2 * s2 - l * q[1] * s3;
        let vby = r * omega2 * c2 + l * q[1] * c3;
        let dvx = q[3] - vbx;
        let dvy = -vby;
        let dd = if e > 0.0 {
            (dvx * ex + dvy * ey) / e
        } else {
            norm2(dvx, dvy)
        };
        (e - self.clearance, dd)
    }

    /// The ideal mechanism's x4 and v4 at time t.
    #[inline]
    pub fn ideal_x4_v4(&self, t: f64) -> (f64, f64) {
        let th = self.theta2(t);
        let (s2, c2) = self.sc2.get(th);
        let p = self.geom.pose_sc(th, s2, c2, self.omega, 0.0);
        (p.x4, p.v4)
    }

    /// Relative speed of journal and bearing centres, |v_P − v_B| (m/s).
    pub fn relative_speed(&self, t: f64, y: &[f64; DIM]) -> f64 {
        let (s2, c2) = self.sc2.get(self.theta2(t));
        self.relative_speed_sc(s2, c2, self.omega, [y[THETA3], y[OMEGA3], y[X4], y[V4]])
    }

    /// [`ClearanceModel::relative_speed`] as [`ClearanceModel::penetration_sc`].
    pub fn relative_speed_sc(&self, s2: f64, c2: f64, omega2: f64, q: [f64; 4]) -> f64 {
        let (s3, c3) = self.sc3.get(q[0]);
        let r = self.geom.r;
        let l = self.geom.l;
        let vbx = -r * omega2 * s2 - l * q[1] * s3;
        let vby = r * omega2 * c2 + l * q[1] * c3;
        norm2(q[3] - vbx, vby)
    }

    /// A first step after a contact onset with approach velocity `approach`:
    /// the contact displacement grows like K δ̇^1.5 τ^3.5 / (8.75 m), which a
    /// Runge–Kutta step cannot follow beyond its position tolerance `tol_pos`
    /// (m). With the smaller of the pin bar's mass and the rod's effective
    /// mass at B.
    pub fn onset_step(&self, approach: f64, tol_pos: f64) -> f64 {
        let v = approach.max(self.law.approach_floor);
        let m_eff = self.inertia.m4.min(self.j_a / (self.geom.l * self.geom.l));
        (tol_pos * 8.75 * m_eff / (self.law.k * v * v.sqrt())).powf(1.0 / 3.5)
    }

    /// Scale of the crank-driven relative acceleration (m/s²), for the
    /// free-flight step limit.
    pub fn accel_scale(&self) -> f64 {
        let g = self.inertia.g;
        self.geom.r * self.omega * self.omega * (1.0 + self.geom.r / self.geom.l) + g[0].hypot(g[1])
    }

    /// The joint for a crank pin at `a` moving at `va`, the rod at
    /// (sin θ3, cos θ3) turning at ω3 and the pin bar at (x4, v4), in `mode`
    /// (free flight: no force even past δ = 0).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn joint(
        &self,
        mode: Mode,
        a: [f64; 2],
        va: [f64; 2],
        s3: f64,
        c3: f64,
        omega3: f64,
        x4: f64,
        v4: f64,
    ) -> Joint {
        let Geometry { l, offset, .. } = self.geom;
        // The bearing centre B.
        let b = [a[0] + l * c3, a[1] + l * s3];
        let vb = [va[0] - l * omega3 * s3, va[1] + l * omega3 * c3];
        // Eccentricity of the journal P = (x4, offset).
        let ecc = [x4 - b[0], offset - b[1]];
        let e2 = ecc[0] * ecc[0] + ecc[1] * ecc[1];
        let e = e2.sqrt();
        let delta = e - self.clearance;
        let dv = [v4 - vb[0], -vb[1]];
        let (n, delta_dot) = if e > 0.0 {
            // 1/e as e · (1/e²): the division runs beside the square root
            // instead of after it (the normal and δ̇ are on the critical path).
            let inv_e = e * (1.0 / e2);
            let n = [ecc[0] * inv_e, ecc[1] * inv_e];
            (n, dv[0] * n[0] + dv[1] * n[1])
        } else {
            ([1.0, 0.0], norm2(dv[0], dv[1]))
        };
        let tt = [-n[1], n[0]];
        let v_t = dv[0] * tt[0] + dv[1] * tt[1] - omega3 * self.rb;
        let (f_n, f_t) = if mode.in_contact && delta > 0.0 {
            let f_n = self.law.normal_force(delta, delta_dot, mode.approach);
            (f_n, coulomb(self.c_f, f_n, v_t, self.v0, self.v1))
        } else {
            (0.0, 0.0)
        };
        // Contact force on the rod: normal along +n, friction opposite to the pin bar's.
        let f_rod = [f_n * n[0] - f_t * tt[0], f_n * n[1] - f_t * tt[1]];
        Joint {
            ecc,
            delta,
            delta_dot,
            n,
            tt,
            f_n,
            f_t,
            v_t,
            f_rod,
        }
    }

    /// The full evaluation in the current mode: derivatives and outputs.
    #[inline]
    pub fn evaluate(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) -> Outputs {
        self.evaluate_in(self.mode, t, y, dy)
    }

    /// The rod's angular acceleration (moments about the crank pin A), the
    /// pin bar's balance (guide friction, process load or the part holding
    /// it) and the crank torque M12 from the crank's balance (F_A = m3 a_G3 −
    /// F_rod − m3 g), for the crank pin at `a` accelerating at `aa`. Shared
    /// by the constant-speed model and the motor level, which calls it with
    /// the part of `aa` without α2 (and adds α2's share itself).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn rod_and_bar(
        &self,
        mode: Mode,
        joint: &Joint,
        a: [f64; 2],
        aa: [f64; 2],
        (s2, c2): (f64, f64),
        (s3, c3): (f64, f64),
        omega3: f64,
        x4: f64,
        v4: f64,
    ) -> RodAndBar {
        let Geometry { l, .. } = self.geom;
        let Inertia {
            m2,
            lc2,
            m3,
            lc3,
            m4,
            g,
            ..
        } = self.inertia;
        let Joint {
            n,
            tt,
            f_n,
            f_t,
            f_rod,
            ..
        } = *joint;
        // Rod: moments about A.
        let ba = [l * c3, l * s3];
        let qa = [ba[0] + self.rb * n[0], ba[1] + self.rb * n[1]];
        let u3 = [c3, s3];
        let moment = cross(ba, [f_n * n[0], f_n * n[1]])
            + cross(qa, [-f_t * tt[0], -f_t * tt[1]])
            + lc3 * m3 * cross(u3, g)
            - m3 * lc3 * cross(u3, aa);
        let alpha3 = moment * self.inv_j_a;
        // Pin bar.
        let s = x4 - self.x4_tdc;
        let f_pin_y = -f_rod[1];
        let n_g = (f_pin_y + m4 * g[1]).abs();
        let f_guide = coulomb(self.mu_g, n_g, v4, self.v0, self.v1);
        let (f_proc, a4) = if mode.process == ProcessMode::Held {
            // Held by the part: the part balances every other force.
            (-(-f_rod[0] + f_guide + m4 * g[0]), 0.0)
        } else {
            let f_proc = self.process.force_in(mode.process, s, v4);
            (f_proc, (-f_rod[0] + f_guide + f_proc) * self.inv_m4 + g[0])
        };
        // Drive torque from the crank's balance: F_A = m3 a_G3 − F_rod − m3 g.
        let a_g3 = self
            .inertia
            .rod_centroid_accel_sc(aa, s3, c3, omega3, alpha3);
        let f_a = [
            m3 * a_g3[0] - f_rod[0] - m3 * g[0],
            m3 * a_g3[1] - f_rod[1] - m3 * g[1],
        ];
        let g2 = [lc2 * c2, lc2 * s2];
        let m12 = cross(a, f_a) - cross(g2, [m2 * g[0], m2 * g[1]]);
        RodAndBar {
            alpha3,
            s,
            f_guide,
            f_proc,
            a4,
            m12,
        }
    }

    /// The ideal mechanism at (θ2, ω2, α2) beside the joint's stroke `s`
    /// and torque `m12`, when the quadratures run (see [`Beside`]).
    #[inline(always)]
    pub(crate) fn beside_ideal(
        &self,
        theta2: f64,
        (s2, c2): (f64, f64),
        w: f64,
        alpha2: f64,
        s: f64,
        m12: f64,
    ) -> Beside {
        if self.quadratures {
            let id = self.ideal.at_sc(theta2, s2, c2, w, alpha2);
            let ideal_s = id.pose.x4 - self.x4_tdc;
            let dm = m12 - id.m12;
            Beside {
                s: ideal_s,
                v: id.pose.v4,
                a: id.pose.a4,
                m12: id.m12,
                process_force: id.process_force,
                q_s: s - ideal_s,
                q_dm2: dm * dm,
            }
        } else {
            Beside {
                s: f64::NAN,
                v: f64::NAN,
                a: f64::NAN,
                m12: f64::NAN,
                process_force: f64::NAN,
                q_s: 0.0,
                q_dm2: 0.0,
            }
        }
    }

    /// The full evaluation in a given mode. Inlined into the right-hand side,
    /// where the outputs it does not need are then never computed.
    #[inline(always)]
    pub fn evaluate_in(&self, mode: Mode, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) -> Outputs {
        let theta2 = self.theta2(t);
        let (s2, c2) = self.sc2.get(theta2);
        let r = self.geom.r;
        let w = self.omega;
        let (theta3, omega3, x4, v4) = (y[THETA3], y[OMEGA3], y[X4], y[V4]);
        let (s3, c3) = self.sc3.get(theta3);
        // Crank pin A.
        let a = [r * c2, r * s2];
        let va = [-r * w * s2, r * w * c2];
        let aa = [-r * w * w * c2, -r * w * w * s2];
        let joint = self.joint(mode, a, va, s3, c3, omega3, x4, v4);
        let rb = self.rod_and_bar(mode, &joint, a, aa, (s2, c2), (s3, c3), omega3, x4, v4);
        dy[THETA3] = omega3;
        dy[OMEGA3] = rb.alpha3;
        dy[X4] = v4;
        dy[V4] = rb.a4;
        // The ideal mechanism at the same angle.
        let ideal = self.beside_ideal(theta2, (s2, c2), w, 0.0, rb.s, rb.m12);
        dy[Q_S] = ideal.q_s;
        dy[Q_DM2] = ideal.q_dm2;
        joint_outputs(t, (theta2, w, 0.0, f64::NAN), &joint, &rb, v4, &ideal)
    }

    pub fn outputs(&self, t: f64, y: &[f64; DIM]) -> Outputs {
        let mut dy = [0.0; DIM];
        self.evaluate(t, y, &mut dy)
    }

    pub fn outputs_in(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Outputs {
        let mut dy = [0.0; DIM];
        self.evaluate_in(mode, t, y, &mut dy)
    }
}

pub use super::joint_model::InMode;

impl System<DIM> for ClearanceModel {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate(t, y, dy);
    }
    fn rhs_step_end(&self, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        let o = self.evaluate(t, y, dy);
        self.end.store(t, y, self.mode, o);
    }
}

impl JointModel<DIM> for ClearanceModel {
    const Q_S: usize = Q_S;
    const Q_DM2: usize = Q_DM2;
    fn has_joint(&self) -> bool {
        true
    }
    fn mode(&self) -> Mode {
        self.mode
    }
    fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
    }
    fn set_quadratures(&mut self, on: bool) {
        self.quadratures = on;
    }
    fn clearance(&self) -> f64 {
        self.clearance
    }
    fn rb(&self) -> f64 {
        self.rb
    }
    fn x4_tdc(&self) -> f64 {
        self.x4_tdc
    }
    fn tolerance(&self, rtol: f64, atol: f64) -> Tolerance<DIM> {
        tolerance(self.clearance, self.geom.l, rtol, atol)
    }
    fn initial_state(&self, dx4: f64) -> [f64; DIM] {
        ClearanceModel::initial_state(self, dx4)
    }
    #[inline]
    fn theta2(&self, t: f64, _y: &[f64; DIM]) -> f64 {
        ClearanceModel::theta2(self, t)
    }
    #[inline]
    fn penetration(&self, t: f64, y: &[f64; DIM]) -> (f64, f64) {
        ClearanceModel::penetration(self, t, y)
    }
    fn relative_speed(&self, t: f64, y: &[f64; DIM]) -> f64 {
        ClearanceModel::relative_speed(self, t, y)
    }
    #[inline]
    fn deviation(&self, t: f64, y: &[f64; DIM]) -> (f64, f64) {
        let (x, v) = self.ideal_x4_v4(t);
        (y[X4] - x, y[V4] - v)
    }
    fn onset_step(&self, approach: f64, tol_pos: f64) -> f64 {
        ClearanceModel::onset_step(self, approach, tol_pos)
    }
    fn accel_scale(&self) -> f64 {
        ClearanceModel::accel_scale(self)
    }
    #[inline]
    fn outputs_in(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Outputs {
        ClearanceModel::outputs_in(self, mode, t, y)
    }
    #[inline]
    fn rhs_in(&self, mode: Mode, t: f64, y: &[f64; DIM], dy: &mut [f64; DIM]) {
        self.evaluate_in(mode, t, y, dy);
    }
    /// The pin bar's own state gives both, as [`Self::rod_and_bar`]
    /// computes them, except while the part holds the bar (the stick law):
    /// the load then balances every other force.
    fn stroke_and_process_in(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> (f64, f64) {
        if mode.process == ProcessMode::Held {
            let o = self.outputs_in(mode, t, y);
            return (o.s, o.process_force);
        }
        let s = y[X4] - self.x4_tdc;
        (s, self.process.force_in(mode.process, s, y[V4]))
    }
    fn cached_end(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Option<Outputs> {
        self.end.get(t, y, mode)
    }
    fn process_event(&self, mode: Mode, t: f64, y: &[f64; DIM]) -> Option<f64> {
        stick_event(&self.process, mode, y[V4], || {
            ClearanceModel::outputs_in(self, mode, t, y)
        })
    }
    fn process_switch(&self, mode: Mode, t: f64, y: &mut [f64; DIM]) -> ProcessMode {
        stick_switch(&self.process, y, V4, |y| {
            ClearanceModel::outputs_in(
                self,
                Mode {
                    process: ProcessMode::Held,
                    ..mode
                },
                t,
                y,
            )
        })
    }
    fn stall_margin(&self, _y: &[f64; DIM]) -> Option<f64> {
        None
    }
}

/// The stick law's event function in `mode` (None under the regularized
/// law): resisting down it is v4 (the pin bar stops when it reaches 0),
/// resisting up −v4, holding the distance of the other forces F_o from the
/// ends of −F_wd … F_ins (`held` gives the outputs in the held mode, whose
/// process force is −F_o).
#[inline]
pub fn stick_event(
    process: &ProcessLoad,
    mode: Mode,
    v4: f64,
    held: impl FnOnce() -> Outputs,
) -> Option<f64> {
    if process.law != super::params::ProcessLaw::Stick {
        return None;
    }
    Some(match mode.process {
        ProcessMode::Down => v4,
        ProcessMode::Up => -v4,
        ProcessMode::Held => {
            let o = held();
            let f_o = -o.process_force;
            let (lo, hi) = process.hold_range(o.s);
            (-lo - f_o).min(f_o + hi)
        }
    })
}

/// What the part does after a stick-law event at state `y` (v4 ≈ 0): it
/// holds the pin bar when the other forces F_o lie inside −F_wd … F_ins
/// (strictly: on an end the pin moves on), else the pin moves the way F_o
/// pushes it. The pin bar's speed is set to exactly 0 (the event's point).
pub fn stick_switch<const N: usize>(
    process: &ProcessLoad,
    y: &mut [f64; N],
    v4: usize,
    held: impl Fn(&[f64; N]) -> Outputs,
) -> ProcessMode {
    y[v4] = 0.0;
    let o = held(y);
    let f_o = -o.process_force;
    let (lo, hi) = process.hold_range(o.s);
    let margin = 1e-12 * (1.0 + lo.abs() + hi.abs());
    if f_o >= -lo - margin && f_o > 0.0 {
        ProcessMode::Down
    } else if f_o <= -hi + margin && f_o < 0.0 {
        ProcessMode::Up
    } else if lo < 0.0 || hi > 0.0 {
        ProcessMode::Held
    } else if f_o >= 0.0 {
        ProcessMode::Down
    } else {
        ProcessMode::Up
    }
}

/// The integrator's tolerance for a clearance model: positions judged at
/// the scale of the clearance (θ3 through the rod length), velocities
/// relative, quadratures not controlled.
pub fn tolerance(clearance: f64, l: f64, rtol: f64, atol: f64) -> Tolerance<DIM> {
    let cref = clearance.max(1e-9);
    Tolerance {
        rtol,
        atol: [atol / l, atol / l, atol, atol, 0.0, 0.0],
        scale: [
            Scale::Fixed(cref / l),
            Scale::Relative,
            Scale::Fixed(cref),
            Scale::Relative,
            Scale::Ignore,
            Scale::Ignore,
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With the journal centred and moving with the ideal mechanism, the
    /// initial state is the ideal one and nothing penetrates.
    #[test]
    fn initial_state_is_ideal() {
        let p = Params::flores();
        let m = ClearanceModel::new(&p);
        let y = m.initial_state(0.0);
        let o = m.outputs(0.0, &y);
        assert!((o.delta + p.clearance).abs() < 1e-15);
        assert!(o.s.abs() < 1e-15 && o.ideal_s.abs() < 1e-15);
        assert!((o.v4 - o.ideal_v).abs() < 1e-12);
        assert_eq!(o.f_n, 0.0);
        let (d, dd) = m.penetration(0.0, &y);
        assert!((d - o.delta).abs() < 1e-18 && dd.abs() < 1e-9);
    }

    /// In free flight the pin bar coasts under gravity (no guide friction
    /// without a normal force from the joint), and the rod's angular
    /// acceleration follows from the crank pin's motion alone.
    #[test]
    fn free_flight_dynamics() {
        let mut p = Params::paper();
        p.f_ins = crate::model::table::Table::zero();
        let m = ClearanceModel::new(&p);
        let y = m.initial_state(0.0);
        let mut dy = [0.0; DIM];
        let o = m.evaluate(0.001, &y, &mut dy);
        assert_eq!(o.f_n, 0.0);
        assert!((dy[V4] - 9.81).abs() < 1e-12, "a4 = {}", dy[V4]);
        // Rod: (I3 + m3 Lc3²) α3 = m3 Lc3 u3 × (g − a_A).
        let th2 = m.theta2(0.001);
        let aa = [
            -p.r * m.omega.powi(2) * th2.cos(),
            -p.r * m.omega.powi(2) * th2.sin(),
        ];
        let u3 = [y[THETA3].cos(), y[THETA3].sin()];
        let expect =
            p.m3 * p.lc3 * cross(u3, [9.81 - aa[0], -aa[1]]) / (p.i3 + p.m3 * p.lc3 * p.lc3);
        assert!((dy[OMEGA3] - expect).abs() < 1e-9 * expect.abs().max(1.0));
    }

    /// In contact, the contact force acts equal and opposite: the pin bar's
    /// x force balance and the normal force agree.
    #[test]
    fn contact_force_balance() {
        let mut p = Params::flores();
        p.gravity = [0.0, 0.0];
        let mut m = ClearanceModel::new(&p);
        m.mode = Mode {
            in_contact: true,
            approach: 1.0,
            ..Mode::default()
        };
        let mut y = m.initial_state(0.0);
        // Push the journal 1 µm into the wall along +x.
        y[X4] += p.clearance + 1e-6;
        let mut dy = [0.0; DIM];
        let o = m.evaluate(0.0, &y, &mut dy);
        let expect = m.law.k * 1e-6f64.powf(1.5) * (1.0 + m.law.d * o.delta_dot / 1.0);
        assert!(
            (o.f_n - expect).abs() < 1e-6 * expect,
            "{} vs {}",
            o.f_n,
            expect
        );
        // Pushed along +x: the pin bar is pushed back (−x).
        assert!((dy[V4] * p.m4 + o.f_n * o.ecc[0] / o.ecc[0].hypot(o.ecc[1])).abs() < 1e-6 * o.f_n);
    }
}
