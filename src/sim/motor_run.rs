//! Level `motor`: the crank driven by a motor through its gear, with the
//! flywheel — the speed ripple, the torque demanded of the motor and the
//! energy balance, on top of every summary figure of the levels below.
//!
//! c = 0 runs the one-degree-of-freedom model (`model::motor_rigid`), c > 0
//! the clearance ODE with θ2 free (`model::motor_clearance`); both through
//! the event loop of [`super::clearance_run`], which locates contact events
//! and the stall (ω2 reaching zero: a clear error naming the crank angle
//! and the revolution, never a hang).
//!
//! The protocol's revolutions are counted at the operating speed (the
//! crank period 2π/ω_op): with the open-loop curve the head need not run
//! at `motor_rpm`. The ideal figures compare with the ideal mechanism at
//! that speed.

use super::clearance_run::{Finished, RunSetup, run_model};
pub use super::summary::{EnergyBalance, MotorSummary};
use super::summary::{Q_TM, Q_W2MAX, Q_W2MIN};
use super::{SimError, SimOptions, SimResult};
use crate::model::joint_model::JointModel;
use crate::model::motor::*;
use crate::model::motor_clearance::{self, MotorClearanceModel};
use crate::model::motor_rigid::{self, RigidMotorModel};
use crate::model::params::{Driver, Params};
use crate::progress::Progress;
use std::f64::consts::TAU;

/// What the summary needs of a motor model beyond the event loop.
trait MotorModel<const N: usize>: JointModel<N> {
    fn drive(&self) -> &MotorDrive;
    /// Index of the drive's part of the state.
    const BASE: usize;
    /// (kinetic, potential, elastic) energy at state y, J.
    fn energy(&self, y: &[f64; N]) -> (f64, f64, f64);
}

/// Gravity's potential −Σ m g·r of the three moving bodies.
fn potential(
    p: &crate::model::kinetostatics::Inertia,
    g2: [f64; 2],
    g3: [f64; 2],
    p4: [f64; 2],
) -> f64 {
    let g = p.g;
    -(p.m2 * (g[0] * g2[0] + g[1] * g2[1])
        + p.m3 * (g[0] * g3[0] + g[1] * g3[1])
        + p.m4 * (g[0] * p4[0] + g[1] * p4[1]))
}

impl MotorModel<{ motor_rigid::DIM }> for RigidMotorModel {
    const BASE: usize = motor_rigid::BASE;
    fn drive(&self) -> &MotorDrive {
        &self.drive
    }
    fn energy(&self, y: &[f64; motor_rigid::DIM]) -> (f64, f64, f64) {
        let th = y[motor_rigid::THETA2];
        let w = y[motor_rigid::OMEGA2];
        let ke = 0.5 * self.drive.inertia * w * w + self.ks.kinetic_energy(th, w);
        let pose = self.geom.pose(th, w, 0.0);
        let i = &self.ks.inertia;
        let (s2, c2) = th.sin_cos();
        let a = [self.geom.r * c2, self.geom.r * s2];
        let pe = potential(
            i,
            [i.lc2 * c2, i.lc2 * s2],
            [a[0] + i.lc3 * pose.c3, a[1] + i.lc3 * pose.s3],
            [pose.x4, self.geom.offset],
        );
        (ke, pe, 0.0)
    }
}

impl MotorModel<{ motor_clearance::DIM }> for MotorClearanceModel {
    const BASE: usize = motor_clearance::BASE;
    fn drive(&self) -> &MotorDrive {
        &self.drive
    }
    fn energy(&self, y: &[f64; motor_clearance::DIM]) -> (f64, f64, f64) {
        use crate::model::clearance::{OMEGA3, THETA3, V4, X4};
        let m = &self.inner;
        let i = &m.inertia;
        let r = m.geom.r;
        let th = y[motor_clearance::THETA2];
        let w = y[motor_clearance::OMEGA2];
        let (s2, c2) = th.sin_cos();
        let (s3, c3) = y[THETA3].sin_cos();
        let w3 = y[OMEGA3];
        let v_g3 = [-r * w * s2 - i.lc3 * w3 * s3, r * w * c2 + i.lc3 * w3 * c3];
        let ke = 0.5 * (self.drive.inertia + i.i_o()) * w * w
            + 0.5 * i.m3 * (v_g3[0] * v_g3[0] + v_g3[1] * v_g3[1])
            + 0.5 * i.i3 * w3 * w3
            + 0.5 * i.m4 * y[V4] * y[V4];
        let a = [r * c2, r * s2];
        let pe = potential(
            i,
            [i.lc2 * c2, i.lc2 * s2],
            [a[0] + i.lc3 * c3, a[1] + i.lc3 * s3],
            [y[X4], m.geom.offset],
        );
        let (delta, _) = self.penetration(0.0, y);
        let el = if delta > 0.0 {
            0.4 * m.law.k * delta * delta * delta.sqrt()
        } else {
            0.0
        };
        (ke, pe, el)
    }
}

