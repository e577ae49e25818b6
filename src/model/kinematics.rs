//! Closed-form kinematics of the ideal slider-crank (level `kinematic`).
//!
//! Frame of model.md: origin at the crank centre O, x along the pin bar's
//! line of motion (down, the insertion direction), θ2 from +x
//! counter-clockwise. The pin bar moves on y = offset; the rod runs from the
//! crank pin A to the pin bar's journal B with B to the +x side of A.

use super::params::Params;
use serde::Serialize;

/// The three lengths that fix the ideal mechanism's motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Geometry {
    /// Crank length r, m.
    pub r: f64,
    /// Rod length l, m.
    pub l: f64,
    /// Offset of the pin bar line, m.
    pub offset: f64,
}

/// Positions, velocities and accelerations of the ideal mechanism at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    pub theta2: f64,
    /// sin θ3 and cos θ3 (θ3 itself by [`Pose::theta3`]).
    pub s3: f64,
    pub c3: f64,
    pub omega3: f64,
    pub alpha3: f64,
    /// Pin bar position x4 (m), velocity (m/s), acceleration (m/s²).
    pub x4: f64,
    pub v4: f64,
    pub a4: f64,
}

impl Pose {
    /// The rod angle θ3; cos θ3 > 0 (B lies to the +x side of A), so θ3 = asin(sin θ3).
    pub fn theta3(&self) -> f64 {
        self.s3.asin()
    }
}

impl Geometry {
    pub fn new(r: f64, l: f64, offset: f64) -> Self {
        Self { r, l, offset }
    }

    pub fn of(p: &Params) -> Self {
        Self::new(p.r, p.l, p.offset)
    }

    /// Crank angle of top dead centre θ0 (smallest x4): crank and rod folded,
    /// the crank pointing away from B. π for zero offset.
    pub fn tdc_angle(&self) -> f64 {
        let x = self.x4_tdc();
        (-self.offset)
            .atan2(-x)
            .rem_euclid(2.0 * std::f64::consts::PI)
    }

    /// Crank angle of bottom dead centre (largest x4): crank and rod in line.
    pub fn bdc_angle(&self) -> f64 {
        let x = self.x4_bdc();
        self.offset.atan2(x).rem_euclid(2.0 * std::f64::consts::PI)
    }

    /// x4 at top dead centre, sqrt((l − r)² − offset²).
    pub fn x4_tdc(&self) -> f64 {
        ((self.l - self.r).powi(2) - self.offset * self.offset).sqrt()
    }

    /// x4 at bottom dead centre, sqrt((l + r)² − offset²).
    pub fn x4_bdc(&self) -> f64 {
        ((self.l + self.r).powi(2) - self.offset * self.offset).sqrt()
    }

    /// Full stroke S (2r for zero offset).
    pub fn stroke(&self) -> f64 {
        self.x4_bdc() - self.x4_tdc()
    }

    /// The ideal pose at crank angle θ2 with crank speed ω2 and acceleration α2.
    #[inline]
    pub fn pose(&self, theta2: f64, omega2: f64, alpha2: f64) -> Pose {
        let (s2, c2) = theta2.sin_cos();
        self.pose_sc(theta2, s2, c2, omega2, alpha2)
    }

    /// [`Geometry::pose`] with sin θ2 and cos θ2 given.
    #[inline]
    pub fn pose_sc(&self, theta2: f64, s2: f64, c2: f64, omega2: f64, alpha2: f64) -> Pose {
        let Geometry { r, l, offset } = *self;
        let s3 = (offset - r * s2) / l;
        let c3 = (1.0 - s3 * s3).sqrt();
        let inv_lc3 = 1.0 / (l * c3);

        let omega3 = -r * c2 * omega2 * inv_lc3;
        let alpha3 =
            (r * s2 * omega2 * omega2 - r * c2 * alpha2 + l * s3 * omega3 * omega3) * inv_lc3;
        let x4 = r * c2 + l * c3;
        let v4 = -r * s2 * omega2 - l * s3 * omega3;
        let a4 = -r * c2 * omega2 * omega2
            - r * s2 * alpha2
            - l * c3 * omega3 * omega3
            - l * s3 * alpha3;
        Pose {
            theta2,
            s3,
            c3,
            omega3,
            alpha3,
            x4,
            v4,
            a4,
        }
    }

