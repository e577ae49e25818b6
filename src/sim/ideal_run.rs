//! Levels `kinematic` and `ideal`: closed form at every crank angle.

use super::summary::{PeakTracker, Q_ACC, Q_FN, Q_M12, Q_PROC, Q_SMAX, Q_SMIN, quantities};
use super::{Curves, SimOptions, SimResult, Summary};
use crate::model::clearance::Outputs;
use crate::model::kinematics::Geometry;
use crate::model::kinetostatics::Kinetostatics;
use crate::model::params::Params;
use crate::solver::Stats;
use crate::solver::roots::maximize;
use std::time::Instant;

/// The ideal mechanism's outputs at time t (crank at TDC at t = 0).
/// At this level `f_n` is the magnitude of the rod–pin-bar joint force.
pub fn ideal_outputs(ks: &Kinetostatics, theta0: f64, omega: f64, t: f64) -> Outputs {
    let theta2 = theta0 + omega * t;
    let f = ks.at(theta2, omega, 0.0);
    let s = f.pose.x4 - ks.geom.x4_tdc();
    Outputs::rigid(t, (theta2, omega, 0.0), f64::NAN, s, &f)
}

pub fn run(p: &Params, opts: &SimOptions) -> SimResult {
    let start = Instant::now();
    let ks = Kinetostatics::of(p);
    let geom = Geometry::of(p);
    let theta0 = geom.tdc_angle();
    let omega = p.omega();
    let period = p.period();
    let t0 = opts.warmup * period;
    let t1 = (opts.warmup + opts.revs) * period;
    let forces = opts.level != super::Level::Kinematic;
    let mut evals = 0u64;
    let eval = |t: f64, evals: &mut u64| {
        *evals += 1;
        ideal_outputs(&ks, theta0, omega, t)
    };
    // Peaks: a 0.5° scan, then Brent around every discrete local maximum.
    let n_scan = ((opts.revs * 720.0).ceil() as usize).max(4);
    let dt = (t1 - t0) / n_scan as f64;
    let mut tracker = PeakTracker::new();
    let first = eval(t0, &mut evals);
    tracker.start(t0, quantities(&first));
    let mut prev_t = t0;
    for i in 1..=n_scan {
        let t = t0 + dt * i as f64;
        let o = eval(t, &mut evals);
        let refine = tracker.push(t, quantities(&o));
        for (q, &r) in refine.iter().enumerate() {
            if r {
                let a = (prev_t - dt).max(t0);
                let (_, v, n) = maximize(
                    |tt| quantities(&ideal_outputs(&ks, theta0, omega, tt))[q],
                    a,
                    t,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                    dt * 1e-7,
                );
                evals += n as u64;
                tracker.offer(q, v);
            }
        }
        prev_t = t;
    }
    let best = tracker.best;
    // Curves.
    let curves = opts.grid_deg.map(|g| {
        let n = ((opts.revs * 360.0 / g) + 1e-9).floor() as usize;
        let dtg = g.to_radians() / omega;
        let mut c = Curves::with_capacity(n + 1);
        for k in 0..=n {
            let o = eval(t0 + dtg * k as f64, &mut evals);
            c.push(&o, forces);
        }
        c
    });
    let summary = Summary {
        preset: p.preset.clone(),
        motor_rpm: p.motor_rpm,
        clearance_mm: p.clearance * 1e3,
        material: p.material_name(),
        contact_model: p.contact_model.name().into(),
        level: opts.level.name().into(),
        method: "closed form".into(),
        rtol: 0.0,
        atol: 0.0,
        step_s: None,
        warmup_revs: opts.warmup,
        revs: opts.revs,
        view: "closed form (periodic)".into(),
        steps: 0,
        rejected_steps: 0,
        rhs_evals: 0,
        aux_evals: evals,
        jacobians: 0,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        n_impacts: 0,
        peak_accel_mps2: best[Q_ACC],
        peak_contact_force_n: if forces { best[Q_FN] } else { f64::NAN },
        disp_dev_mean_mm: 0.0,
        disp_dev_max_mm: 0.0,
        vel_dev_mean_mps: 0.0,
        vel_dev_max_mps: 0.0,
        peak_torque_nm: forces.then_some(best[Q_M12]),
        torque_dev_rms_nm: forces.then_some(0.0),
        stroke_min_mm: -best[Q_SMIN] * 1e3,
        stroke_max_mm: best[Q_SMAX] * 1e3,
        peak_process_force_n: forces.then_some(best[Q_PROC]),
        ideal_peak_accel_mps2: best[Q_ACC],
        ideal_peak_torque_nm: forces.then_some(best[Q_M12]),
        double_crossings_caught: 0,
        peak_penetration_um: 0.0,
        contact_steps: 0,
        free_steps: 0,
        motor: None,
        stick: None,
    };
    let mut notes = Vec::new();
    if opts.level == super::Level::Ideal {
        notes.push("level ideal: contact_force_n is the rod–pin-bar joint force magnitude".into());
    }
    SimResult {
        summary,
        curves,
        events: Vec::new(),
        stats: Stats::default(),
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Level;

    /// Flores ideal table: peaks of the closed form over one revolution.
    #[test]
    fn flores_ideal_peaks() {
        let p = Params::flores();
        let opts = SimOptions {
            level: Level::Ideal,
            warmup: 0.0,
            revs: 1.0,
            ..SimOptions::default()
        };
        let r = run(&p, &opts);
        let s = &r.summary;
        assert!(
            (s.peak_accel_mps2 - 19_419.36).abs() < 0.01,
            "{}",
            s.peak_accel_mps2
        );
        assert!((s.peak_torque_nm.unwrap() - 138.6242).abs() < 1e-3);
        assert!((s.peak_contact_force_n - 2_718.71).abs() < 0.01);
        assert!(s.stroke_min_mm.abs() < 1e-9 && (s.stroke_max_mm - 100.0).abs() < 1e-9);
    }
}
