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
//! The fourth rung, `motor`, is weighed when a motor drives the head
//! (`driver = "motor"`); the levels below then run at its operating speed.
//! What it adds is the crank's speed ripple, which the spindle's speed
//! channel sees directly, and what the ripple does to the load-cell force
//! and the stroke on the crank-angle grid, measured with the ideal joint
//! (the deterministic, periodic motion after a revolution of warm-up).
//! With a clearance the motion is chaotic: two runs that differ by a
//! ripple of 1e-4 % part within the deterministic window after a few
//! impacts, so such a comparison would weigh the chaos, not the motor.
//! Differences are compared at equal crank angle: a motor run's curves are
//! sampled in time, so they are interpolated to the constant-speed run's
//! angles.

use super::{Level, SimError, SimOptions, SimResult, simulate};
use crate::model::params::{Driver, Params};
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
    /// Smallest first harmonic of the crank speed the spindle channel
    /// resolves per cycle, % of the mean (default 0.05 %: the rig's 0.3 %
    /// speed noise at 5 kHz over the 250 samples of a 1200 rpm cycle gives
    /// the harmonic's amplitude a σ of 0.3 %·√(2/250) = 0.027 %; 2σ).
    #[serde(default = "default_speed_pct")]
    pub speed_pct: f64,
}

fn default_speed_pct() -> f64 {
    0.05
}

