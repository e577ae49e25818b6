//! What the cycle analysis reports: its options, each cycle, the sensor
//! offsets with where their values came from, the run's bands.

use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::rig::report::Finding;
use serde::Serialize;

/// Options of the cycle analysis.
#[derive(Debug, Clone, Serialize)]
pub struct CycleOptions {
    /// Mechanism geometry (m) for the ideal stroke; default: the `paper` preset.
    pub geometry: Geometry,
    /// Grid points per revolution (720 = 0.5°).
    pub points_per_rev: usize,
    /// Session overrides (take precedence over metadata and estimates).
    pub standoff_mm: Option<f64>,
    pub laser_zero_mm: Option<f64>,
    pub force_tare_n: Option<f64>,
    pub angle_offset_rad: Option<f64>,
    pub gear_ratio: Option<f64>,
    /// Largest accepted difference between the crank angle at a cycle mark and TDC.
    pub mark_tolerance_deg: f64,
}

impl Default for CycleOptions {
    fn default() -> Self {
        CycleOptions {
            geometry: Geometry::of(&Params::paper()),
            points_per_rev: 720,
            standoff_mm: None,
            laser_zero_mm: None,
            force_tare_n: None,
            angle_offset_rad: None,
            gear_ratio: None,
            mark_tolerance_deg: 3.0,
        }
    }
}

/// Where a value in use comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ValueSource {
    /// Given in the session / on the command line.
    Override,
    /// The log's `rig` metadata.
    Metadata,
    /// Estimated from the log.
    Estimated,
    /// A default (preset value, or zero).
    Default,
    /// Could not be determined (signal missing).
    Unavailable,
}

/// A sensor offset: the value applied, where it comes from, and the estimate from the data.
#[derive(Debug, Clone, Serialize)]
pub struct OffsetEstimate {
    pub name: String,
    pub unit: String,
    /// The value used.
    pub applied: f64,
    pub source: ValueSource,
    /// Metadata value, if any.
    pub metadata: Option<f64>,
    /// Estimate from the data and its standard uncertainty (statistical).
    pub estimate: Option<f64>,
    pub sigma: Option<f64>,
    /// Systematic uncertainty bound of the estimate (e.g. ± clearance for the laser zero).
    pub systematic: Option<f64>,
    /// How the estimate was made and why the applied value was chosen.
    pub note: String,
}

/// The sensor offsets of a run.
#[derive(Debug, Clone, Serialize)]
pub struct SensorOffsets {
    /// Added to the logged angle to get θ2 (rad).
    pub angle_offset_rad: OffsetEstimate,
    /// Stroke at which the laser reads 0 (mm).
    pub laser_zero_mm: OffsetEstimate,
    /// Load-cell reading with no load (N): the mean over the run.
    pub force_tare_n: OffsetEstimate,
    /// Fitted tare line at the log's start and end (N) and its drift (N/s).
    pub force_tare_start_n: Option<f64>,
    pub force_tare_end_n: Option<f64>,
    /// Standard uncertainties of the fitted tare at the start and the end (N).
    pub force_tare_start_sigma_n: Option<f64>,
    pub force_tare_end_sigma_n: Option<f64>,
    pub force_tare_drift_n_per_s: Option<f64>,
    pub force_tare_drift_sigma: Option<f64>,
}

/// How the cycles were delimited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CycleSource {
    /// The `/rig/cycle` marks.
    Marks,
    /// Crank-angle TDC crossings.
    Angle,
    /// No cycles (no crank angle).
    None,
}

/// One crank revolution, TDC to TDC.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Cycle {
    pub index: u64,
    pub t_start_ns: i64,
    pub t_end_ns: i64,
    pub duration_s: f64,
    /// Crank speed from the cycle's duration (rev/min).
    pub crank_rpm: f64,
    /// Motor speed over the cycle (rev/min): mean, standard deviation and range.
    pub motor_rpm_mean: f64,
    pub motor_rpm_std: f64,
    pub motor_rpm_min: f64,
    pub motor_rpm_max: f64,
    /// Ripple as fractions of the mean: RMS (std/mean), peak-to-peak/2, and the
    /// amplitude of the first harmonic in crank angle (the once-per-rev ripple).
    pub ripple_rms: f64,
    pub ripple_half_p2p: f64,
    pub ripple_first_harmonic: f64,
    /// Crank angle minus TDC at the cycle's marks (degrees; the larger of
    /// its start and end marks), with marks.
    pub mark_mismatch_deg: Option<f64>,
    /// Whether the cycle enters the ensemble statistics.
    pub usable: bool,
    /// Stroke (mm, from TDC; displacement + laser zero) on the grid; NaN = no data.
    pub stroke_mm: Vec<f64>,
    /// Force (N, tare removed) on the grid; empty without a force channel.
    pub force_n: Vec<f64>,
    /// Fractions of grid points with data.
    pub stroke_coverage: f64,
    pub force_coverage: f64,
    pub stroke_max_mm: f64,
    pub stroke_min_mm: f64,
    /// Insertion depth reached: max stroke − standoff (mm; ≤ 0: no contact).
    pub depth_mm: f64,
    pub peak_force_n: f64,
    /// Stroke minus ideal stroke at TDC and BDC (mm).
    pub stroke_err_tdc_mm: f64,
    pub stroke_err_bdc_mm: f64,
    /// Displacement deviation from the ideal mechanism over the cycle: RMS and max |s − s_ideal| (mm).
    pub stroke_dev_rms_mm: f64,
    pub stroke_dev_max_mm: f64,
}

