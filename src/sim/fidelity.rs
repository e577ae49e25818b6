//! Model no more than a scene needs: each level's difference from the next,
//! its cost, and the cheapest sufficient level (`--level auto`).
//!
//! A scene is what the sensors can see: the laser's stroke resolution and
//! the load cell's force resolution (defaults from the rig's sensor models:
//! 2 µm noise on the stroke, 0.05 N on the force), and whether forces are
//! wanted at all. Differences are measured, not guessed: each level is run
//! over one revolution after one revolution of warm-up at a loose tolerance
//! (the differences sought are at sensor scale, far above the integration
//! error), and compared with the next level on the same crank-angle grid.
//!
//! The `motor` level (speed ripple from a motor curve) is not modelled yet:
//! the clearance level assumes the logged mean speed, and this is reported.

use super::{Level, SimError, SimOptions, simulate};
use crate::model::params::Params;
use crate::progress::Progress;
use serde::{Deserialize, Serialize};

/// What the scene can resolve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SceneResolution {
    /// Smallest stroke difference the displacement sensor resolves, mm.
    pub stroke_mm: f64,
    /// Smallest force difference the load cell resolves, N.
    pub force_n: f64,
    /// Whether forces (torque, load cell) are part of the question.
    pub needs_forces: bool,
}

impl Default for SceneResolution {
    fn default() -> Self {
        Self {
            stroke_mm: 0.002,
            force_n: 0.05,
            needs_forces: true,
        }
    }
}

/// Difference between one level and the next.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelStep {
    pub from: Level,
    pub to: Level,
    /// Largest stroke difference over the revolution, mm (None: not comparable).
    pub stroke_diff_mm: Option<f64>,
    /// Largest load-cell force difference after the load cell's 1 kHz
    /// filter, N (None: the lower level has no forces).
    pub force_diff_n: Option<f64>,
    /// Largest acceleration difference, m/s².
    pub accel_diff_mps2: Option<f64>,
    /// Whether the difference is below what the scene resolves.
    pub invisible: bool,
    pub note: String,
}

/// Cost of one level per simulated revolution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelCost {
    pub level: Level,
    pub wall_ms_per_rev: f64,
    pub rhs_evals_per_rev: f64,
}

/// The choice and its evidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FidelityReport {
    pub chosen: Level,
    pub reason: String,
    pub resolution: SceneResolution,
    pub steps: Vec<LevelStep>,
    pub costs: Vec<LevelCost>,
}

/// Bandwidth of the load cell's signal chain (rig-log README: a first-order
/// 1 kHz filter). Force differences are compared after this filter: the
/// load cell cannot see the sub-millisecond chatter of the regularized
/// process law at bottom dead centre.
pub const LOAD_CELL_FC_HZ: f64 = 1000.0;