    /// Stroke s = x4 − x4_TDC at crank angle θ2.
    #[inline]
    pub fn stroke_at(&self, theta2: f64) -> f64 {
        let s3 = (self.offset - self.r * theta2.sin()) / self.l;
        self.r * theta2.cos() + self.l * (1.0 - s3 * s3).sqrt() - self.x4_tdc()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn dead_centres_zero_offset() {
        let g = Geometry::new(8e-3, 45e-3, 0.0);
        assert!((g.tdc_angle() - PI).abs() < 1e-15);
        assert!(g.bdc_angle().abs() < 1e-15);
        assert!((g.stroke() - 16e-3).abs() < 1e-15);
        assert!(g.stroke_at(PI).abs() < 1e-15);
        assert!((g.stroke_at(0.0) - 16e-3).abs() < 1e-15);
    }

    #[test]
    fn dead_centres_with_offset_are_extrema() {
        let g = Geometry::new(8e-3, 45e-3, 3e-3);
        let t0 = g.tdc_angle();
        let tb = g.bdc_angle();
        let p0 = g.pose(t0, 1.0, 0.0);
        assert!(p0.v4.abs() < 1e-12, "v at TDC {}", p0.v4);
        assert!((p0.x4 - g.x4_tdc()).abs() < 1e-15);
        assert!(g.pose(tb, 1.0, 0.0).v4.abs() < 1e-12);
        // Minimum over a fine grid is at TDC.
        let min = (0..100_000)
            .map(|i| g.pose(i as f64 * 2.0 * PI / 100_000.0, 1.0, 0.0).x4)
            .fold(f64::INFINITY, f64::min);
        assert!(min >= g.x4_tdc() - 1e-15 && min - g.x4_tdc() < 1e-9);
    }

    /// Velocity and acceleration against central differences of the position.
    #[test]
    fn derivatives_match_numerical_differentiation() {
        let g = Geometry::new(0.05, 0.12, 0.01);
        let (w, a) = (523.6, 1000.0);
        for i in 0..37 {
            let t = 1e-4 * i as f64;
            let th = |t: f64| 0.3 + w * t + 0.5 * a * t * t;
            let x = |t: f64| g.pose(th(t), 0.0, 0.0).x4;
            let th3 = |t: f64| g.pose(th(t), 0.0, 0.0).theta3();
            let h = 1e-7;
            let p = g.pose(th(t), w + a * t, a);
            let v_num = (x(t + h) - x(t - h)) / (2.0 * h);
            let a_num = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
            let w3_num = (th3(t + h) - th3(t - h)) / (2.0 * h);
            let a3_num = (th3(t + h) - 2.0 * th3(t) + th3(t - h)) / (h * h);
            assert!(
                (p.v4 - v_num).abs() < 1e-6 * (1.0 + p.v4.abs()),
                "v {} {}",
                p.v4,
                v_num
            );
            assert!(
                (p.a4 - a_num).abs() < 2e-3 * (1.0 + p.a4.abs()),
                "a {} {}",
                p.a4,
                a_num
            );
            assert!((p.omega3 - w3_num).abs() < 1e-6 * (1.0 + p.omega3.abs()));
            assert!((p.alpha3 - a3_num).abs() < 2e-3 * (1.0 + p.alpha3.abs()));
        }
    }

    /// Flores benchmark table: slider acceleration and velocity extremes.
    #[test]
    fn flores_ideal_extremes() {
        let g = Geometry::new(0.05, 0.12, 0.0);
        let w = 2.0 * PI * 5000.0 / 60.0;
        let at = |deg: f64| g.pose(deg.to_radians(), w, 0.0);
        assert!((at(0.0).a4 - (-19_419.36)).abs() < 0.01);
        assert!((at(122.0).a4 - 9_695.856).abs() < 0.01);
        assert!((at(70.2).v4 - (-28.41133)).abs() < 1e-4);
        assert!((at(289.8).v4 - 28.41133).abs() < 1e-4);
    }
}