/// Per-grid-point statistics over cycles (NaN where no cycle has data).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Band {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
    /// Cycles contributing to each point.
    pub count: Vec<u32>,
}

impl Band {
    /// Statistics of the rows (NaN entries skipped).
    pub fn of<'a>(rows: impl Iterator<Item = &'a [f64]>, n: usize) -> Band {
        Self::of_mapped(rows, n, |v| v)
    }

    /// [`Band::of`] of the rows with `map` applied to every entry (e.g. an
    /// offset), without materialising the mapped rows.
    pub fn of_mapped<'a>(
        rows: impl Iterator<Item = &'a [f64]>,
        n: usize,
        map: impl Fn(f64) -> f64,
    ) -> Band {
        let mut s = vec![0.0; n];
        let mut s2 = vec![0.0; n];
        let mut mn = vec![f64::INFINITY; n];
        let mut mx = vec![f64::NEG_INFINITY; n];
        let mut c = vec![0u32; n];
        for r in rows {
            for (j, &v) in r.iter().enumerate().take(n) {
                let v = map(v);
                if v.is_finite() {
                    s[j] += v;
                    s2[j] += v * v;
                    mn[j] = mn[j].min(v);
                    mx[j] = mx[j].max(v);
                    c[j] += 1;
                }
            }
        }
        let mut b = Band {
            mean: vec![f64::NAN; n],
            std: vec![f64::NAN; n],
            min: vec![f64::NAN; n],
            max: vec![f64::NAN; n],
            count: c.clone(),
        };
        for j in 0..n {
            if c[j] > 0 {
                let m = s[j] / c[j] as f64;
                b.mean[j] = m;
                b.std[j] = if c[j] > 1 {
                    ((s2[j] - c[j] as f64 * m * m) / (c[j] - 1) as f64)
                        .max(0.0)
                        .sqrt()
                } else {
                    0.0
                };
                b.min[j] = mn[j];
                b.max[j] = mx[j];
            }
        }
        b
    }
}

/// Facts about the crank.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CrankInfo {
    /// The logged angle was wrapped to [0, 2π).
    pub wrapped_input: bool,
    /// Encoder counts per revolution when the logged angle sits on a lattice 2π/N.
    pub encoder_counts: Option<u64>,
    /// Half a count added to every angle (encoders report floor(θ/Δ)), rad.
    pub quantisation_correction_rad: f64,
    pub samples: u64,
    /// Revolutions covered by the angle signal.
    pub revolutions: f64,
    /// "channel" (speed signal) or "angle" (derived).
    pub speed_source: String,
    pub gear_ratio: f64,
    pub gear_ratio_source: Option<ValueSource>,
    /// Mean speeds over the complete cycles (rev/min).
    pub motor_rpm_mean: f64,
    pub crank_rpm_mean: f64,
    /// Smallest and largest cycle-mean motor speed, and their spread relative to the mean.
    pub motor_rpm_cycle_min: f64,
    pub motor_rpm_cycle_max: f64,
    pub speed_spread_rel: f64,
    /// Motor speed set-point from metadata.
    pub motor_rpm_setpoint: Option<f64>,
}

impl CrankInfo {
    /// The σ of an encoder's quantisation (Δ/√12, rad; 0 without an
    /// encoder lattice): a rig sampling in step with the crank sees the
    /// same counts at every mark, so this is the floor of an angle's
    /// uncertainty.
    pub fn encoder_quantum_rad(&self) -> f64 {
        self.encoder_counts
            .map_or(0.0, |n| std::f64::consts::TAU / n as f64 / 12f64.sqrt())
    }
}

/// The cycles of a run.
#[derive(Debug, Clone, Serialize)]
pub struct CycleSet {
    pub file: String,
    pub source: CycleSource,
    pub points_per_rev: usize,
    /// Grid crank angle from TDC, degrees (0, 0.5, ... 359.5).
    pub grid_deg: Vec<f64>,
    /// Ideal (zero-clearance) stroke on the grid, mm.
    pub ideal_stroke_mm: Vec<f64>,
    pub geometry: Geometry,
    pub standoff_mm: f64,
    pub standoff_source: ValueSource,
    pub crank: CrankInfo,
    pub offsets: SensorOffsets,
    pub cycles: Vec<Cycle>,
    /// Statistics of the usable cycles' stroke and force per grid point.
    pub stroke_band: Band,
    pub force_band: Band,
    pub findings: Vec<Finding>,
}

impl CycleSet {
    pub fn usable(&self) -> impl Iterator<Item = &Cycle> {
        self.cycles.iter().filter(|c| c.usable)
    }
}
