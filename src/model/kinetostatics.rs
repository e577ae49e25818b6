//! Newton–Euler kinetostatics of the ideal mechanism (level `ideal`): joint
//! forces, guide friction, process load and the drive torque M12 at each
//! crank angle, in closed form.
//!
//! Conventions: `f_a` is the force the crank exerts on the rod at A, `f_b` the
//! force the pin bar exerts on the rod at B (the pin bar feels −`f_b`).

use super::contact::{ProcessLoad, smoothing};
use super::kinematics::{Geometry, Pose};
use super::params::Params;
use serde::Serialize;

/// Planar cross product a × b = a_x b_y − a_y b_x.
#[inline]
pub fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Inertial data of the three moving bodies and gravity.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Inertia {
    pub m2: f64,
    pub lc2: f64,
    pub i2: f64,
    pub m3: f64,
    pub lc3: f64,
    pub i3: f64,
    pub m4: f64,
    pub g: [f64; 2],
}

impl Inertia {
    pub fn of(p: &Params) -> Self {
        Self {
            m2: p.m2,
            lc2: p.lc2,
            i2: p.i2,
            m3: p.m3,
            lc3: p.lc3,
            i3: p.i3,
            m4: p.m4,
            g: p.gravity,
        }
    }

    /// Crank inertia about O.
    pub fn i_o(&self) -> f64 {
        self.i2 + self.m2 * self.lc2 * self.lc2
    }

    /// Drive torque from the crank's moment balance about O, given the force
    /// the crank exerts on the rod at A: M12 = I_O α2 + A × F_A − G2 × m2 g.
    #[inline]
    pub fn drive_torque(&self, r: f64, theta2: f64, alpha2: f64, f_a: [f64; 2]) -> f64 {
        let (s2, c2) = theta2.sin_cos();
        self.drive_torque_sc(r, s2, c2, alpha2, f_a)
    }

    /// [`Inertia::drive_torque`] with sin θ2 and cos θ2 given.
    #[inline]
    pub fn drive_torque_sc(&self, r: f64, s2: f64, c2: f64, alpha2: f64, f_a: [f64; 2]) -> f64 {
        let a = [r * c2, r * s2];
        let g2 = [self.lc2 * c2, self.lc2 * s2];
        self.i_o() * alpha2 + cross(a, f_a) - cross(g2, [self.m2 * self.g[0], self.m2 * self.g[1]])
    }

    /// Acceleration of the rod's centroid G3 from the crank pin's acceleration
    /// and the rod's angular motion.
    #[inline]
    pub fn rod_centroid_accel(
        &self,
        a_a: [f64; 2],
        theta3: f64,
        omega3: f64,
        alpha3: f64,
    ) -> [f64; 2] {
        let (s3, c3) = theta3.sin_cos();
        self.rod_centroid_accel_sc(a_a, s3, c3, omega3, alpha3)
    }

    /// [`Inertia::rod_centroid_accel`] with sin θ3 and cos θ3 given.
    #[inline]
    pub fn rod_centroid_accel_sc(
        &self,
        a_a: [f64; 2],
        s3: f64,
        c3: f64,
        omega3: f64,
        alpha3: f64,
    ) -> [f64; 2] {
        [
            a_a[0] + self.lc3 * (-alpha3 * s3 - omega3 * omega3 * c3),
            a_a[1] + self.lc3 * (alpha3 * c3 - omega3 * omega3 * s3),
        ]
    }
}

/// Forces and torque of the ideal mechanism at one crank angle.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct IdealForces {
    pub pose: Pose,
    /// Force of the crank on the rod at A, N.
    pub f_a: [f64; 2],
    /// Force of the pin bar on the rod at B, N (the clearance joint's force).
    pub f_b: [f64; 2],
    /// Force of the ground on the crank at O, N.
    pub f_o: [f64; 2],
    /// The guide's y reaction on the pin bar, N.
    pub guide_normal: f64,
    /// Guide friction on the pin bar along x, N.
    pub guide_friction: f64,
    /// Process load on the pin bar along x, N (the load cell reads minus this).
    pub process_force: f64,
    /// Drive torque, N·m.
    pub m12: f64,
}

impl IdealForces {
    /// Magnitude of the rod–pin-bar joint force.
    pub fn joint_force_b(&self) -> f64 {
        self.f_b[0].hypot(self.f_b[1])
    }
}

/// Closed-form kinetostatics of the ideal mechanism.
#[derive(Debug, Clone, Serialize)]
pub struct Kinetostatics {
    pub geom: Geometry,
    pub inertia: Inertia,
    pub mu_g: f64,
    pub v0: f64,
    pub v1: f64,
    pub process: ProcessLoad,
    x4_tdc: f64,
}

