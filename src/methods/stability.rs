//! Linear stability limits of the fixed-step formulas, measured on the
//! methods themselves: one step of the stepper applied to the test equation
//! y' = λ y (as a real 2-D system), the amplification |R(hλ)| read off, and
//! the largest h|λ| with |R| ≤ 1 found by scanning and bisection. On the
//! imaginary axis this is the bound for an undamped contact oscillation of
//! angular frequency ω: stable while h ≤ limit / ω (pitfalls.md quotes about
//! 2.83 for RK4).

use crate::solver::{Method, Stepper, StepperConfig, System, Tolerance};

/// y' = λ y for complex λ = a + i b, as the real system (Re y, Im y).
struct Linear {
    a: f64,
    b: f64,
}

impl System<2> for Linear {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = self.a * y[0] - self.b * y[1];
        dy[1] = self.b * y[0] + self.a * y[1];
    }
}

/// |R(z)| for z = h λ with λ = (cos φ + i sin φ): one fixed step of size |z|.
pub fn amplification(method: Method, z_re: f64, z_im: f64) -> f64 {
    let h = z_re.hypot(z_im);
    if h == 0.0 {
        return 1.0;
    }
    let sys = Linear {
        a: z_re / h,
        b: z_im / h,
    };
    let cfg = StepperConfig {
        tol: Tolerance::uniform(1e-14, 1e-14),
        h,
        h_max: f64::INFINITY,
        max_steps: 10,
        fixed: true,
    };
    let mut st = Stepper::new(method, cfg);
    st.reset(&sys, 0.0, [1.0, 0.0], false);
    match st.step(&sys, h, f64::INFINITY) {
        Ok(()) => {
            let y = st.y();
            y[0].hypot(y[1])
        }
        Err(_) => f64::INFINITY,
    }
}

/// Largest r such that |R(r·e^{iφ})| ≤ 1 + 1e-9 on (0, r]; None when it
/// holds up to `r_max` (A-stable along that ray as far as checked).
pub fn stability_limit(method: Method, phi: f64, r_max: f64) -> Option<f64> {
    let (c, s) = (phi.cos(), phi.sin());
    let ok = |r: f64| amplification(method, r * c, r * s) <= 1.0 + 1e-9;
    let n = 4000;
    let mut prev = 0.0;
    for i in 1..=n {
        let r = r_max * i as f64 / n as f64;
        if !ok(r) {
            let (mut lo, mut hi) = (prev, r);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if ok(mid) { lo = mid } else { hi = mid }
            }
            return Some(lo);
        }
        prev = r;
    }
    None
}

/// The bound on h·ω for an undamped oscillation (the imaginary axis).
pub fn imaginary_axis_limit(method: Method) -> Option<f64> {
    stability_limit(method, std::f64::consts::FRAC_PI_2, 20.0)
}

/// The bound on h·|λ| for a decaying mode (the negative real axis).
pub fn real_axis_limit(method: Method) -> Option<f64> {
    stability_limit(method, std::f64::consts::PI, 20.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms: RK4 is stable on the imaginary axis up to 2√2 and on the
    /// real axis up to 2.785; Radau IIA is A-stable.
    #[test]
    fn known_limits() {
        let rk4_im = imaginary_axis_limit(Method::Rk4).unwrap();
        assert!((rk4_im - 8f64.sqrt()).abs() < 1e-6, "{rk4_im}");
        let rk4_re = real_axis_limit(Method::Rk4).unwrap();
        assert!((rk4_re - 2.785_293_563).abs() < 1e-6, "{rk4_re}");
        assert!(imaginary_axis_limit(Method::Radau5).is_none());
        assert!(real_axis_limit(Method::Radau5).is_none());
        // DOPRI5's real-axis limit is about 3.31 (Hairer–Nørsett–Wanner I).
        let d5 = real_axis_limit(Method::Dopri5).unwrap();
        assert!((d5 - 3.31).abs() < 0.02, "{d5}");
    }
}