/// The crank speed the lower levels use when a motor drives the head:
/// its operating speed, as `motor_rpm` (rev/min of the motor).
pub fn operating_params(p: &Params) -> (Params, MotorDrive) {
    let drive = MotorDrive::of(p);
    let mut q = p.clone();
    q.motor_rpm = drive.operating.omega * p.gear_ratio * 60.0 / TAU;
    (q, drive)
}

/// Runs the motor level.
pub fn run(p: &Params, opts: &SimOptions, progress: &Progress) -> Result<SimResult, SimError> {
    let (ideal, drive) = operating_params(p);
    let omega = drive.operating.omega;
    let how = RunSetup {
        ideal: &ideal,
        period: TAU / omega,
        omega,
        level: "motor",
    };
    let mut result = if p.clearance == 0.0 {
        finish(p, RigidMotorModel::new(p), &how, opts, progress)?
    } else {
        finish(p, MotorClearanceModel::new(p), &how, opts, progress)?
    };
    if p.driver != Driver::Motor {
        result.notes.push(
            "driver = constant_speed in the parameters: level motor ran with the motor keys as they are (set driver = \"motor\" for a motor-driven head)".into(),
        );
    }
    if !drive.operating.found {
        result.notes.push(format!(
            "no motor speed carries the mean drive torque of {:.4} N·m: the run started at the set speed",
            drive.operating.mean_demand_nm
        ));
    }
    Ok(result)
}

fn finish<M: MotorModel<N>, const N: usize>(
    p: &Params,
    model: M,
    how: &RunSetup,
    opts: &SimOptions,
    progress: &Progress,
) -> Result<SimResult, SimError> {
    let drive = model.drive().clone();
    let theta_tdc = model.theta2(0.0, &model.initial_state(0.0));
    let energy_model = model.clone();
    let Finished {
        mut result,
        window_start: (t0, y0),
        end: (t1, y1),
        best,
    } = run_model(p, opts, model, how, progress)?;
    let b = M::BASE;
    let d = |i: usize| y1[b + i] - y0[b + i];
    let dt = t1 - t0;
    let (tha, thb) = (y0[b + D_THETA2], y1[b + D_THETA2]);
    let turned = thb - tha;
    let rpm = 60.0 / TAU;
    let mean_w = turned / dt;
    // First harmonic over crank angle, the mean's leakage over a window
    // that is not a whole number of turns removed.
    // (A window of one period at the operating speed turns a hair less or
    // more than a revolution: the leakage correction covers it.)
    let (h1, phase) = if turned >= 0.95 * TAU {
        let w_bar = d(D_Q_W2) / turned;
        let c = d(D_Q_WC) - w_bar * (thb.sin() - tha.sin());
        let s = d(D_Q_WS) - w_bar * (tha.cos() - thb.cos());
        let amp = 2.0 / turned * c.hypot(s);
        let phase = (s.atan2(c) - theta_tdc).rem_euclid(TAU).to_degrees();
        (Some(amp / w_bar * 100.0), Some(phase))
    } else {
        (None, None)
    };
    let (k0, v0, e0) = energy_model.energy(&y0);
    let (k1, v1, e1) = energy_model.energy(&y1);
    let w_motor = d(D_W_MOTOR);
    let gear = d(D_W_GEAR);
    let guide = d(D_W_GUIDE);
    let proc_ = d(D_W_PROC);
    let joint = d(D_W_JOINT);
    let energy = EnergyBalance {
        motor_work_j: w_motor,
        gear_loss_j: gear,
        guide_friction_j: guide,
        process_work_j: proc_,
        impact_and_joint_friction_j: joint - (e1 - e0),
        kinetic_change_j: k1 - k0,
        potential_change_j: v1 - v0,
        elastic_change_j: e1 - e0,
        residual_j: w_motor - gear - guide - proc_ - joint - (k1 - k0) - (v1 - v0),
    };
    let (w_max, w_min) = (best[Q_W2MAX], -best[Q_W2MIN]);
    result.summary.motor = Some(MotorSummary {
        curve: p.motor.curve.name().into(),
        control: p.motor.control.name().into(),
        operating_crank_rpm: drive.operating.omega * rpm,
        no_load_rpm: drive.operating.no_load_rpm,
        drive_inertia_kgm2: drive.inertia,
        mean_crank_rpm: mean_w * rpm,
        min_crank_rpm: w_min * rpm,
        max_crank_rpm: w_max * rpm,
        ripple_p2p_pct: (w_max - w_min) / mean_w * 100.0,
        ripple_h1_pct: h1,
        ripple_h1_phase_deg: phase,
        peak_motor_torque_nm: best[Q_TM],
        rms_motor_torque_nm: (d(D_Q_T2) / dt).max(0.0).sqrt(),
        mean_motor_power_w: w_motor / dt,
        curve_torque_at_mean_nm: drive.curve.torque(drive.gear * mean_w),
        energy,
    });
    Ok(result)
}