impl Kinetostatics {
    pub fn of(p: &Params) -> Self {
        let geom = Geometry::of(p);
        Self {
            geom,
            inertia: Inertia::of(p),
            mu_g: p.mu_g,
            v0: p.v0,
            v1: p.v1,
            process: ProcessLoad::of(p),
            x4_tdc: geom.x4_tdc(),
        }
    }

    /// Forces at crank angle θ2, speed ω2 and acceleration α2.
    pub fn at(&self, theta2: f64, omega2: f64, alpha2: f64) -> IdealForces {
        let (s2, c2) = theta2.sin_cos();
        self.at_sc(theta2, s2, c2, omega2, alpha2)
    }

    /// [`Kinetostatics::at`] with sin θ2 and cos θ2 given.
    #[inline(always)]
    pub fn at_sc(&self, theta2: f64, s2: f64, c2: f64, omega2: f64, alpha2: f64) -> IdealForces {
        let pose = self.geom.pose_sc(theta2, s2, c2, omega2, alpha2);
        let Inertia {
            m3, i3, lc3, m4, g, ..
        } = self.inertia;
        let r = self.geom.r;
        let l = self.geom.l;
        let (s3, c3) = (pose.s3, pose.c3);
        let a_a = [
            -r * omega2 * omega2 * c2 - r * alpha2 * s2,
            -r * omega2 * omega2 * s2 + r * alpha2 * c2,
        ];
        let a_g3 = self
            .inertia
            .rod_centroid_accel_sc(a_a, s3, c3, pose.omega3, pose.alpha3);
        // Rod moments about A: (B − A) × F_B = I3 α3 + (G3 − A) × m3 (a_G3 − g).
        let rg = [lc3 * c3, lc3 * s3];
        let r1 = i3 * pose.alpha3 + cross(rg, [m3 * (a_g3[0] - g[0]), m3 * (a_g3[1] - g[1])]);
        // Pin bar x: F_Bx = Q + F_guide(F_By), Q = −m4 a4 + m4 g_x + F_proc.
        let s = pose.x4 - self.x4_tdc;
        let f_proc = self.process.force(s, pose.v4);
        let q = -m4 * pose.a4 + m4 * g[0] + f_proc;
        // Guide: N = F_By − m4 g_y (the y reaction), friction −μ' |N| with
        // μ' = μ_g c_d(|v4|) sign(v4). With w = N:
        //   c3 w + s3 μ' |w| = r1 / l + s3 Q − c3 m4 g_y
        let mu = self.mu_g * smoothing(pose.v4.abs(), self.v0, self.v1) * pose.v4.signum();
        // The reciprocals do not wait for r1 (off the critical path).
        let inv_pos = 1.0 / (c3 + s3 * mu);
        let rhs = r1 * (1.0 / l) + s3 * q - c3 * m4 * g[1];
        let w = if mu == 0.0 {
            rhs / c3
        } else {
            let w_pos = rhs * inv_pos;
            if w_pos >= 0.0 {
                w_pos
            } else {
                rhs / (c3 - s3 * mu)
            }
        };
        let guide_friction = -mu * w.abs();
        let f_b = [q + guide_friction, w + m4 * g[1]];
        let f_a = [
            m3 * a_g3[0] - f_b[0] - m3 * g[0],
            m3 * a_g3[1] - f_b[1] - m3 * g[1],
        ];
        let m12 = self.inertia.drive_torque_sc(r, s2, c2, alpha2, f_a);
        let m2 = self.inertia.m2;
        let lc2 = self.inertia.lc2;
        let a_g2 = [
            -lc2 * omega2 * omega2 * c2 - lc2 * alpha2 * s2,
            -lc2 * omega2 * omega2 * s2 + lc2 * alpha2 * c2,
        ];
        let f_o = [
            m2 * a_g2[0] + f_a[0] - m2 * g[0],
            m2 * a_g2[1] + f_a[1] - m2 * g[1],
        ];
        IdealForces {
            pose,
            f_a,
            f_b,
            f_o,
            guide_normal: w,
            guide_friction,
            process_force: f_proc,
            m12,
        }
    }

    /// Kinetic energy of the ideal mechanism at θ2, ω2.
    pub fn kinetic_energy(&self, theta2: f64, omega2: f64) -> f64 {
        let pose = self.geom.pose(theta2, omega2, 0.0);
        let Inertia {
            m3, i3, lc3, m4, ..
        } = self.inertia;
        let r = self.geom.r;
        let (s2, c2) = theta2.sin_cos();
        let (s3, c3) = (pose.s3, pose.c3);
        let v_g3 = [
            -r * omega2 * s2 - lc3 * pose.omega3 * s3,
            r * omega2 * c2 + lc3 * pose.omega3 * c3,
        ];
        0.5 * self.inertia.i_o() * omega2 * omega2
            + 0.5 * m3 * (v_g3[0] * v_g3[0] + v_g3[1] * v_g3[1])
            + 0.5 * i3 * pose.omega3 * pose.omega3
            + 0.5 * m4 * pose.v4 * pose.v4
    }

