//! The motor level's drive (model.md, "Fidelity levels": crank speed
//! ripple from a motor curve and flywheel): the motor's torque–speed curve
//! (linear T = T_stall (1 − ω/ω0), or a table), an optional PI speed
//! controller within that curve, the gear (ratio G, efficiency η) and the
//! rotor + flywheel inertia referred to the crank, J_d = J_rotor G² + J_fly.
//!
//! The crank's moment balance with θ2 free: J_d α2 = M_drive − M12, where
//! M_drive = G η T when the motor drives (T ≥ 0) and G T / η when it
//! brakes, and M12 is the drive torque the mechanism demands at the crank
//! (it contains the crank's own I_O α2 and the rod's reaction, so it is
//! affine in α2: the models solve for α2).
//!
//! The state of a motor model ends with the drive's part, laid out by the
//! offsets below from its base index: θ2, ω2, the PI integrator, and
//! quadratures (not error-controlled) for the energy balance and the
//! ripple: the motor's work at its shaft, the gear's loss, the guide
//! friction's, the process's and the joint's (contact + joint friction)
//! absorbed work, ∫ω2² dt, ∫ω2² cos θ2 dt and ∫ω2² sin θ2 dt (dθ2 = ω2 dt,
//! so these are ∫ω2 dθ2 and its first Fourier pair over crank angle), and
//! ∫T² dt (the motor torque's RMS, what heats a motor).

use super::choices::{MotorCurve, SpeedControl};
use super::kinetostatics::{IdealForces, Kinetostatics};
pub use super::motor_params::MotorParams;
use super::params::Params;
use super::table::Table;
use crate::solver::Scale;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Offsets of the drive's part of a motor model's state.
pub const D_THETA2: usize = 0;
pub const D_OMEGA2: usize = 1;
pub const D_PI: usize = 2;
pub const D_W_MOTOR: usize = 3;
pub const D_W_GEAR: usize = 4;
pub const D_W_GUIDE: usize = 5;
pub const D_W_PROC: usize = 6;
pub const D_W_JOINT: usize = 7;
pub const D_Q_W2: usize = 8;
pub const D_Q_WC: usize = 9;
pub const D_Q_WS: usize = 10;
pub const D_Q_T2: usize = 11;
/// Length of the drive's part.
pub const D_LEN: usize = 12;

/// A crank turning slower than this fraction of its operating speed has
/// stalled.
pub const STALL_FRACTION: f64 = 0.01;

/// The motor's torque–speed curve at its shaft, speeds in rad/s.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Curve {
    Linear {
        stall: f64,
        no_load: f64,
    },
    /// Points (rad/s, N·m).
    Table(Table),
}

impl Curve {
    /// Torque at motor speed `wm` (rad/s).
    #[inline]
    pub fn torque(&self, wm: f64) -> f64 {
        match self {
            Curve::Linear { stall, no_load } => stall * (1.0 - wm / no_load),
            Curve::Table(t) => t.eval(wm),
        }
    }

    /// The largest speed the curve describes (rad/s): the no-load speed,
    /// or the table's last speed.
    fn top_speed(&self) -> f64 {
        match self {
            Curve::Linear { no_load, .. } => *no_load,
            Curve::Table(t) => t.points.last().map_or(0.0, |p| p.0),
        }
    }
}

/// A PI speed controller at the motor shaft.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PiControl {
    pub kp: f64,
    pub ki: f64,
    /// Reference motor speed, rad/s.
    pub reference: f64,
}

/// The drive with its constants resolved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotorDrive {
    pub gear: f64,
    pub efficiency: f64,
    /// Rotor + flywheel inertia referred to the crank, J_rotor G² + J_fly.
    pub inertia: f64,
    pub curve: Curve,
    pub control: Option<PiControl>,
    /// The operating point the run starts from.
    pub operating: Operating,
}

/// Where the head runs on average: crank speed, the mean drive torque the
/// ideal mechanism demands there, and how it was found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Operating {
    /// Mean crank speed, rad/s.
    pub omega: f64,
    /// Mean drive torque at the crank (ideal mechanism, constant speed), N·m.
    pub mean_demand_nm: f64,
    /// The motor torque that carries it (motor shaft), N·m: the PI
    /// integrator's start value.
    pub motor_torque_nm: f64,
    /// No-load speed of the linear curve (rev/min of the motor), as given
    /// or as chosen by `auto`.
    pub no_load_rpm: Option<f64>,
    /// false when no speed carries the mean demand (the run will stall).
    pub found: bool,
}

