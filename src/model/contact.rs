//! Contact-impact law of the clearance joint, friction smoothing and the
//! process load (model.md, "Clearance joint contact" and "Loads").

use super::params::{ContactModel, Params, ProcessLaw};
use super::table::Table;
use serde::Serialize;

/// Hertz stiffness of a journal inside a bearing (internal cylinders):
/// K = (4/3) / (σ_J + σ_B) · sqrt(R_J R_B / (R_B − R_J)), N/m^1.5.
/// Infinite when the clearance is zero (the joint is then ideal).
pub fn hertz_stiffness(p: &Params) -> f64 {
    let rb = p.rb();
    if p.clearance <= 0.0 {
        return f64::INFINITY;
    }
    (4.0 / 3.0) / (p.journal.sigma() + p.bearing.sigma()) * (p.rj * rb / p.clearance).sqrt()
}

/// The normal-force law with its constants resolved.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ContactLaw {
    /// Stiffness K, N/m^1.5.
    pub k: f64,
    /// Hysteresis factor D.
    pub d: f64,
    /// Floor on the onset approach velocity, m/s.
    pub approach_floor: f64,
    pub model: ContactModel,
}

impl ContactLaw {
    pub fn of(p: &Params) -> Self {
        Self {
            k: hertz_stiffness(p),
            d: p.contact_model.damping_factor(p.restitution),
            approach_floor: p.approach_floor,
            model: p.contact_model,
        }
    }

    /// F_N = max(0, K δ^1.5 (1 + D δ̇ / δ̇⁻)) for penetration δ (≤ 0: no force),
    /// penetration rate δ̇ and onset approach velocity δ̇⁻ (floored).
    #[inline]
    pub fn normal_force(&self, delta: f64, delta_dot: f64, approach: f64) -> f64 {
        if delta <= 0.0 {
            return 0.0;
        }
        // D/δ̇⁻ does not wait for δ̇ (the division is off the right-hand
        // side's critical path).
        let damping = self.d / approach.max(self.approach_floor);
        let f = self.k * delta * delta.sqrt() * (1.0 + damping * delta_dot);
        f.max(0.0)
    }

    /// Natural angular frequency of small contact oscillations at penetration
    /// δ for an effective mass m: ω = sqrt(1.5 K sqrt(δ) / m) (pitfalls.md).
    pub fn frequency(&self, delta: f64, m_eff: f64) -> f64 {
        (1.5 * self.k * delta.max(0.0).sqrt() / m_eff).sqrt()
    }
}

/// The friction smoothing ramp c_d(|v|): 0 below v0, 1 above v1, linear between.
#[inline]
pub fn smoothing(v_abs: f64, v0: f64, v1: f64) -> f64 {
    if v_abs <= v0 {
        0.0
    } else if v_abs >= v1 {
        1.0
    } else {
        (v_abs - v0) / (v1 - v0)
    }
}

/// Modified Coulomb friction force (Ambrósio): −coef · c_d(|v|) · N · sign(v).
#[inline]
pub fn coulomb(coef: f64, normal: f64, v: f64, v0: f64, v1: f64) -> f64 {
    if coef == 0.0 || normal == 0.0 {
        return 0.0;
    }
    -coef * smoothing(v.abs(), v0, v1) * normal * v.signum()
}

/// The process load on the pin bar from the part.
#[derive(Debug, Clone, Serialize)]
pub struct ProcessLoad {
    pub standoff: f64,
    pub f_ins: Table,
    pub f_wd: Table,
    pub v0: f64,
    pub v1: f64,
    /// `regularized` (the c_d ramp) or `stick` (set-valued: see
    /// [`ProcessMode`]; the ideal mechanism takes the plain sign law, its
    /// pin bar stops only at the dead centres' instants).
    pub law: ProcessLaw,
}

/// Under the stick law, what the part does to the pin bar: resists it
/// moving down (−F_ins) or up (+F_wd), or holds it at rest with whatever
/// force within −F_ins … +F_wd balances the others. Switched at located
/// events (model.md, "Loads"); the regularized law ignores it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum ProcessMode {
    #[default]
    Down,
    Up,
    Held,
}

impl ProcessLoad {
    pub fn of(p: &Params) -> Self {
        Self {
            standoff: p.standoff,
            f_ins: p.f_ins.clone(),
            f_wd: p.f_wd.clone(),
            v0: p.v0,
            v1: p.v1,
            law: p.process_law,
        }
    }

    /// The force in a mode of the stick law (Down, Up; Held is decided by
    /// the balance, not here), or the regularized law's.
    #[inline(always)]
    pub fn force_in(&self, pm: ProcessMode, s: f64, v4: f64) -> f64 {
        if self.law == ProcessLaw::Regularized {
            return self.force(s, v4);
        }
        let d = s - self.standoff;
        if d <= 0.0 {
            return 0.0;
        }
        match pm {
            ProcessMode::Down => -self.f_ins.eval(d),
            ProcessMode::Up => self.f_wd.eval(d),
            ProcessMode::Held => 0.0,
        }
    }

    /// The interval the part's force may take while it holds the pin bar
    /// at stroke `s`: (−F_ins(d), F_wd(d)); (0, 0) out of the part.
    #[inline]
    pub fn hold_range(&self, s: f64) -> (f64, f64) {
        let d = s - self.standoff;
        if d <= 0.0 {
            (0.0, 0.0)
        } else {
            (-self.f_ins.eval(d), self.f_wd.eval(d))
        }
    }

