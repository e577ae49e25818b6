//! The mechanism's true signals a synthetic log is made from: the ideal
//! mechanism with the quasi-static process law, or a clearance-model run.

use super::*;
use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::model::table::Table;
use std::f64::consts::TAU;

/// The mechanism's true signals.
pub trait Truth: Sync {
    /// Stroke (mm, from TDC) and load-cell force (N, + = pin pushed into the part)
    /// at crank angle θ2 (rad, unwrapped) turning at ω2 (rad/s), simulation time t (s).
    fn eval(&self, t: f64, theta2: f64, omega2: f64) -> (f64, f64);
}

/// The ideal (zero-clearance) mechanism with the regularised process law
/// evaluated quasi-statically: force = F_ins(depth)·c_d(v4) moving down,
/// F_wd(depth)·c_d(|v4|) moving up (as a load-cell reading, + into the part).
#[derive(Debug, Clone)]
pub struct IdealTruth {
    pub geometry: Geometry,
    pub standoff_m: f64,
    pub f_ins: Table,
    pub f_wd: Table,
    pub v0: f64,
    pub v1: f64,
}

impl IdealTruth {
    pub fn from_params(p: &Params) -> Self {
        IdealTruth {
            geometry: Geometry::of(p),
            standoff_m: p.standoff,
            f_ins: p.f_ins.clone(),
            f_wd: p.f_wd.clone(),
            v0: p.v0,
            v1: p.v1,
        }
    }
}

/// The process law's velocity ramp: the model's c_d (0 below v0, 1 above
/// v1), so the synthetic truth and the model share one definition.
pub(super) use crate::model::contact::smoothing as cd;

impl Truth for IdealTruth {
    fn eval(&self, _t: f64, theta2: f64, omega2: f64) -> (f64, f64) {
        let pose = self.geometry.pose(theta2, omega2, 0.0);
        let s = pose.x4 - self.geometry.x4_tdc();
        let d = s - self.standoff_m;
        let f = if d > 0.0 {
            if pose.v4 > 0.0 {
                self.f_ins.eval(d) * cd(pose.v4, self.v0, self.v1)
            } else {
                -self.f_wd.eval(d) * cd(-pose.v4, self.v0, self.v1)
            }
        } else {
            0.0
        };
        (s * 1e3, f)
    }
}

/// The clearance-joint model as the truth: the mechanism simulated at the
/// clearance level (constant crank speed at the configured motor speed)
/// through the whole log after a warm-up, sampled on a fine crank-angle grid
/// and interpolated linearly in θ2. The speed ripple acts as a time warp of
/// this trajectory (as in the interop logs), so the truth is a function of θ2
/// only. The motion is chaotic: the log's cycles are realisations of the
/// attractor, not copies of one cycle.
#[derive(Debug, Clone)]
pub struct ModelTruth {
    /// θ2 (unwrapped, rad) of the first grid point; a top dead centre.
    theta_first: f64,
    dtheta: f64,
    stroke_mm: Vec<f64>,
    force_n: Vec<f64>,
}

impl ModelTruth {
    /// Simulates `p` for the log `cfg` describes: `warmup` revolutions, then
    /// every revolution the log spans, sampled every `grid_deg` degrees,
    /// integrated with DOP853 at relative tolerance `rtol`.
    pub fn simulate(
        p: &Params,
        cfg: &SynthConfig,
        warmup: f64,
        grid_deg: f64,
        rtol: f64,
    ) -> Result<Self, crate::sim::SimError> {
        Self::simulate_perturbed(p, cfg, warmup, grid_deg, rtol, 0.0)
    }

    /// [`ModelTruth::simulate`] from a pin bar started `perturb_x4` (m) off
    /// the model's initial position: another realisation of the chaotic
    /// clearance motion (the calibration's own predictions start at 0, so a
    /// log made from them would share their trajectory for the first
    /// revolutions; a real rig does not).
    pub fn simulate_perturbed(
        p: &Params,
        cfg: &SynthConfig,
        warmup: f64,
        grid_deg: f64,
        rtol: f64,
        perturb_x4: f64,
    ) -> Result<Self, crate::sim::SimError> {
        let mut p = p.clone();
        p.motor_rpm = cfg.motor_rpm;
        p.gear_ratio = cfg.gear_ratio;
        let tdc = Geometry::of(&p).tdc_angle();
        let (th0, _) = cfg.crank(0.0);
        let (th1, _) = cfg.crank(cfg.duration_s());
        let theta_first = tdc + ((th0 - tdc) / TAU).floor() * TAU;
        let revs = ((th1 - theta_first) / TAU).ceil() + 1.0;
        let so = crate::sim::SimOptions {
            level: crate::sim::Level::Clearance,
            warmup: warmup.max(0.0).ceil(),
            revs,
            rtol,
            grid_deg: Some(grid_deg),
            perturb_x4,
            ..crate::sim::SimOptions::default()
        };
        let r = crate::sim::simulate(&p, &so, &crate::progress::Progress::hidden())?;
        let c = r.curves.unwrap_or_default();
        Ok(ModelTruth {
            theta_first,
            dtheta: grid_deg.to_radians(),
            force_n: c
                .process_force_n
                .iter()
                .map(|f| if f.is_finite() { *f } else { 0.0 })
                .collect(),
            stroke_mm: c.stroke_mm,
        })
    }
}

impl Truth for ModelTruth {
    fn eval(&self, _t: f64, theta2: f64, _omega2: f64) -> (f64, f64) {
        let n = self.stroke_mm.len().min(self.force_n.len());
        if n == 0 {
            return (f64::NAN, f64::NAN);
        }
        let x = ((theta2 - self.theta_first) / self.dtheta).clamp(0.0, (n - 1) as f64);
        let i = (x.floor() as usize).min(n.saturating_sub(2));
        let w = x - i as f64;
        let j = (i + 1).min(n - 1);
        let lerp = |v: &[f64]| v[i] + w * (v[j] - v[i]);
        (lerp(&self.stroke_mm), lerp(&self.force_n))
    }
}
