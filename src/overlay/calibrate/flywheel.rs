//! The flywheel inertia from a log's crank speed ripple (the motor level).
//!
//! What a log identifies: the first harmonic of the crank speed over crank
//! angle per cycle (`rig::cycles`, the `ripple %` of `pinsight log`). The
//! motor level predicts the same figure for a flywheel inertia J_fly on
//! the crank shaft; it falls monotonically with J_fly (the once-per-
//! revolution torque of the process and gravity divided by |k + i J ω|,
//! k the curve's slope), so one measured ripple gives one J_fly, found by
//! bisection in log J. The prediction uses the ideal joint: the clearance's
//! impacts add sub-millisecond torque spikes whose once-per-revolution
//! content is small (for the paper head at 0.1 mm the ripple moves from
//! 0.66 % to 0.64 %) and their chaos would only add noise to the fit.
//!
//! Uncertainty: the standard error of the mean ripple over the log's
//! cycles, carried through the local slope dh/dJ; U95 = 2σ.

use crate::model::Params;
use crate::model::params::Driver;
use crate::progress::Progress;
use crate::rig::cycles::CycleSet;
use crate::sim::{Level, SimError, SimOptions, simulate};
use serde::Serialize;

/// The flywheel fitted to a log's ripple.
#[derive(Debug, Clone, Serialize)]
pub struct FlywheelFit {
    /// Usable cycles with a ripple figure, their mean crank speed (rev/min).
    pub cycles: usize,
    pub crank_rpm: f64,
    /// Logged first-harmonic ripple: mean over the cycles and its standard
    /// error, %.
    pub measured_pct: f64,
    pub measured_sigma_pct: f64,
    /// The fitted flywheel inertia on the crank shaft and its uncertainty.
    pub flywheel_inertia_kgm2: f64,
    pub sigma_kgm2: f64,
    pub u95_kgm2: f64,
    /// The model's ripple at the fit and without a flywheel, %.
    pub predicted_pct: f64,
    pub without_flywheel_pct: f64,
    /// (J_fly, predicted ripple %) at the points the search evaluated.
    pub profile: Vec<(f64, f64)>,
    pub notes: Vec<String>,
}

/// The model's first-harmonic ripple (%) for the head `p` with flywheel
/// `j_fly` (ideal joint, motor level, warmed up for three of the drive's
/// time constants).
pub fn predicted_ripple(p: &Params, j_fly: f64) -> Result<f64, SimError> {
    let mut q = p.clone();
    q.clearance = 0.0;
    q.driver = Driver::Motor;
    q.motor.flywheel_inertia = j_fly;
    let drive = crate::model::motor::MotorDrive::of(&q);
    // The speed's time constant J / k (k: the torque's slope at the crank,
    // the curve's or the controller's) in revolutions.
    let w = drive.operating.omega;
    let g = drive.gear;
    let slope_curve = {
        let h = 1e-4 * w;
        (drive.at_crank(drive.curve.torque(g * (w - h)))
            - drive.at_crank(drive.curve.torque(g * (w + h))))
            / (2.0 * h)
    };
    let slope = match drive.control {
        Some(pi) => slope_curve + g * g * q.motor.efficiency * pi.kp,
        None => slope_curve,
    };
    let ks = crate::model::kinetostatics::Kinetostatics::of(&q);
    let j_total = drive.inertia + ks.inertia.i_o();
    let tau_revs = if slope > 0.0 {
        j_total / slope * w / std::f64::consts::TAU
    } else {
        10.0
    };
    let warmup = (3.0 * tau_revs).clamp(2.0, 60.0);
    let s = simulate(
        &q,
        &SimOptions {
            level: Level::Motor,
            warmup,
            revs: 2.0,
            rtol: 1e-8,
            ..SimOptions::default()
        },
        &Progress::hidden(),
    )?
    .summary;
    Ok(s.motor.and_then(|m| m.ripple_h1_pct).unwrap_or(f64::NAN))
}

