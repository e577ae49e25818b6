//! The predicted ensemble on the crank-angle grid.
//!
//! The clearance motion is chaotic (model.md): one simulated cycle cannot be
//! matched against one measured cycle. So the model is run for `revs`
//! revolutions after `warmup` at the logged speed, and every revolution is
//! one realisation of the attractor: per crank angle, the mean, standard
//! deviation, minimum and maximum over the revolutions form the predicted
//! band, and per revolution the same figures as for a measured cycle (depth,
//! peak force, deviations from the ideal mechanism) give their predicted
//! distributions.
//!
//! The prediction is seen through the sensors it is compared with: the
//! laser's and the load cell's first-order lags (when known) are applied to
//! the simulated stroke and force in time, and the velocity used for the
//! speed-deviation figure is differentiated from the (lagged) stroke exactly
//! as it is from the measured one.

use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::progress::Progress;
use crate::rig::cycles::Band;
use crate::sim::{Level, SimError, SimOptions, simulate};
use crate::solver::Method;
use serde::Serialize;
use std::f64::consts::TAU;

/// How to predict.
#[derive(Debug, Clone, Serialize)]
pub struct PredictOptions {
    /// Fidelity level: `Kinematic`, `Ideal` or `Clearance`.
    pub level: Level,
    /// Revolutions simulated before the ensemble (transient).
    pub warmup: f64,
    /// Revolutions in the ensemble (the clearance level; 1 for the deterministic levels).
    pub revs: usize,
    /// Integrator relative tolerance. Statistics over revolutions do not need
    /// the tight tolerances of the deterministic window: 1e-6 by default.
    pub rtol: f64,
    /// Integrator: DOP853 by default (the overlay's trajectories); the
    /// calibration's ensembles use DOPRI5 (see `calibrate::ENSEMBLE_METHOD`).
    pub method: Method,
    /// Grid points per revolution (must match the measured cycles' grid).
    pub points_per_rev: usize,
    /// First-order lags of the sensors (s) applied to the prediction.
    pub laser_lag_s: f64,
    pub force_lag_s: f64,
}

impl Default for PredictOptions {
    fn default() -> Self {
        PredictOptions {
            level: Level::Clearance,
            warmup: 3.0,
            revs: 40,
            rtol: 1e-6,
            method: Method::Dop853,
            points_per_rev: 720,
            laser_lag_s: 0.0,
            force_lag_s: 0.0,
        }
    }
}

/// Figures of one cycle (measured or simulated), computed the same way for both.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct CycleFigures {
    /// Max stroke − standoff (mm).
    pub depth_mm: f64,
    pub stroke_max_mm: f64,
    pub stroke_min_mm: f64,
    pub peak_force_n: f64,
    /// Stroke − ideal stroke at TDC and BDC (mm).
    pub stroke_err_tdc_mm: f64,
    pub stroke_err_bdc_mm: f64,
    /// The paper's displacement deviation: mean and max |s − s_ideal| (mm).
    pub disp_dev_mean_mm: f64,
    pub disp_dev_max_mm: f64,
    /// The paper's speed deviation: mean and max |v − v_ideal| (m/s), with v
    /// differentiated from the stroke over ±1°.
    pub vel_dev_mean_mps: f64,
    pub vel_dev_max_mps: f64,
}

/// Names and units of the figures, in [`CycleFigures::values`] order.
pub const FIGURE_NAMES: [(&str, &str); 10] = [
    ("depth_mm", "mm"),
    ("stroke_max_mm", "mm"),
    ("stroke_min_mm", "mm"),
    ("peak_force_n", "N"),
    ("stroke_err_tdc_mm", "mm"),
    ("stroke_err_bdc_mm", "mm"),
    ("disp_dev_mean_mm", "mm"),
    ("disp_dev_max_mm", "mm"),
    ("vel_dev_mean_mps", "m/s"),
    ("vel_dev_max_mps", "m/s"),
];

impl CycleFigures {
    pub fn values(&self) -> [f64; 10] {
        [
            self.depth_mm,
            self.stroke_max_mm,
            self.stroke_min_mm,
            self.peak_force_n,
            self.stroke_err_tdc_mm,
            self.stroke_err_bdc_mm,
            self.disp_dev_mean_mm,
            self.disp_dev_max_mm,
            self.vel_dev_mean_mps,
            self.vel_dev_max_mps,
        ]
    }

