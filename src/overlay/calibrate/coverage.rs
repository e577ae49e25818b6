//! Coverage of the calibration's clearance uncertainty: synthetic logs whose
//! truth is known, made to differ from the fitting model's assumptions the
//! way real rigs (and other generators) do, every factor randomised at once.
//!
//! A case is drawn from a seed ([`CoverageCase::random`]): true clearance
//! 0.05–1.0 mm, motor 1000–2000 rpm, one of the five materials, 10–200
//! cycles, a true standoff of 13.7–14.3 mm, metadata clearance ≠ truth,
//! encoder resolution (1024–8192 counts or none), speed ripple (0–1 %, any
//! phase) and speed noise, laser zero (8–12 mm, not in the metadata), laser
//! lag (0 or 1–10 kHz), noise (0–5 µm) and quantisation, load-cell filter
//! (0.5–3 kHz) and noise, force tare and drift, the crank angle at the log
//! start, and the realisation of the chaotic clearance motion (the pin bar
//! started off the model's initial position, 1–5 warm-up revolutions).
//! [`run_case`] writes the log as MCAP in memory, reads it back, cuts it
//! into cycles and calibrates it as `pinsight calibrate` does. The truth is
//! the generator's input, never read back from the log.
//!
//! `tests/dynamics/calibration_coverage.rs` runs a reduced sweep;
//! `examples/calib_coverage.rs` the full one (docs/rig-logs.md,
//! "Calibration: bias and coverage").

use super::{CalibrateOptions, calibrate};
use crate::model::Params;
use crate::model::materials::MATERIALS;
use crate::progress::Progress;
use crate::rig::synth::{self, ModelTruth, SynthConfig, WriteSettings};
use crate::rig::{CycleOptions, LoadOptions, analyse, load_source};
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};

/// The sweep's random numbers (own salt: not the rig generator's stream).
pub type CoverageRng = crate::rng::SplitMix64<0x5EED_C0DE_CA11_B8A7>;

/// One synthetic log of the sweep: the truth and the sensor models.
#[derive(Debug, Clone, Serialize)]
pub struct CoverageCase {
    pub seed: u64,
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub material: String,
    pub cycles: usize,
    pub standoff_mm: f64,
    /// The clearance written in the log's metadata (the calibration's nominal).
    pub meta_clearance_mm: f64,
    pub encoder_counts: u32,
    pub speed_ripple: f64,
    pub ripple_phase: f64,
    pub speed_noise: f64,
    pub laser_zero_mm: f64,
    pub laser_lag_s: f64,
    pub laser_noise_mm: f64,
    pub laser_quantum_mm: f64,
    pub force_lag_s: f64,
    pub force_noise_n: f64,
    pub force_tare_n: f64,
    pub force_drift_n: f64,
    pub start_theta: f64,
    pub warmup_revs: f64,
    pub perturb_x4_m: f64,
    pub cycle_topic: bool,
}

fn pick<T: Copy>(r: &mut CoverageRng, v: &[T]) -> T {
    v[((r.uniform() * v.len() as f64) as usize).min(v.len() - 1)]
}

impl CoverageCase {
    /// A case with every factor drawn from `seed`.
    pub fn random(seed: u64) -> Self {
        let mut r = CoverageRng::new(seed);
        let clearance_mm = r.range(0.05, 1.0);
        let motor_rpm = r.range(1000.0, 2000.0);
        let material = MATERIALS[pick(&mut r, &[0usize, 1, 2, 3, 4])].0.to_string();
        // Log-uniform in 10–200: short logs are as common as long ones.
        let cycles = (10f64 * 20f64.powf(r.uniform())).round() as usize;
        let standoff_mm = r.range(13.7, 14.3);
        // Metadata clearance: a nominal that is not the truth.
        let meta_clearance_mm = loop {
            let m = pick(&mut r, &[0.05, 0.1, 0.2, 0.3, 0.5, 0.8]);
            if (m - clearance_mm).abs() > 0.02 {
                break m;
            }
        };
        let encoder_counts = pick(&mut r, &[0u32, 1024, 2048, 4096, 4096, 8192]);
        let speed_ripple = r.range(0.0, 0.01);
        let ripple_phase = r.range(0.0, TAU);
        let speed_noise = r.range(0.0, 0.005);
        let laser_zero_mm = r.range(8.0, 12.0);
        let laser_lag_s = if r.uniform() < 0.2 {
            0.0
        } else {
            1.0 / (TAU * r.range(1000.0, 10_000.0))
        };
        let laser_noise_mm = r.range(0.0, 0.005);
        let laser_quantum_mm = pick(&mut r, &[0.0, 0.0005, 0.001]);
        let force_lag_s = 1.0 / (TAU * r.range(500.0, 3000.0));
        let force_noise_n = r.range(0.01, 0.1);
        let force_tare_n = r.range(-0.2, 0.2);
        let force_drift_n = r.range(-0.05, 0.05);
        let start_theta = PI + r.range(0.0, TAU);
        let warmup_revs = pick(&mut r, &[1.0, 2.0, 3.0, 4.0, 5.0]);
        let perturb_x4_m = r.range(-1.0, 1.0) * 1e-6;
        let cycle_topic = r.uniform() < 0.8;
        CoverageCase {
            seed,
            clearance_mm,
            motor_rpm,
            material,
            cycles,
            standoff_mm,
            meta_clearance_mm,
            encoder_counts,
            speed_ripple,
            ripple_phase,
            speed_noise,
            laser_zero_mm,
            laser_lag_s,
            laser_noise_mm,
            laser_quantum_mm,
            force_lag_s,
            force_noise_n,
            force_tare_n,
            force_drift_n,
            start_theta,
            warmup_revs,
            perturb_x4_m,
            cycle_topic,
        }
    }