    /// Force along x on the pin bar at stroke `s` and velocity `v4`:
    /// −F_ins(d)·c_d(v4) moving down, +F_wd(d)·c_d(|v4|) moving up, zero
    /// before the pin meets the part (d = s − standoff ≤ 0).
    /// Under the stick law this is the plain sign law (the ideal mechanism's).
    #[inline(always)]
    pub fn force(&self, s: f64, v4: f64) -> f64 {
        let d = s - self.standoff;
        if d <= 0.0 {
            return 0.0;
        }
        if self.law == ProcessLaw::Stick {
            return if v4 > 0.0 {
                -self.f_ins.eval(d)
            } else if v4 < 0.0 {
                self.f_wd.eval(d)
            } else {
                0.0
            };
        }
        if v4 > 0.0 {
            -self.f_ins.eval(d) * smoothing(v4, self.v0, self.v1)
        } else if v4 < 0.0 {
            self.f_wd.eval(d) * smoothing(-v4, self.v0, self.v1)
        } else {
            0.0
        }
    }

    pub fn is_zero(&self) -> bool {
        self.f_ins.is_zero() && self.f_wd.is_zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flores_stiffness_values() {
        let mut p = Params::flores();
        assert!((hertz_stiffness(&p) / 6.6102e10 - 1.0).abs() < 1e-4);
        p.clearance = 0.25e-3;
        assert!((hertz_stiffness(&p) / 9.2306e10 - 1.0).abs() < 1e-4);
        p.clearance = 0.1e-3;
        assert!((hertz_stiffness(&p) / 1.44822e11 - 1.0).abs() < 1e-5);
        p.clearance = 0.0;
        assert!(hertz_stiffness(&p).is_infinite());
    }

    #[test]
    fn normal_force_law() {
        let law = ContactLaw {
            k: 1e10,
            d: 0.5,
            approach_floor: 1e-3,
            model: ContactModel::LankaraniNikravesh,
        };
        assert_eq!(law.normal_force(-1e-6, 1.0, 1.0), 0.0);
        let d: f64 = 1e-6;
        let f0 = 1e10 * d.powf(1.5);
        assert!((law.normal_force(d, 0.0, 1.0) - f0).abs() < 1e-9 * f0);
        assert!((law.normal_force(d, 1.0, 1.0) - 1.5 * f0).abs() < 1e-9 * f0);
        // Large separation speed: the force is clipped at zero, never pulls.
        assert_eq!(law.normal_force(d, -3.0, 1.0), 0.0);
        // The approach velocity is floored.
        assert!((law.normal_force(d, 1e-3, 0.0) - 1.5 * f0).abs() < 1e-9 * f0);
    }

    #[test]
    fn smoothing_and_coulomb() {
        assert_eq!(smoothing(0.5e-4, 1e-4, 1e-3), 0.0);
        assert!((smoothing(5.5e-4, 1e-4, 1e-3) - 0.5).abs() < 1e-12);
        assert_eq!(smoothing(2.0, 1e-4, 1e-3), 1.0);
        assert_eq!(coulomb(0.1, 10.0, 2.0, 1e-4, 1e-3), -1.0);
        assert_eq!(coulomb(0.1, 10.0, -2.0, 1e-4, 1e-3), 1.0);
        assert_eq!(coulomb(0.1, 10.0, 0.0, 1e-4, 1e-3), 0.0);
    }

    #[test]
    fn process_load_resists_motion() {
        let p = Params::paper();
        let pl = ProcessLoad::of(&p);
        assert_eq!(pl.force(13e-3, 1.0), 0.0);
        assert!((pl.force(14.35e-3, 1.0) + 14.5).abs() < 1e-9);
        assert_eq!(pl.force(16e-3, 1.0), -23.0);
        // Moving up with no withdrawal table: no force.
        assert_eq!(pl.force(15e-3, -1.0), 0.0);
        // At rest the regularized law gives no force.
        assert_eq!(pl.force(15e-3, 0.0), 0.0);
    }

    /// The stick law: full force while sliding (no ramp), the hold range
    /// −F_ins … F_wd in the part, nothing outside it.
    #[test]
    fn stick_law_forces_and_hold_range() {
        let mut p = Params::paper();
        p.process_law = ProcessLaw::Stick;
        p.f_wd = Table::from_mm(&[(0.0, 1.0), (2.0, 3.0)]).unwrap();
        let pl = ProcessLoad::of(&p);
        // Sliding slowly down: the whole F_ins, not a ramp of it.
        assert_eq!(pl.force_in(ProcessMode::Down, 16e-3, 1e-9), -23.0);
        assert!((pl.force_in(ProcessMode::Up, 15e-3, -1e-9) - 2.0).abs() < 1e-12);
        assert_eq!(pl.force_in(ProcessMode::Down, 13e-3, 1.0), 0.0);
        let (lo, hi) = pl.hold_range(15e-3);
        // d = 1 mm: F_ins = 21 + 2 · 0.5 / 1.5 N, F_wd = 1 + 2 · 1 / 2 N.
        assert!((lo + 21.0 + 2.0 / 3.0).abs() < 1e-12 && (hi - 2.0).abs() < 1e-12);
        assert_eq!(pl.hold_range(13e-3), (0.0, 0.0));
        // The ideal mechanism's sign law.
        assert_eq!(pl.force(16e-3, 1e-9), -23.0);
        assert_eq!(pl.force(16e-3, 0.0), 0.0);
    }
}