/// Mean drive torque of the ideal mechanism at constant crank speed ω
/// (N·m): the work the process and the guide friction take per
/// revolution over 2π (the inertia torques average out). 360 points of a
/// periodic function.
pub fn mean_demand(ks: &Kinetostatics, omega: f64) -> f64 {
    const N: usize = 360;
    (0..N)
        .map(|i| ks.at(2.0 * PI * i as f64 / N as f64, omega, 0.0).m12)
        .sum::<f64>()
        / N as f64
}

impl MotorDrive {
    /// The drive of a parameter set, with its operating point.
    pub fn of(p: &Params) -> Self {
        let m = &p.motor;
        let g = p.gear_ratio;
        let rpm = 2.0 * PI / 60.0;
        let ks = Kinetostatics::of(p);
        let omega_set = p.omega();
        let mut d = Self {
            gear: g,
            efficiency: m.efficiency,
            inertia: m.rotor_inertia * g * g + m.flywheel_inertia,
            curve: match m.curve {
                MotorCurve::Linear => Curve::Linear {
                    stall: m.stall_torque,
                    no_load: m.no_load_rpm * rpm,
                },
                MotorCurve::Table => Curve::Table(Table {
                    points: m
                        .torque_table
                        .points
                        .iter()
                        .map(|&(w, t)| (w * rpm, t))
                        .collect(),
                }),
            },
            control: None,
            operating: Operating {
                omega: omega_set,
                mean_demand_nm: 0.0,
                motor_torque_nm: 0.0,
                no_load_rpm: None,
                found: false,
            },
        };
        let demand = mean_demand(&ks, omega_set);
        // `auto` no-load speed: the linear curve through the mean demand at
        // the set speed (a motor on a frequency inverter set for it).
        if let Curve::Linear { stall, no_load } = &mut d.curve
            && *no_load == 0.0
        {
            let need = d_from_crank(g, m.efficiency, demand);
            let wm = g * omega_set;
            *no_load = if need < *stall {
                wm / (1.0 - need / *stall)
            } else {
                // No speed carries the demand: a curve through twice the
                // set speed; the run says where it stalls.
                2.0 * wm
            };
        }
        if let Curve::Linear { no_load, .. } = d.curve {
            d.operating.no_load_rpm = Some(no_load / rpm);
        }
        d.operating = match m.control {
            SpeedControl::Pi => {
                d.control = Some(PiControl {
                    kp: m.kp,
                    ki: m.ki,
                    reference: g * omega_set,
                });
                let need = d_from_crank(g, m.efficiency, demand);
                Operating {
                    omega: omega_set,
                    mean_demand_nm: demand,
                    motor_torque_nm: need,
                    found: need <= d.curve.torque(g * omega_set),
                    ..d.operating
                }
            }
            SpeedControl::None => d.equilibrium(&ks, omega_set),
        };
        d
    }

    /// Motor torque at its shaft for crank speed ω2 and PI integrator
    /// state `i`, and the integrator's rate.
    #[inline]
    pub fn torque(&self, omega2: f64, i: f64) -> (f64, f64) {
        let wm = self.gear * omega2;
        let tc = self.curve.torque(wm);
        match self.control {
            None => (tc, 0.0),
            Some(pi) => {
                let e = pi.reference - wm;
                let cmd = pi.kp * e + i;
                let env = tc.max(0.0);
                let t = cmd.clamp(-env, env);
                // Back-calculation anti-windup at the rate ki/kp.
                (t, pi.ki * e + pi.ki / pi.kp * (t - cmd))
            }
        }
    }

    /// Torque at the crank from motor torque `t` (gear losses against the
    /// power flow).
    #[inline]
    pub fn at_crank(&self, t: f64) -> f64 {
        if t >= 0.0 {
            self.gear * self.efficiency * t
        } else {
            self.gear * t / self.efficiency
        }
    }