    /// The true parameters (preset `paper` + clearance, standoff, material).
    pub fn params(&self) -> Params {
        let mut p = Params::paper();
        p.set_str("material", &self.material)
            .expect("a built-in material");
        p.clearance = self.clearance_mm * 1e-3;
        p.standoff = self.standoff_mm * 1e-3;
        p.motor_rpm = self.motor_rpm;
        p
    }

    /// The generator's configuration; the metadata carries the nominal
    /// clearance, standoff 14.0 and the material (no laser zero).
    pub fn synth_config(&self) -> SynthConfig {
        let base = SynthConfig::default();
        let mut meta = BTreeMap::new();
        meta.insert("rig_id".to_string(), "coverage".to_string());
        meta.insert(
            "clearance_mm".to_string(),
            format!("{}", self.meta_clearance_mm),
        );
        meta.insert("material".to_string(), self.material.clone());
        meta.insert("motor_rpm".to_string(), format!("{:.0}", self.motor_rpm));
        meta.insert("gear_ratio".to_string(), "1".to_string());
        meta.insert("standoff_mm".to_string(), "14.0".to_string());
        SynthConfig {
            motor_rpm: self.motor_rpm,
            // Whole cycles between the first and the last TDC, part-cycles at both ends.
            revolutions: self.cycles as f64 + 1.4,
            start_theta: self.start_theta,
            encoder_counts: self.encoder_counts,
            speed_ripple: self.speed_ripple,
            ripple_phase: self.ripple_phase,
            speed_noise: self.speed_noise,
            laser_zero_mm: self.laser_zero_mm,
            laser_lag_s: self.laser_lag_s,
            laser_noise_mm: self.laser_noise_mm,
            laser_quantum_mm: self.laser_quantum_mm,
            force_lag_s: self.force_lag_s,
            force_noise_n: self.force_noise_n,
            force_tare_n: self.force_tare_n,
            force_drift_n: self.force_drift_n,
            cycle_topic: self.cycle_topic,
            metadata: Some(meta),
            seed: self.seed,
            ..base
        }
    }
}

/// The calibration of one case against its truth.
#[derive(Debug, Clone, Serialize)]
pub struct CaseResult {
    pub case: CoverageCase,
    /// Cycles the calibration used.
    pub cycles_used: usize,
    pub clearance_mm: f64,
    pub sigma_mm: f64,
    pub u95_mm: f64,
    /// The estimate is at the edge of the simulated grid.
    pub at_edge: bool,
    /// Seconds: making the log, calibrating it.
    pub generate_s: f64,
    pub calibrate_s: f64,
    /// The calibration's notes (how σ was made up).
    pub notes: Vec<String>,
}

impl CaseResult {
    /// Estimate − truth (mm).
    pub fn error_mm(&self) -> f64 {
        self.clearance_mm - self.case.clearance_mm
    }

    /// The truth lies within value ± U95.
    pub fn covered(&self) -> bool {
        self.error_mm().abs() <= self.u95_mm
    }
}