    /// Power of gravity on all bodies at θ2, ω2.
    pub fn gravity_power(&self, theta2: f64, omega2: f64) -> f64 {
        let pose = self.geom.pose(theta2, omega2, 0.0);
        let Inertia {
            m2,
            lc2,
            m3,
            lc3,
            m4,
            g,
            ..
        } = self.inertia;
        let r = self.geom.r;
        let (s2, c2) = theta2.sin_cos();
        let (s3, c3) = (pose.s3, pose.c3);
        let v_g2 = [-lc2 * omega2 * s2, lc2 * omega2 * c2];
        let v_g3 = [
            -r * omega2 * s2 - lc3 * pose.omega3 * s3,
            r * omega2 * c2 + lc3 * pose.omega3 * c3,
        ];
        m2 * (g[0] * v_g2[0] + g[1] * v_g2[1])
            + m3 * (g[0] * v_g3[0] + g[1] * v_g3[1])
            + m4 * g[0] * pose.v4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// M12·ω = d(KE)/dt − (gravity + guide friction + process) power, with
    /// d(KE)/dt from central differences of the closed-form kinetic energy.
    #[test]
    fn torque_matches_power_balance() {
        let mut p = Params::paper();
        p.mu_g = 0.2; // exercise friction strongly
        p.gravity = [9.81, 3.0];
        p.offset = 2e-3;
        p.f_wd = crate::model::table::Table::from_mm(&[(0.0, 2.0), (1.0, 5.0)]).unwrap();
        let ks = Kinetostatics::of(&p);
        let w = p.omega();
        for i in 0..360 {
            let th = (i as f64 + 0.37).to_radians();
            let f = ks.at(th, w, 0.0);
            let h = 1e-6;
            let dth = w * h;
            let dke = (ks.kinetic_energy(th + dth, w) - ks.kinetic_energy(th - dth, w)) / (2.0 * h);
            let p_ext = ks.gravity_power(th, w) + (f.guide_friction + f.process_force) * f.pose.v4;
            let lhs = f.m12 * w;
            let rhs = dke - p_ext;
            let scale = 1.0 + dke.abs() + p_ext.abs();
            assert!(
                (lhs - rhs).abs() < 1e-6 * scale,
                "θ={i}: M12ω={lhs} vs {rhs}"
            );
        }
    }

    /// The guide's reaction is consistent: friction is μ_g |N| and opposes v4.
    #[test]
    fn guide_friction_opposes_motion() {
        let mut p = Params::paper();
        p.mu_g = 0.3;
        let ks = Kinetostatics::of(&p);
        for i in 0..72 {
            let f = ks.at((i as f64 * 5.0 + 1.0).to_radians(), p.omega(), 0.0);
            if f.pose.v4.abs() > 1e-2 {
                assert!((f.guide_friction.abs() - 0.3 * f.guide_normal.abs()).abs() < 1e-9);
                assert!(f.guide_friction * f.pose.v4 <= 0.0);
            }
        }
    }

    /// Flores benchmark, ideal mechanism: torque and joint-force extremes.
    #[test]
    fn flores_ideal_torque_and_joint_force() {
        let p = Params::flores();
        let ks = Kinetostatics::of(&p);
        let w = p.omega();
        let m = |deg: f64| ks.at(deg.to_radians(), w, 0.0);
        assert!(
            (m(325.0).m12 - (-138.4192)).abs() < 1e-3,
            "{}",
            m(325.0).m12
        );
        assert!((m(35.0).m12 - 138.6242).abs() < 1e-3, "{}", m(35.0).m12);
        assert!(
            (m(75.0).joint_force_b() - 433.55).abs() < 0.01,
            "{}",
            m(75.0).joint_force_b()
        );
        assert!(
            (m(0.0).joint_force_b() - 2718.71).abs() < 0.01,
            "{}",
            m(0.0).joint_force_b()
        );
        // And they are the extremes over a 0.1° grid.
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..3600 {
            let t = m(i as f64 * 0.1).m12;
            lo = lo.min(t);
            hi = hi.max(t);
        }
        assert!(
            (lo + 138.4192).abs() < 1e-3 && (hi - 138.6242).abs() < 1e-3,
            "{lo} {hi}"
        );
        let _ = PI;
    }
}