    /// Figures of a cycle on the grid: stroke and force (NaN = no data),
    /// ideal stroke and velocity, crank speed ω (rad/s), standoff (mm).
    pub fn of(
        stroke: &[f64],
        force: &[f64],
        ideal: &[f64],
        ideal_vel: &[f64],
        omega: f64,
        standoff_mm: f64,
    ) -> Self {
        let n = stroke.len();
        let fin = |v: &[f64]| {
            v.iter()
                .copied()
                .filter(|x| x.is_finite())
                .collect::<Vec<f64>>()
        };
        let s = fin(stroke);
        let smax = s.iter().copied().fold(f64::NAN, f64::max);
        let smin = s.iter().copied().fold(f64::NAN, f64::min);
        let dev: Vec<f64> = stroke
            .iter()
            .zip(ideal)
            .map(|(a, b)| a - b)
            .filter(|x| x.is_finite())
            .collect();
        let vel = velocity(stroke, omega);
        let vdev: Vec<f64> = vel
            .iter()
            .zip(ideal_vel)
            .map(|(a, b)| (a - b).abs())
            .filter(|x| x.is_finite())
            .collect();
        let mean = |v: &[f64]| {
            if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        CycleFigures {
            depth_mm: smax - standoff_mm,
            stroke_max_mm: smax,
            stroke_min_mm: smin,
            peak_force_n: fin(force).into_iter().fold(f64::NAN, f64::max),
            stroke_err_tdc_mm: stroke.first().map_or(f64::NAN, |v| v - ideal[0]),
            stroke_err_bdc_mm: stroke.get(n / 2).map_or(f64::NAN, |v| v - ideal[n / 2]),
            disp_dev_mean_mm: mean(&dev.iter().map(|d| d.abs()).collect::<Vec<_>>()),
            disp_dev_max_mm: dev.iter().map(|d| d.abs()).fold(f64::NAN, f64::max),
            vel_dev_mean_mps: mean(&vdev),
            vel_dev_max_mps: vdev.iter().copied().fold(f64::NAN, f64::max),
        }
    }
}

/// Pin-bar velocity (m/s) from the stroke grid (mm) of one revolution at
/// crank speed ω: central difference over ±2 grid points (±1° at 720
/// points), wrapping around the revolution; NaN where a neighbour is NaN.
pub fn velocity(stroke_mm: &[f64], omega: f64) -> Vec<f64> {
    let n = stroke_mm.len();
    if n < 5 {
        return vec![f64::NAN; n];
    }
    let k = 2usize;
    let dphi = 2.0 * k as f64 * TAU / n as f64;
    (0..n)
        .map(|j| {
            let a = stroke_mm[(j + n - k) % n];
            let b = stroke_mm[(j + k) % n];
            (b - a) * 1e-3 / dphi * omega
        })
        .collect()
}

/// The ideal mechanism's stroke (mm) and velocity (m/s) on the grid at ω.
pub fn ideal_curves(geom: &Geometry, n: usize, omega: f64) -> (Vec<f64>, Vec<f64>) {
    ideal_curves_on(geom, &crank_grid(geom, n), omega)
}

/// The grid's crank angles from top dead centre with their sines and
/// cosines, (θ2, sin θ2, cos θ2): computed once for many [`ideal_curves_on`].
pub fn crank_grid(geom: &Geometry, n: usize) -> Vec<(f64, f64, f64)> {
    let tdc = geom.tdc_angle();
    (0..n)
        .map(|j| {
            let th = tdc + j as f64 * TAU / n as f64;
            let (s, c) = th.sin_cos();
            (th, s, c)
        })
        .collect()
}

/// [`ideal_curves`] on a precomputed [`crank_grid`] (the same numbers,
/// without the trigonometry: the overlay needs them once per cycle).
pub fn ideal_curves_on(
    geom: &Geometry,
    grid: &[(f64, f64, f64)],
    omega: f64,
) -> (Vec<f64>, Vec<f64>) {
    let mut s = Vec::with_capacity(grid.len());
    let mut v = Vec::with_capacity(grid.len());
    for &(th, s2, c2) in grid {
        let p = geom.pose_sc(th, s2, c2, omega, 0.0);
        s.push((p.x4 - geom.x4_tdc()) * 1e3);
        v.push(p.v4);
    }
    (s, v)
}

/// Coefficients (a, b0, b1) of a first-order lag τ discretised exactly for
/// an input linear between samples h apart: y₁ = a·y₀ + b0·u₀ + b1·u₁.
/// (Holding the input constant instead delays it by h/2: on a 0.5° grid at
/// 1200 rpm that is 35 µs, 0.8 N on the insertion force's edge.) τ = 0: no lag.
pub fn ramp_lag_coefficients(h: f64, tau: f64) -> (f64, f64, f64) {
    if tau <= 0.0 || h <= 0.0 {
        return (0.0, 0.0, 1.0);
    }
    let e = (-h / tau).exp();
    let q = tau / h * (1.0 - e);
    (e, q - e, 1.0 - q)
}

/// First-order low-pass along a sequence sampled every `dt` (input linear
/// between samples), started at the first value.
pub fn lag_filter(x: &mut [f64], dt: f64, tau: f64) {
    if tau <= 0.0 || x.is_empty() {
        return;
    }
    let (a, b0, b1) = ramp_lag_coefficients(dt, tau);
    let mut y = x[0];
    let mut u0 = x[0];
    for v in x.iter_mut() {
        let u1 = *v;
        y = a * y + b0 * u0 + b1 * u1;
        u0 = u1;
        *v = y;
    }
}

/// The predicted ensemble at one speed.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    /// Motor speed simulated (rev/min).
    pub motor_rpm: f64,
    pub gear_ratio: f64,
    pub clearance_mm: f64,
    pub standoff_mm: f64,
    pub level: Level,
    /// Revolutions in the ensemble.
    pub revs: usize,
    pub points_per_rev: usize,
    pub ideal_stroke_mm: Vec<f64>,
    pub ideal_vel_mps: Vec<f64>,
    /// Per crank angle over the revolutions.
    pub stroke: Band,
    pub force: Band,
    /// Per revolution: stroke and force on the grid (the realisations).
    #[serde(skip)]
    pub stroke_revs: Vec<Vec<f64>>,
    #[serde(skip)]
    pub force_revs: Vec<Vec<f64>>,
    /// Per-revolution figures.
    pub figures: Vec<CycleFigures>,
    /// Integrator work and wall time.
    pub rhs_evals: u64,
    pub wall_ms: f64,
    pub notes: Vec<String>,
}