    /// The open-loop operating point: the crank speed where the curve's
    /// torque at the crank equals the mean demand, searched down from the
    /// curve's top speed (the stable crossing, where the torque falls with
    /// speed). None found: start at the set speed (the run will stall).
    fn equilibrium(&self, ks: &Kinetostatics, omega_set: f64) -> Operating {
        let g = self.gear;
        let excess = |w: f64| self.at_crank(self.curve.torque(g * w)) - mean_demand(ks, w);
        let top = self.curve.top_speed() / g;
        let not_found = Operating {
            omega: omega_set,
            mean_demand_nm: mean_demand(ks, omega_set),
            motor_torque_nm: self.curve.torque(g * omega_set),
            found: false,
            ..self.operating
        };
        if !(top > 0.0) {
            return not_found;
        }
        let n = 32;
        let mut hi = top;
        let mut f_hi = excess(hi);
        if f_hi >= 0.0 {
            // The curve still carries the demand at its top speed (a table
            // that holds its last torque): the head runs there or faster.
            return Operating {
                omega: top,
                mean_demand_nm: mean_demand(ks, top),
                motor_torque_nm: self.curve.torque(g * top),
                found: true,
                ..self.operating
            };
        }
        for k in (0..n).rev() {
            let lo = top * k as f64 / n as f64;
            let f_lo = excess(lo.max(1e-9 * top));
            if f_lo >= 0.0 {
                // Bisection on [lo, hi].
                let (mut a, mut b) = (lo.max(1e-9 * top), hi);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if excess(m) >= 0.0 {
                        a = m;
                    } else {
                        b = m;
                    }
                    if b - a <= 1e-13 * b {
                        break;
                    }
                }
                let w = 0.5 * (a + b);
                return Operating {
                    omega: w,
                    mean_demand_nm: mean_demand(ks, w),
                    motor_torque_nm: self.curve.torque(g * w),
                    found: true,
                    ..self.operating
                };
            }
            hi = lo;
            f_hi = f_lo;
        }
        let _ = f_hi;
        not_found
    }

    /// The crank speed below which the head counts as stalled (rad/s):
    /// [`STALL_FRACTION`] of the operating speed. (With the regularized
    /// process law a pin bar held by the part creeps at the friction
    /// ramp's speeds instead of stopping.)
    pub fn stall_speed(&self) -> f64 {
        STALL_FRACTION * self.operating.omega
    }

    /// The PI integrator's start value (the torque that carries the mean
    /// demand), 0 without a controller.
    pub fn integrator_start(&self) -> f64 {
        if self.control.is_some() {
            self.operating.motor_torque_nm
        } else {
            0.0
        }
    }

    /// Fills the drive's part (from state index `base`) of a model's
    /// tolerance: the error scales of its controlled states (θ2 at
    /// `theta_scale` rad, ω2 relative, the integrator against the stall
    /// torque) and the absolute tolerance `atol` (m) on θ2 and ω2 through
    /// the crank length `r` (m).
    pub fn fill_tolerance<const DIM: usize>(
        &self,
        base: usize,
        theta_scale: Scale,
        atol: f64,
        r: f64,
        scale: &mut [Scale; DIM],
        at: &mut [f64; DIM],
    ) {
        let t_ref = match &self.curve {
            Curve::Linear { stall, .. } => *stall,
            Curve::Table(t) => t.points.iter().map(|p| p.1.abs()).fold(0.0, f64::max),
        };
        scale[base + D_THETA2] = theta_scale;
        scale[base + D_OMEGA2] = Scale::Relative;
        scale[base + D_PI] = Scale::Fixed(t_ref.max(1e-9));
        at[base + D_THETA2] = atol / r;
        at[base + D_OMEGA2] = atol / r;
    }
}

/// Motor torque that gives `m` at the crank (inverse of `at_crank`).
fn d_from_crank(g: f64, eff: f64, m: f64) -> f64 {
    if m >= 0.0 { m / (g * eff) } else { m * eff / g }
}

/// Solves J_d α2 + M12(α2) = M_drive for the ideal mechanism: M12 is affine
/// in α2 except where the guide's normal force changes sign (its friction
/// |N| has a kink), so the line through α2 = 0 and 1 is exact unless the
/// branch changed, and secant steps find the other branch's root.
pub fn solve_alpha2(
    ks: &Kinetostatics,
    theta2: f64,
    s2: f64,
    c2: f64,
    omega2: f64,
    j_d: f64,
    m_drive: f64,
) -> (f64, IdealForces) {
    let f0 = ks.at_sc(theta2, s2, c2, omega2, 0.0);
    let r0 = f0.m12 - m_drive;
    let f1 = ks.at_sc(theta2, s2, c2, omega2, 1.0);
    let slope = j_d + f1.m12 - f0.m12;
    let mut a = -r0 / slope;
    let mut f = ks.at_sc(theta2, s2, c2, omega2, a);
    let mut r = j_d * a + f.m12 - m_drive;
    let tol = 1e-14 * (m_drive.abs() + f0.m12.abs() + f1.m12.abs() + (j_d * a).abs());
    let (mut ap, mut rp) = (0.0, r0);
    for _ in 0..6 {
        if !(r.abs() > tol) {
            break;
        }
        let s = (r - rp) / (a - ap);
        if !(s > 0.0) {
            break;
        }
        let an = a - r / s;
        ap = a;
        rp = r;
        a = an;
        f = ks.at_sc(theta2, s2, c2, omega2, a);
        r = j_d * a + f.m12 - m_drive;
    }
    (a, f)
}