/// First-order low-pass filter of a uniformly sampled signal (NaN → 0).
fn low_pass(x: &[f64], dt: f64, fc: f64) -> Vec<f64> {
    let a = 1.0 - (-2.0 * std::f64::consts::PI * fc * dt).exp();
    let mut y = Vec::with_capacity(x.len());
    let mut s = x.first().copied().filter(|v| v.is_finite()).unwrap_or(0.0);
    for &v in x {
        let v = if v.is_finite() { v } else { 0.0 };
        s += a * (v - s);
        y.push(s);
    }
    y
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

const GRID_DEG: f64 = 0.1;

/// Measures the levels for a scene and picks the cheapest sufficient one.
pub fn assess(
    p: &Params,
    res: SceneResolution,
    method: crate::solver::Method,
) -> Result<FidelityReport, SimError> {
    let run = |level: Level| {
        simulate(
            p,
            &SimOptions {
                level,
                method,
                rtol: 1e-7,
                warmup: 1.0,
                revs: 1.0,
                grid_deg: Some(GRID_DEG),
                ..SimOptions::default()
            },
            &Progress::hidden(),
        )
    };
    let kin = run(Level::Kinematic)?;
    let ideal = run(Level::Ideal)?;
    let clear = run(Level::Clearance)?;
    let cost = |level: Level, r: &super::SimResult| LevelCost {
        level,
        wall_ms_per_rev: r.summary.wall_ms / 2.0,
        rhs_evals_per_rev: (r.summary.rhs_evals + r.summary.aux_evals) as f64 / 2.0,
    };
    let costs = vec![
        cost(Level::Kinematic, &kin),
        cost(Level::Ideal, &ideal),
        cost(Level::Clearance, &clear),
    ];
    let (ck, ci, cc) = match (&kin.curves, &ideal.curves, &clear.curves) {
        (Some(a), Some(b), Some(c)) => (a, b, c),
        _ => return Err(SimError::Options("fidelity: curves missing".into())),
    };
    // kinematic → ideal: same motion; the ideal level adds the forces.
    let forces_peak = ci
        .process_force_n
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let s1 = LevelStep {
        from: Level::Kinematic,
        to: Level::Ideal,
        stroke_diff_mm: Some(max_abs_diff(&ck.stroke_mm, &ci.stroke_mm)),
        force_diff_n: None,
        accel_diff_mps2: Some(max_abs_diff(&ck.acc_mps2, &ci.acc_mps2)),
        invisible: !res.needs_forces,
        note: format!(
            "same motion; the ideal level adds joint forces, guide friction, drive torque and the load-cell force (peak {forces_peak:.3} N)"
        ),
    };
    let sd = max_abs_diff(&ci.stroke_mm, &cc.stroke_mm);
    let dt = GRID_DEG.to_radians() / p.omega();
    let fd = max_abs_diff(
        &low_pass(&ci.process_force_n, dt, LOAD_CELL_FC_HZ),
        &low_pass(&cc.process_force_n, dt, LOAD_CELL_FC_HZ),
    );
    let ad = max_abs_diff(&ci.acc_mps2, &cc.acc_mps2);
    let s2 = LevelStep {
        from: Level::Ideal,
        to: Level::Clearance,
        stroke_diff_mm: Some(sd),
        force_diff_n: Some(fd),
        accel_diff_mps2: Some(ad),
        invisible: sd < res.stroke_mm && (!res.needs_forces || fd < res.force_n),
        note: format!(
            "clearance {:.4} mm: journal free flight and impacts ({} impacts/rev)",
            p.clearance * 1e3,
            clear.summary.n_impacts
        ),
    };
    let s3 = LevelStep {
        from: Level::Clearance,
        to: Level::Motor,
        stroke_diff_mm: None,
        force_diff_n: None,
        accel_diff_mps2: None,
        invisible: false,
        note: "not modelled yet: constant crank speed assumed (the logged speed ripple is not fed back)".into(),
    };
    let (chosen, reason) = if s1.invisible && s2.invisible {
        (
            Level::Kinematic,
            format!(
                "forces not needed and the clearance changes the stroke by {sd:.4} mm < {} mm resolution",
                res.stroke_mm
            ),
        )
    } else if s2.invisible {
        (
            Level::Ideal,
            format!(
                "the clearance changes the stroke by {sd:.4} mm (< {} mm) and the load-cell force by {fd:.3} N (< {} N): below what the sensors resolve",
                res.stroke_mm, res.force_n
            ),
        )
    } else {
        let why = if sd >= res.stroke_mm {
            format!(
                "the clearance changes the stroke by {sd:.4} mm ≥ {} mm resolution",
                res.stroke_mm
            )
        } else {
            format!(
                "the clearance changes the load-cell force by {fd:.3} N ≥ {} N resolution",
                res.force_n
            )
        };
        (Level::Clearance, why)
    };
    Ok(FidelityReport {
        chosen,
        reason,
        resolution: res,
        steps: vec![s1, s2, s3],
        costs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::Method;

    /// A 0.1 µm clearance with no part in the press changes neither the
    /// stroke nor the load-cell force visibly; 0.3 mm does. (With the part,
    /// even 0.1 µm shifts the regularized load's 23 N drop at bottom dead
    /// centre by microseconds, which a 1 kHz load cell still sees.)
    #[test]
    fn tiny_clearance_is_invisible_large_one_is_not() {
        let mut p = Params::paper();
        p.f_ins = crate::model::table::Table::zero();
        p.clearance = 1e-7; // 0.1 µm
        let r = assess(&p, SceneResolution::default(), Method::Dop853).unwrap();
        assert_eq!(r.chosen, Level::Ideal, "{}", r.reason);
        let r = assess(
            &p,
            SceneResolution {
                needs_forces: false,
                ..SceneResolution::default()
            },
            Method::Dop853,
        )
        .unwrap();
        assert_eq!(r.chosen, Level::Kinematic, "{}", r.reason);
        let mut p = Params::paper();
        p.clearance = 0.3e-3;
        let r = assess(&p, SceneResolution::default(), Method::Dop853).unwrap();
        assert_eq!(r.chosen, Level::Clearance, "{}", r.reason);
        let s = &r.steps[1];
        assert!(s.stroke_diff_mm.unwrap() > 0.1, "{s:?}");
    }
}