/// The flywheel inertia whose predicted ripple is `measured_pct` (%), with
/// the ripple's standard error `sigma_pct` carried to the inertia.
pub fn fit_flywheel(
    base: &Params,
    measured_pct: f64,
    sigma_pct: f64,
) -> Result<FlywheelFit, SimError> {
    let mut profile = Vec::new();
    let mut notes = Vec::new();
    let eval = |j: f64, profile: &mut Vec<(f64, f64)>| -> Result<f64, SimError> {
        let h = predicted_ripple(base, j)?;
        profile.push((j, h));
        Ok(h)
    };
    let h0 = eval(0.0, &mut profile)?;
    let fit_at = |j: f64, h: f64, profile: Vec<(f64, f64)>, notes: Vec<String>| FlywheelFit {
        cycles: 0,
        crank_rpm: base.omega() * 60.0 / std::f64::consts::TAU,
        measured_pct,
        measured_sigma_pct: sigma_pct,
        flywheel_inertia_kgm2: j,
        sigma_kgm2: f64::NAN,
        u95_kgm2: f64::NAN,
        predicted_pct: h,
        without_flywheel_pct: h0,
        profile,
        notes,
    };
    if !(measured_pct > 0.0) || !measured_pct.is_finite() {
        notes.push("no ripple measured: no flywheel fitted".into());
        return Ok(fit_at(0.0, h0, profile, notes));
    }
    if measured_pct >= h0 {
        notes.push(format!(
            "the logged ripple {measured_pct:.3} % is at least what the motor gives without a flywheel ({h0:.3} %): J_fly = 0 (check the rotor inertia and the motor curve)"
        ));
        return Ok(fit_at(0.0, h0, profile, notes));
    }
    // Bracket: J grows by decades from the rotor's scale until the ripple
    // falls below the measured one.
    let j_ref = (base.motor.rotor_inertia * base.gear_ratio * base.gear_ratio).max(1e-6);
    let (mut lo, mut hi) = (0.0, j_ref);
    let mut h_hi = eval(hi, &mut profile)?;
    while h_hi > measured_pct {
        lo = hi;
        hi *= 10.0;
        if hi > 1e4 {
            notes.push("the ripple stays above the logged one up to 1e4 kg m²".into());
            return Ok(fit_at(lo, h_hi, profile, notes));
        }
        h_hi = eval(hi, &mut profile)?;
    }
    // Bisection (geometric once lo > 0) to 1e-4 relative.
    for _ in 0..60 {
        let mid = if lo > 0.0 { (lo * hi).sqrt() } else { 0.5 * hi };
        let h = eval(mid, &mut profile)?;
        if h > measured_pct {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-4 * hi {
            break;
        }
    }
    let j = 0.5 * (lo + hi);
    let h = eval(j, &mut profile)?;
    // The slope dh/dJ at the fit, for the uncertainty.
    let dj = 0.02 * j;
    let slope = (eval(j + dj, &mut profile)? - eval(j - dj, &mut profile)?) / (2.0 * dj);
    let sigma = if slope < 0.0 {
        sigma_pct / -slope
    } else {
        f64::NAN
    };
    profile.sort_by(|a, b| a.0.total_cmp(&b.0));
    profile.dedup_by(|a, b| a.0 == b.0);
    let mut f = fit_at(j, h, profile, notes);
    f.sigma_kgm2 = sigma;
    f.u95_kgm2 = 2.0 * sigma;
    Ok(f)
}

/// The logged first-harmonic ripple of a cycle set: mean and standard
/// error over the usable cycles (%), their number and mean crank speed.
pub fn logged_ripple(cs: &CycleSet) -> Option<(f64, f64, usize, f64)> {
    let v: Vec<(f64, f64)> = cs
        .usable()
        .filter(|c| c.ripple_first_harmonic.is_finite())
        .map(|c| (c.ripple_first_harmonic * 100.0, c.crank_rpm))
        .collect();
    if v.len() < 2 {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().map(|x| x.0).sum::<f64>() / n;
    let var = v.iter().map(|x| (x.0 - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let rpm = v.iter().map(|x| x.1).sum::<f64>() / n;
    Some((mean, (var / n).sqrt(), v.len(), rpm))
}

/// Calibrates the flywheel of `base` against the log's cycles.
pub fn calibrate_flywheel(cs: &CycleSet, base: &Params) -> Result<FlywheelFit, String> {
    let (mean, se, n, rpm) = logged_ripple(cs).ok_or_else(|| {
        format!(
            "{}: the flywheel needs the crank speed ripple of at least 2 usable cycles",
            cs.file
        )
    })?;
    let mut p = base.clone();
    // The head at the log's speed.
    p.motor_rpm = rpm * p.gear_ratio;
    let mut f = fit_flywheel(&p, mean, se).map_err(|e| format!("{}: {e}", cs.file))?;
    f.cycles = n;
    f.crank_rpm = rpm;
    Ok(f)
}

/// Adds the fitted flywheel to a calibration: an estimate, the parameters
/// (driver = motor with this flywheel) and their file.
pub fn apply_to_report(report: &mut super::CalibrationReport, fit: &FlywheelFit) {
    report.estimates.push(super::Estimate {
        name: "flywheel_inertia".into(),
        unit: "kg m²".into(),
        nominal: Some(report.params.motor.flywheel_inertia),
        value: fit.flywheel_inertia_kgm2,
        sigma: fit.sigma_kgm2,
        u95: fit.u95_kgm2,
        method: format!(
            "motor level (ideal joint): first-harmonic speed ripple {:.4} ± {:.4} % over {} cycles, predicted {:.4} % (without flywheel {:.4} %)",
            fit.measured_pct, fit.measured_sigma_pct, fit.cycles, fit.predicted_pct, fit.without_flywheel_pct
        ),
    });
    report.params.driver = Driver::Motor;
    report.params.motor.flywheel_inertia = fit.flywheel_inertia_kgm2;
    report.notes.extend(fit.notes.iter().cloned());
    let header: String = report
        .params_toml
        .lines()
        .take_while(|l| l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    report.params_toml = format!(
        "{header}#   flywheel_inertia = {:.6e} ± {:.2e} kg m² (crank speed ripple)\n{}",
        fit.flywheel_inertia_kgm2,
        fit.u95_kgm2,
        report.params.to_toml()
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inversion: a ripple predicted for a known flywheel gives that
    /// flywheel back.
    #[test]
    fn the_fit_returns_the_flywheel_that_made_the_ripple() {
        let p = Params::paper();
        for j_true in [2e-4, 3e-3] {
            let h = predicted_ripple(&p, j_true).unwrap();
            let f = fit_flywheel(&p, h, 0.01 * h).unwrap();
            eprintln!(
                "J_true {j_true:e}: ripple {h:.4} %, fit {:e} ± {:e}",
                f.flywheel_inertia_kgm2, f.sigma_kgm2
            );
            assert!(
                (f.flywheel_inertia_kgm2 / j_true - 1.0).abs() < 1e-3,
                "{f:?}"
            );
            assert!(f.sigma_kgm2 > 0.0 && f.sigma_kgm2 < 0.1 * j_true);
        }
    }
}