/// The drive's derivatives: θ2, ω2, the integrator, the energy and ripple
/// quadratures. `losses` = (guide, process, joint) absorbed power, W.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn drive_derivatives(
    dy: &mut [f64],
    base: usize,
    drive: &MotorDrive,
    omega2: f64,
    alpha2: f64,
    s2: f64,
    c2: f64,
    t_motor: f64,
    m_drive: f64,
    di: f64,
    losses: (f64, f64, f64),
) {
    let w = omega2;
    dy[base + D_THETA2] = w;
    dy[base + D_OMEGA2] = alpha2;
    dy[base + D_PI] = di;
    let p_motor = t_motor * drive.gear * w;
    dy[base + D_W_MOTOR] = p_motor;
    dy[base + D_W_GEAR] = p_motor - m_drive * w;
    dy[base + D_W_GUIDE] = losses.0;
    dy[base + D_W_PROC] = losses.1;
    dy[base + D_W_JOINT] = losses.2;
    let w2 = w * w;
    dy[base + D_Q_W2] = w2;
    dy[base + D_Q_WC] = w2 * c2;
    dy[base + D_Q_WS] = w2 * s2;
    dy[base + D_Q_T2] = t_motor * t_motor;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The auto no-load speed puts the operating point at the set speed;
    /// the PI controller's integrator starts at the torque that carries
    /// the mean demand.
    #[test]
    fn operating_point_at_the_set_speed() {
        let p = Params::paper();
        let d = MotorDrive::of(&p);
        assert!(d.operating.found);
        assert!(
            (d.operating.omega / p.omega() - 1.0).abs() < 1e-9,
            "{:?}",
            d.operating
        );
        let at = d.at_crank(d.curve.torque(d.gear * d.operating.omega));
        assert!((at - d.operating.mean_demand_nm).abs() < 1e-9);
        // The demand is the process and guide work per revolution / 2π.
        assert!(d.operating.mean_demand_nm > 0.0);
        let mut p2 = p.clone();
        p2.motor.control = SpeedControl::Pi;
        let d2 = MotorDrive::of(&p2);
        assert!((d2.integrator_start() - d2.operating.mean_demand_nm).abs() < 1e-12);
        let (t, di) = d2.torque(p2.omega(), d2.integrator_start());
        assert!((t - d2.integrator_start()).abs() < 1e-15 && di == 0.0);
    }

    /// An explicit linear curve: the equilibrium lies where the curve meets
    /// the mean demand, below the no-load speed.
    #[test]
    fn open_loop_equilibrium_on_an_explicit_curve() {
        let mut p = Params::paper();
        p.motor.no_load_rpm = 1300.0;
        p.motor.stall_torque = 0.5;
        p.gear_ratio = 2.0;
        p.motor.efficiency = 0.8;
        let d = MotorDrive::of(&p);
        let ks = Kinetostatics::of(&p);
        let w = d.operating.omega;
        assert!(d.operating.found && w < 1300.0 * 2.0 * PI / 60.0 / 2.0);
        let supply = 2.0 * 0.8 * 0.5 * (1.0 - 2.0 * w / (1300.0 * 2.0 * PI / 60.0));
        assert!((supply - mean_demand(&ks, w)).abs() < 1e-9, "{supply}");
        // Braking through the gear costs 1/η.
        assert!((d.at_crank(-1.0) + 2.0 / 0.8).abs() < 1e-15);
    }

    /// The α2 solve satisfies the crank's balance on both sides of the
    /// guide friction's kink.
    #[test]
    fn alpha2_solves_the_crank_balance() {
        let mut p = Params::paper();
        p.mu_g = 0.4;
        p.gravity = [9.81, 4.0];
        let ks = Kinetostatics::of(&p);
        for i in 0..72 {
            let th = (i as f64 * 5.0 + 0.3).to_radians();
            let (s2, c2) = th.sin_cos();
            for m_d in [-2.0, 0.0, 0.05, 3.0] {
                let (a, f) = solve_alpha2(&ks, th, s2, c2, 120.0, 1e-5, m_d);
                let res = 1e-5 * a + f.m12 - m_d;
                assert!(res.abs() < 1e-10, "θ {i}: residual {res}");
            }
        }
    }
}