impl Default for SceneResolution {
    fn default() -> Self {
        Self {
            stroke_mm: 0.002,
            force_n: 0.05,
            needs_forces: true,
            speed_pct: default_speed_pct(),
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
    /// Step to `motor`: the crank speed's first harmonic, % of the mean.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_ripple_pct: Option<f64>,
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
/// The motor rung's comparison grid (see `motor_step`).
const MOTOR_GRID_DEG: f64 = 0.01;

/// One revolution after one of warm-up at rtol 1e-7, sampled every
/// `grid_deg`: what every rung is compared on.
fn one_revolution(
    p: &Params,
    level: Level,
    method: crate::solver::Method,
    grid_deg: f64,
) -> Result<SimResult, SimError> {
    simulate(
        p,
        &SimOptions {
            level,
            method,
            rtol: 1e-7,
            warmup: 1.0,
            revs: 1.0,
            grid_deg: Some(grid_deg),
            ..SimOptions::default()
        },
        &Progress::hidden(),
    )
}

/// Measures the levels for a scene and picks the cheapest sufficient one.
pub fn assess(
    p: &Params,
    res: SceneResolution,
    method: crate::solver::Method,
) -> Result<FidelityReport, SimError> {
    let run = |level: Level| one_revolution(p, level, method, GRID_DEG);
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
        speed_ripple_pct: None,
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
        speed_ripple_pct: None,
        invisible: sd < res.stroke_mm && (!res.needs_forces || fd < res.force_n),
        note: format!(
            "clearance {:.4} mm: journal free flight and impacts ({} impacts/rev)",
            p.clearance * 1e3,
            clear.summary.n_impacts
        ),
    };
    let (s3, motor_cost) = motor_step(p, res, method)?;
    let mut costs = costs;
    costs.extend(motor_cost);
    let (chosen, reason) = if !s3.invisible {
        (Level::Motor, s3.note.clone())
    } else if s1.invisible && s2.invisible {
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
    let reason = if chosen != Level::Motor && p.driver == Driver::Motor {
        format!("{reason}; {}", s3.note)
    } else {
        reason
    };
    Ok(FidelityReport {
        chosen,
        reason,
        resolution: res,
        steps: vec![s1, s2, s3],
        costs,
    })
}

/// Unwrapped crank angles (degrees) of a wrapped series.
fn unwrap_deg(w: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(w.len());
    let mut turns = 0.0;
    for (i, &a) in w.iter().enumerate() {
        if i > 0 {
            let d = a - w[i - 1];
            if d < -180.0 {
                turns += 360.0;
            } else if d > 180.0 {
                turns -= 360.0;
            }
        }
        out.push(a + turns);
    }
    out
}

/// `b` (sampled at wrapped crank angles `b_deg`) at the crank angles of
/// `a_deg`, linearly interpolated; NaN outside b's span.
fn at_angles(a_deg: &[f64], b_deg: &[f64], b: &[f64]) -> Vec<f64> {
    let ua = unwrap_deg(a_deg);
    let mut ub = unwrap_deg(b_deg);
    if let (Some(&a0), Some(&b0)) = (ua.first(), ub.first()) {
        let shift = ((a0 - b0) / 360.0).round() * 360.0;
        ub.iter_mut().for_each(|x| *x += shift);
    }
    let mut j = 0;
    ua.iter()
        .map(|&x| {
            while j + 1 < ub.len() && ub[j + 1] < x {
                j += 1;
            }
            if j + 1 >= ub.len() || x < ub[j] {
                return f64::NAN;
            }
            let w = (x - ub[j]) / (ub[j + 1] - ub[j]);
            b[j] + w * (b[j + 1] - b[j])
        })
        .collect()
}

/// Stroke, filtered load-cell force and acceleration differences of a
/// motor run from a constant-speed one at equal crank angle.
fn angle_diffs(cs: &SimResult, motor: &SimResult, omega: f64) -> Option<(f64, f64, f64)> {
    let (a, b) = (cs.curves.as_ref()?, motor.curves.as_ref()?);
    let dt = MOTOR_GRID_DEG.to_radians() / omega;
    let fa = low_pass(&a.process_force_n, dt, LOAD_CELL_FC_HZ);
    let fb = low_pass(&b.process_force_n, dt, LOAD_CELL_FC_HZ);
    let on = |x: &[f64]| at_angles(&a.crank_deg, &b.crank_deg, x);
    Some((
        max_abs_diff(&a.stroke_mm, &on(&b.stroke_mm)),
        max_abs_diff(&fa, &on(&fb)),
        max_abs_diff(&a.acc_mps2, &on(&b.acc_mps2)),
    ))
}

/// The step clearance → motor: measured when a motor drives the head.
fn motor_step(
    p: &Params,
    res: SceneResolution,
    method: crate::solver::Method,
) -> Result<(LevelStep, Option<LevelCost>), SimError> {
    let blank = LevelStep {
        from: Level::Clearance,
        to: Level::Motor,
        stroke_diff_mm: None,
        force_diff_n: None,
        accel_diff_mps2: None,
        speed_ripple_pct: None,
        invisible: true,
        note: "driver = constant_speed: the crank speed is held (set driver = \"motor\" and the motor keys to weigh its ripple)".into(),
    };
    if p.driver != Driver::Motor {
        return Ok((blank, None));
    }
    // A finer grid than the other rungs': the regularized process law
    // drops its 23 N within 0.05° at bottom dead centre, and on a coarser
    // grid where the samples fall on that drop differs between the two
    // runs by a sample's phase, which the filter turns into a tenth of a
    // newton that is no physics.
    let run = |q: &Params, level: Level| one_revolution(q, level, method, MOTOR_GRID_DEG);
    // The ideal joint: periodic after a revolution.
    let mut rigid = p.clone();
    rigid.clearance = 0.0;
    let id = run(&rigid, Level::Ideal)?;
    let mo = run(&rigid, Level::Motor)?;
    let m = mo.summary.motor.clone().unwrap_or_else(|| unreachable!());
    let omega = m.operating_crank_rpm * std::f64::consts::TAU / 60.0;
    let (sd, fd, ad) = angle_diffs(&id, &mo, omega).unwrap_or((0.0, 0.0, 0.0));
    let ripple = m.ripple_h1_pct.unwrap_or(f64::NAN);
    let ripple_seen = ripple >= res.speed_pct;
    let stroke_seen = sd >= res.stroke_mm;
    let force_seen = res.needs_forces && fd >= res.force_n;
    let invisible = !(ripple_seen || stroke_seen || force_seen);
    let cmp = |seen: bool| if seen { "≥" } else { "<" };
    let note = format!(
        "the motor's speed ripple is {ripple:.3} % (first harmonic; {:.3} % peak to peak) {} {} % the spindle resolves, and it changes the stroke by {sd:.4} mm ({} {} mm) and the load-cell force by {fd:.3} N ({} {} N) at equal crank angle (ideal joint)",
        m.ripple_p2p_pct,
        cmp(ripple_seen),
        res.speed_pct,
        cmp(stroke_seen),
        res.stroke_mm,
        cmp(fd >= res.force_n),
        res.force_n,
    );
    let cost = LevelCost {
        level: Level::Motor,
        wall_ms_per_rev: mo.summary.wall_ms / 2.0,
        rhs_evals_per_rev: (mo.summary.rhs_evals + mo.summary.aux_evals) as f64 / 2.0,
    };
    Ok((
        LevelStep {
            stroke_diff_mm: Some(sd),
            force_diff_n: Some(fd),
            accel_diff_mps2: Some(ad),
            speed_ripple_pct: Some(ripple),
            invisible,
            note,
            ..blank
        },
        Some(cost),
    ))
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

    /// The fourth rung. A motor without a flywheel ripples the crank speed
    /// well above the 0.05 % the spindle channel resolves: the chooser
    /// takes the motor level. A 0.05 kg m² flywheel (2500× the rotor's
    /// inertia) holds the ripple below it: the chooser stays with the
    /// clearance level and says the ripple is unseen. A constant-speed
    /// driver leaves the rung blank.
    #[test]
    fn the_motor_rung_is_chosen_when_the_spindle_sees_the_ripple() {
        let mut p = Params::paper();
        p.clearance = 0.1e-3;
        let r = assess(&p, SceneResolution::default(), Method::Dop853).unwrap();
        assert_eq!(r.chosen, Level::Clearance, "{}", r.reason);
        assert_eq!(r.steps[2].speed_ripple_pct, None, "{:?}", r.steps[2]);
        p.driver = Driver::Motor;
        let r = assess(&p, SceneResolution::default(), Method::Dop853).unwrap();
        assert_eq!(r.chosen, Level::Motor, "{}", r.reason);
        let ripple = r.steps[2].speed_ripple_pct.unwrap();
        assert!(ripple > 0.1, "{:?}", r.steps[2]);
        assert!(r.costs.iter().any(|c| c.level == Level::Motor), "{r:?}");
        p.motor.flywheel_inertia = 0.05;
        let r = assess(&p, SceneResolution::default(), Method::Dop853).unwrap();
        assert_eq!(r.chosen, Level::Clearance, "{}", r.reason);
        let s = &r.steps[2];
        assert!(s.speed_ripple_pct.unwrap() < 0.05 && s.invisible, "{s:?}");
        assert!(r.reason.contains("speed ripple"), "{}", r.reason);
    }
}