impl Prediction {
    /// Per-revolution figures with white measurement noise of the given σ
    /// added to the stroke (mm) and force (N) first — so that max/min-type
    /// figures are compared with measured ones on equal terms (noise raises
    /// a maximum by ~2–3σ). Deterministic (seeded).
    pub fn figures_with_noise(
        &self,
        sigma_stroke_mm: f64,
        sigma_force_n: f64,
        seed: u64,
    ) -> Vec<CycleFigures> {
        let mut rng = crate::rig::synth::Rng::new(seed);
        let omega = TAU * self.motor_rpm / 60.0 / self.gear_ratio;
        self.stroke_revs
            .iter()
            .zip(&self.force_revs)
            .map(|(s, f)| {
                let sn: Vec<f64> = s
                    .iter()
                    .map(|x| x + sigma_stroke_mm * rng.normal())
                    .collect();
                let fnz: Vec<f64> = f.iter().map(|x| x + sigma_force_n * rng.normal()).collect();
                CycleFigures::of(
                    &sn,
                    &fnz,
                    &self.ideal_stroke_mm,
                    &self.ideal_vel_mps,
                    omega,
                    self.standoff_mm,
                )
            })
            .collect()
    }
}

/// White-noise level of a sampled signal, from the second difference of
/// consecutive samples (robust: 1.4826 × median |x_i − (x_{i−1} + x_{i+1})/2| / √1.5).
/// Smooth signal content contributes little at the sensor rates of a rig
/// (tens of samples per degree of crank motion are not needed: the
/// curvature term is second order in the sample interval).
pub fn noise_sigma(values: &[f64]) -> f64 {
    if values.len() < 10 {
        return 0.0;
    }
    let stride = (values.len() / 200_000).max(1);
    let mut d: Vec<f64> = (1..values.len() - 1)
        .step_by(stride)
        .map(|i| (values[i] - 0.5 * (values[i - 1] + values[i + 1])).abs())
        .filter(|x| x.is_finite())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    let m = *d.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    1.4826 * m / 1.5f64.sqrt()
}