/// Makes the case's log (truth simulated at rtol 1e-8 on a 0.1° grid),
/// writes it as MCAP in memory, reads it back and calibrates it with `opts`.
pub fn run_case(case: &CoverageCase, opts: &CalibrateOptions) -> Result<CaseResult, String> {
    let t0 = std::time::Instant::now();
    let cfg = case.synth_config();
    let truth = ModelTruth::simulate_perturbed(
        &case.params(),
        &cfg,
        case.warmup_revs,
        0.1,
        1e-8,
        case.perturb_x4_m,
    )
    .map_err(|e| format!("seed {}: truth simulation failed: {e}", case.seed))?;
    let log = synth::generate(&cfg, &truth);
    let mut bytes = std::io::Cursor::new(Vec::new());
    synth::write(&log, &mut bytes, &WriteSettings::default())
        .map_err(|e| format!("seed {}: writing the log: {e}", case.seed))?;
    let generate_s = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let src = crate::rig::mcap_read::Source::from_vec(
        format!("coverage-{}.mcap", case.seed),
        bytes.into_inner(),
    );
    let rig = load_source(&src, &LoadOptions::default(), &Progress::hidden())
        .map_err(|e| format!("seed {}: reading the log back: {e}", case.seed))?;
    let cs = analyse(&rig, &CycleOptions::default());
    let (base, _) = crate::overlay::compare::model_params(&rig, None, &[])
        .map_err(|e| format!("seed {}: parameters: {e}", case.seed))?;
    let r = calibrate(&rig, &cs, &base, opts, &Progress::hidden())
        .map_err(|e| format!("seed {}: calibrate: {e}", case.seed))?;
    let e = r
        .estimates
        .iter()
        .find(|e| e.name == "clearance")
        .ok_or_else(|| format!("seed {}: no clearance estimate", case.seed))?;
    Ok(CaseResult {
        case: case.clone(),
        cycles_used: r.cycles,
        clearance_mm: e.value,
        sigma_mm: e.sigma,
        u95_mm: e.u95,
        at_edge: r
            .notes
            .iter()
            .any(|n| n.contains("edge of the simulated grid")),
        generate_s,
        calibrate_s: t1.elapsed().as_secs_f64(),
        notes: r.notes.clone(),
    })
}

/// Coverage, bias and spread of a set of results.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct CoverageRow {
    pub n: usize,
    /// Fraction of cases with the truth within ± U95.
    pub coverage: f64,
    /// Mean of estimate − truth (mm) and its standard error.
    pub bias_mm: f64,
    pub bias_se_mm: f64,
    /// Mean of (estimate − truth)/truth.
    pub rel_bias: f64,
    pub median_u95_mm: f64,
    /// Mean of (estimate − truth)/σ (≈ 0) and its RMS (≈ 1 when σ is honest).
    pub mean_z: f64,
    pub rms_z: f64,
}

/// The statistics of `rs` (empty: n = 0, the rest NaN).
pub fn coverage_row(rs: &[&CaseResult]) -> CoverageRow {
    let n = rs.len();
    if n == 0 {
        return CoverageRow {
            n,
            coverage: f64::NAN,
            bias_mm: f64::NAN,
            bias_se_mm: f64::NAN,
            rel_bias: f64::NAN,
            median_u95_mm: f64::NAN,
            mean_z: f64::NAN,
            rms_z: f64::NAN,
        };
    }
    let k = n as f64;
    let err: Vec<f64> = rs.iter().map(|r| r.error_mm()).collect();
    let bias = err.iter().sum::<f64>() / k;
    let var = err.iter().map(|e| (e - bias).powi(2)).sum::<f64>() / (k - 1.0).max(1.0);
    let mut u: Vec<f64> = rs.iter().map(|r| r.u95_mm).collect();
    u.sort_by(|a, b| a.total_cmp(b));
    let med = if n % 2 == 1 {
        u[n / 2]
    } else {
        0.5 * (u[n / 2 - 1] + u[n / 2])
    };
    let z: Vec<f64> = rs.iter().map(|r| r.error_mm() / r.sigma_mm).collect();
    CoverageRow {
        n,
        coverage: rs.iter().filter(|r| r.covered()).count() as f64 / k,
        bias_mm: bias,
        bias_se_mm: (var / k).sqrt(),
        rel_bias: rs
            .iter()
            .map(|r| r.error_mm() / r.case.clearance_mm)
            .sum::<f64>()
            / k,
        median_u95_mm: med,
        mean_z: z.iter().sum::<f64>() / k,
        rms_z: (z.iter().map(|x| x * x).sum::<f64>() / k).sqrt(),
    }
}