/// Runs the model at `motor_rpm` and builds the ensemble on the grid.
pub fn predict(
    p: &Params,
    motor_rpm: f64,
    opts: &PredictOptions,
    progress: &Progress,
) -> Result<Prediction, SimError> {
    let started = std::time::Instant::now();
    let mut p = p.clone();
    p.motor_rpm = motor_rpm;
    let n = opts.points_per_rev.max(8);
    // (A motor-driven run needs its warm-up even with the ideal joint.)
    let deterministic = matches!(opts.level, Level::Kinematic | Level::Ideal)
        || (opts.level == Level::Clearance && p.clearance == 0.0);
    // Whole revolutions from TDC: the grid then starts at TDC (θ0 = TDC).
    let warmup = if deterministic {
        0.0
    } else {
        opts.warmup.max(0.0).ceil()
    };
    let revs = if deterministic { 1 } else { opts.revs.max(2) };
    let so = SimOptions {
        level: opts.level,
        warmup,
        revs: revs as f64,
        rtol: opts.rtol,
        method: opts.method,
        grid_deg: Some(360.0 / n as f64),
        // Only the curves are used: the summary's peaks and time averages
        // would cost a tenth of the run for nothing.
        figures: false,
        // Only the stroke and the process force are read below.
        lean_curves: true,
        ..SimOptions::default()
    };
    let r = simulate(&p, &so, progress)?;
    let mut notes = r.notes.clone();
    let curves = r.curves.unwrap_or_default();
    let omega = p.omega();
    let dt = TAU / omega / n as f64;
    let mut stroke = curves.stroke_mm.clone();
    let mut force: Vec<f64> = curves
        .process_force_n
        .iter()
        .map(|f| if f.is_finite() { *f } else { 0.0 })
        .collect();
    if opts.level == Level::Kinematic {
        notes.push("kinematic level: no forces are predicted (force shown as 0)".into());
    }
    lag_filter(&mut stroke, dt, opts.laser_lag_s);
    lag_filter(&mut force, dt, opts.force_lag_s);
    // A deterministic prediction is periodic: filter a second turn so the lag starts settled.
    if deterministic && (opts.laser_lag_s > 0.0 || opts.force_lag_s > 0.0) && stroke.len() >= n {
        let mut s2: Vec<f64> = curves.stroke_mm[..n]
            .iter()
            .chain(curves.stroke_mm[..n].iter())
            .copied()
            .collect();
        let mut f2: Vec<f64> = force[..n]
            .iter()
            .chain(force[..n].iter())
            .copied()
            .collect();
        let f0: Vec<f64> = curves.process_force_n[..n]
            .iter()
            .map(|f| if f.is_finite() { *f } else { 0.0 })
            .collect();
        f2[..n].copy_from_slice(&f0);
        f2[n..].copy_from_slice(&f0);
        lag_filter(&mut s2, dt, opts.laser_lag_s);
        lag_filter(&mut f2, dt, opts.force_lag_s);
        stroke[..n].copy_from_slice(&s2[n..]);
        force[..n].copy_from_slice(&f2[n..]);
    }
    let geom = Geometry::of(&p);
    let (ideal_s, ideal_v) = ideal_curves(&geom, n, omega);
    let stroke_revs: Vec<Vec<f64>> = stroke
        .chunks(n)
        .filter(|c| c.len() == n)
        .map(<[f64]>::to_vec)
        .collect();
    let force_revs: Vec<Vec<f64>> = force
        .chunks(n)
        .filter(|c| c.len() == n)
        .map(<[f64]>::to_vec)
        .collect();
    let standoff_mm = p.standoff * 1e3;
    let figures: Vec<CycleFigures> = stroke_revs
        .iter()
        .zip(&force_revs)
        .map(|(s, f)| CycleFigures::of(s, f, &ideal_s, &ideal_v, omega, standoff_mm))
        .collect();
    Ok(Prediction {
        motor_rpm,
        gear_ratio: p.gear_ratio,
        clearance_mm: p.clearance * 1e3,
        standoff_mm,
        level: opts.level,
        revs: stroke_revs.len(),
        points_per_rev: n,
        stroke: Band::of(stroke_revs.iter().map(Vec::as_slice), n),
        force: Band::of(force_revs.iter().map(Vec::as_slice), n),
        ideal_stroke_mm: ideal_s,
        ideal_vel_mps: ideal_v,
        stroke_revs,
        force_revs,
        figures,
        rhs_evals: r.summary.rhs_evals,
        wall_ms: started.elapsed().as_secs_f64() * 1e3,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_of_a_sine_and_the_lag_filter() {
        let n = 720;
        let omega = 100.0;
        let s: Vec<f64> = (0..n).map(|j| (j as f64 * TAU / n as f64).sin()).collect();
        let v = velocity(&s, omega);
        for (j, vj) in v.iter().enumerate() {
            let want = (j as f64 * TAU / n as f64).cos() * 1e-3 * omega;
            assert!((vj - want).abs() < 1e-3 * 1e-3 * omega, "{j}");
        }
        // Ramp response of a first-order lag: y = t − τ(1 − e^{−t/τ}) for u = t, exact at the samples.
        let (h, tau) = (1e-5, 1e-4);
        let mut x: Vec<f64> = (0..1000).map(|i| i as f64 * h).collect();
        lag_filter(&mut x, h, tau);
        let t = 100.0 * h;
        assert!((x[100] - (t - tau * (1.0 - (-t / tau).exp()))).abs() < 1e-15);
    }

    #[test]
    fn noise_level_of_a_noisy_sine() {
        let mut rng = crate::rig::synth::Rng::new(5);
        let x: Vec<f64> = (0..50_000)
            .map(|i| (i as f64 * 0.01).sin() * 10.0 + 0.05 * rng.normal())
            .collect();
        let s = noise_sigma(&x);
        assert!((s - 0.05).abs() < 0.003, "{s}");
    }

    #[test]
    fn kinematic_prediction_is_the_ideal_curve() {
        let p = Params::paper();
        let o = PredictOptions {
            level: Level::Kinematic,
            ..PredictOptions::default()
        };
        let pr = predict(&p, 1200.0, &o, &Progress::hidden()).unwrap();
        assert_eq!(pr.revs, 1);
        for (a, b) in pr.stroke.mean.iter().zip(&pr.ideal_stroke_mm) {
            assert!((a - b).abs() < 1e-9);
        }
        let f = pr.figures[0];
        assert!((f.stroke_max_mm - 16.0).abs() < 1e-6 && f.disp_dev_max_mm < 1e-9);
        // The velocity differentiated from the stroke matches the closed form.
        assert!(f.vel_dev_max_mps < 2e-3, "{}", f.vel_dev_max_mps);
    }

    #[test]
    fn clearance_prediction_spreads_with_the_clearance() {
        let mut p = Params::paper();
        let o = PredictOptions {
            revs: 12,
            ..PredictOptions::default()
        };
        p.clearance = 0.1e-3;
        let a = predict(&p, 1200.0, &o, &Progress::hidden()).unwrap();
        p.clearance = 0.5e-3;
        let b = predict(&p, 1200.0, &o, &Progress::hidden()).unwrap();
        let rms = |x: &Band| (x.std.iter().map(|s| s * s).sum::<f64>() / x.std.len() as f64).sqrt();
        assert_eq!(a.revs, 12);
        assert!(rms(&b.stroke) > 3.0 * rms(&a.stroke));
        assert!(a.stroke.max.iter().zip(&a.stroke.min).all(|(x, y)| x >= y));
        // Peak load-cell force near the F_ins plateau (23 N).
        let pf = a.figures.iter().map(|f| f.peak_force_n).sum::<f64>() / a.figures.len() as f64;
        assert!((pf - 23.0).abs() < 0.5, "{pf}");
    }
}
