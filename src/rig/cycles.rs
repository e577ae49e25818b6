//! Cycles: the crank angle unwrapped, the run split at top dead centre, and
//! each cycle's stroke and force resampled on a crank-angle grid.
//!
//! Crank angle. The logged angle (wrapped to [0, 2π) or already unwrapped)
//! is unwrapped step by step, choosing the 2π multiple that makes each step
//! closest to the advance expected at the median crank speed (so a spindle
//! drop-out shorter than half a revolution does not lose a turn). θ2 =
//! angle + offset, where the offset is, in this order: a session override,
//! the metadata's `angle_offset_rad`, or an estimate — from the `/rig/cycle`
//! marks (the angle at a mark is TDC by definition) or else from the
//! displacement signal (the phase that best fits the ideal stroke). Without
//! an override or metadata, an estimate is applied only when it is larger
//! than max(3σ, 1°): below that, its own systematic errors (sensor lag,
//! encoder quantisation, clearance) are of the same size and the encoder is
//! taken as calibrated. Either way the estimate is reported.
//!
//! Cycles. Cycle k runs from the TDC with index k to the next TDC. With
//! `/rig/cycle` marks the marks give the indices and the revolution; without
//! them the TDCs are where θ2 passes TDC (π for zero offset), numbered from
//! 0. Within a cycle, samples are placed by crank angle φ = θ2 − θ_TDC ∈
//! [0, 2π) and interpolated linearly onto a grid of `points_per_rev` points
//! (720: 0.5°); a grid point between two samples further apart than 2.5
//! nominal sample intervals (a gap) is NaN. When the crank angle at a mark
//! differs from TDC by more than `mark_tolerance_deg` (a spindle clock jump,
//! a slipping encoder), the cycle is flagged unusable and left out of the
//! ensemble statistics.
//!
//! Sensor zeros are estimated and reported, never silently absorbed:
//! - laser zero mark z (stroke at which the laser reads 0): stroke =
//!   displacement + z; from metadata `laser_zero_mm`, else the mean of
//!   s_ideal(φ) − displacement over the off-part part of every cycle. With a
//!   clearance c the journal's mean position is not the ideal one, so this
//!   estimate carries a systematic uncertainty of up to ±c (reported).
//! - force tare: the load-cell reading off the part (ideal stroke more than
//!   1 mm above the standoff), per cycle, fitted linearly in time (drift);
//!   from metadata `force_tare_n` (a constant) when given, else the fitted
//!   line is subtracted sample by sample.

use super::channel_map::SignalKind;
use super::load::RigLog;
use super::report::{Finding, FindingCode, Place, Severity, fmt_time};
use super::signals::Signal;
use crate::model::Params;
use crate::model::kinematics::Geometry;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::{PI, TAU};

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
#[derive(Debug, Clone, Serialize)]
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

/// Wraps an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(TAU) - PI;
    if w <= -PI { w + TAU } else { w }
}

/// The unwrapped crank angle θ2(t) (offset applied).
#[derive(Debug, Clone)]
pub struct Crank {
    pub t_ns: Vec<i64>,
    /// Unwrapped θ2, rad.
    pub theta: Vec<f64>,
    /// Median sample interval (ns).
    pub dt_ns: i64,
    /// Median crank speed (rad/s).
    pub omega: f64,
}

impl Crank {
    /// Unwraps a logged angle signal (wrapped or not). Returns None with fewer than 3 samples.
    pub fn unwrap(angle: &Signal) -> Option<(Crank, bool)> {
        let n = angle.len();
        if n < 3 {
            return None;
        }
        let t = &angle.t_ns;
        let a = &angle.values;
        let stride = (n / 20_000).max(1);
        let mut rates: Vec<f64> = (1..n)
            .step_by(stride)
            .filter(|&i| t[i] > t[i - 1])
            .map(|i| wrap_pi(a[i] - a[i - 1]) / ((t[i] - t[i - 1]) as f64 * 1e-9))
            .collect();
        let mut dts: Vec<i64> = (1..n).step_by(stride).map(|i| t[i] - t[i - 1]).collect();
        if rates.is_empty() {
            return None;
        }
        let mid = rates.len() / 2;
        let omega = *rates.select_nth_unstable_by(mid, |x, y| x.total_cmp(y)).1;
        let mid = dts.len() / 2;
        let dt_ns = *dts.select_nth_unstable(mid).1;
        let mut theta = Vec::with_capacity(n);
        theta.push(a[0]);
        let mut wrapped = false;
        for i in 1..n {
            let d = a[i] - a[i - 1];
            let expected = omega * (t[i] - t[i - 1]) as f64 * 1e-9;
            let k = ((expected - d) / TAU).round();
            if k != 0.0 {
                wrapped = true;
            }
            theta.push(theta[i - 1] + d + k * TAU);
        }
        Some((
            Crank {
                t_ns: t.clone(),
                theta,
                dt_ns,
                omega,
            },
            wrapped,
        ))
    }

    /// θ2 at time t (linear interpolation; None outside the samples or across
    /// a spindle hole longer than 5 nominal intervals).
    pub fn at(&self, t: i64) -> Option<f64> {
        let mut h = 0;
        self.at_from(t, &mut h)
    }

    /// [`Crank::at`] for increasing times: `hint` remembers where the last
    /// query ended so a sweep costs O(n) instead of O(n log n).
    pub fn at_from(&self, t: i64, hint: &mut usize) -> Option<f64> {
        let n = self.t_ns.len();
        let mut i = (*hint).min(n);
        if i > 0 && self.t_ns[i - 1] >= t {
            i = self.t_ns.partition_point(|&x| x < t);
        } else {
            let stop = (i + 16).min(n);
            while i < stop && self.t_ns[i] < t {
                i += 1;
            }
            if i == stop && i < n && self.t_ns[i] < t {
                i += self.t_ns[i..].partition_point(|&x| x < t);
            }
        }
        *hint = i;
        if i < self.t_ns.len() && self.t_ns[i] == t {
            return Some(self.theta[i]);
        }
        if i == 0 || i >= self.t_ns.len() {
            return None;
        }
        let (t0, t1) = (self.t_ns[i - 1], self.t_ns[i]);
        if t1 - t0 > self.dt_ns.max(1).saturating_mul(5) {
            return None;
        }
        let w = (t - t0) as f64 / (t1 - t0) as f64;
        Some(self.theta[i - 1] + w * (self.theta[i] - self.theta[i - 1]))
    }

    /// Times where θ2 passes `tdc + 2πn` (increasing θ), with n.
    pub fn crossings(&self, tdc: f64) -> Vec<(i64, i64)> {
        let mut out = Vec::new();
        for i in 1..self.theta.len() {
            let (a, b) = (self.theta[i - 1] - tdc, self.theta[i] - tdc);
            let (na, nb) = ((a / TAU).floor(), (b / TAU).floor());
            if nb > na && self.t_ns[i] - self.t_ns[i - 1] <= self.dt_ns.max(1).saturating_mul(5) {
                // One crossing per revolution passed (more only across holes, excluded above).
                for n in (na as i64 + 1)..=(nb as i64) {
                    let target = n as f64 * TAU;
                    let w = (target - a) / (b - a);
                    let tt = self.t_ns[i - 1]
                        + ((self.t_ns[i] - self.t_ns[i - 1]) as f64 * w).round() as i64;
                    out.push((tt, n));
                }
            }
        }
        out
    }
}

/// Encoder counts per revolution, when the angles are multiples of 2π/N for an
/// integer N ≤ 100 000: N = 2π / (approximate GCD of the differences between
/// the distinct angle values), checked on up to 5000 samples. (A rig that
/// samples in step with the crank sees the same few counts every turn, so the
/// smallest difference alone is not the count.)
pub fn detect_encoder_counts(values: &[f64]) -> Option<u64> {
    if values.len() < 200 {
        return None;
    }
    let stride = (values.len() / 5000).max(1);
    let sub: Vec<f64> = values
        .iter()
        .step_by(stride)
        .map(|v| v.rem_euclid(TAU))
        .collect();
    let mut u = sub.clone();
    u.sort_by(|a, b| a.total_cmp(b));
    u.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    if u.len() < 3 {
        return None;
    }
    let tol = 1e-9;
    let fgcd = |a: f64, b: f64| {
        let (mut a, mut b) = (a.max(b), a.min(b));
        let mut steps = 0;
        while b > tol && steps < 200 {
            let mut r = a % b;
            if b - r < tol {
                r = 0.0;
            }
            a = b;
            b = r;
            steps += 1;
        }
        a
    };
    let g = u.windows(2).map(|w| w[1] - w[0]).fold(TAU, fgcd);
    if g <= tol {
        return None;
    }
    let n = (TAU / g).round();
    if !(8.0..=100_000.0).contains(&n) || (TAU / g - n).abs() > 1e-3 {
        return None;
    }
    let q = TAU / n;
    sub.iter()
        .all(|v| (v / q - (v / q).round()).abs() < 1e-6)
        .then_some(n as u64)
}

/// Sample interval (ns) of a signal: the median.
fn median_dt(s: &Signal) -> i64 {
    let n = s.len();
    if n < 2 {
        return 1;
    }
    let stride = (n / 20_000).max(1);
    let mut d: Vec<i64> = (1..n)
        .step_by(stride)
        .map(|i| s.t_ns[i] - s.t_ns[i - 1])
        .collect();
    let mid = d.len() / 2;
    *d.select_nth_unstable(mid).1
}

/// Samples of `sig` around a cycle, placed by crank angle φ = θ2 − θ_tdc,
/// sorted by φ, restricted to φ ∈ [−margin, 2π + margin].
fn placed(
    sig: &Signal,
    crank: &Crank,
    t0: i64,
    t1: i64,
    theta_tdc: f64,
    margin: f64,
) -> Vec<(f64, i64, f64)> {
    let pad = (t1 - t0) / 4;
    let i0 = sig.t_ns.partition_point(|&t| t < t0.saturating_sub(pad));
    let i1 = sig.t_ns.partition_point(|&t| t <= t1.saturating_add(pad));
    let mut pts = Vec::with_capacity(i1.saturating_sub(i0));
    let mut hint = 0;
    for i in i0..i1 {
        if let Some(th) = crank.at_from(sig.t_ns[i], &mut hint) {
            let phi = th - theta_tdc;
            if (-margin..=TAU + margin).contains(&phi) {
                pts.push((phi, sig.t_ns[i], sig.values[i]));
            }
        }
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

/// Linear interpolation of (φ, value) points onto the grid; NaN across holes wider than `max_dphi`.
fn to_grid(pts: &[(f64, f64)], n: usize, max_dphi: f64) -> Vec<f64> {
    let mut out = vec![f64::NAN; n];
    if pts.len() < 2 {
        return out;
    }
    let mut k = 0usize;
    for (j, o) in out.iter_mut().enumerate() {
        let phi = j as f64 * TAU / n as f64;
        while k + 1 < pts.len() && pts[k + 1].0 < phi {
            k += 1;
        }
        if k + 1 >= pts.len() {
            break;
        }
        let (p0, v0) = pts[k];
        let (p1, v1) = pts[k + 1];
        if p0 > phi || p1 < phi || p1 - p0 > max_dphi {
            continue;
        }
        *o = if p1 > p0 {
            v0 + (v1 - v0) * (phi - p0) / (p1 - p0)
        } else {
            v0
        };
    }
    out
}

fn mean_std(x: &[f64]) -> (f64, f64) {
    let v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    let s = if v.len() > 1 {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    } else {
        0.0
    };
    (m, s)
}

/// A least-squares line y = a + b·x with what is needed for its uncertainty.
#[derive(Debug, Clone, Copy)]
struct LineFit {
    a: f64,
    b: f64,
    /// Residual variance, number of points, mean of x, Σ(x − x̄)².
    s2: f64,
    n: f64,
    mx: f64,
    sxx: f64,
}

impl LineFit {
    fn at(&self, x: f64) -> f64 {
        self.a + self.b * x
    }
    /// Standard uncertainty of the fitted line at x.
    fn sigma_at(&self, x: f64) -> f64 {
        (self.s2 * (1.0 / self.n + (x - self.mx).powi(2) / self.sxx)).sqrt()
    }
    fn sigma_b(&self) -> f64 {
        (self.s2 / self.sxx).sqrt()
    }
}

fn line_fit(x: &[f64], y: &[f64]) -> Option<LineFit> {
    let n = x.len();
    if n < 3 {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    let res: f64 = x
        .iter()
        .zip(y)
        .map(|(a2, b2)| (b2 - a - b * a2).powi(2))
        .sum();
    Some(LineFit {
        a,
        b,
        s2: res / (n - 2) as f64,
        n: n as f64,
        mx,
        sxx,
    })
}

/// Motor-speed statistics of one cycle: mean, std, min, max, first-harmonic amplitude (relative).
fn speed_stats(samples: &[(f64, f64)]) -> (f64, f64, f64, f64, f64) {
    if samples.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    }
    let v: Vec<f64> = samples.iter().map(|s| s.1).collect();
    let (m, s) = mean_std(&v);
    let mn = v.iter().copied().fold(f64::INFINITY, f64::min);
    let mx = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // speed ≈ a0 + a1 cos φ + b1 sin φ by least squares (normal equations, 3×3).
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for &(phi, y) in samples {
        let r = nalgebra::Vector3::new(1.0, phi.cos(), phi.sin());
        ata += r * r.transpose();
        atb += r * y;
    }
    let h = ata
        .lu()
        .solve(&atb)
        .map(|c| (c[1] * c[1] + c[2] * c[2]).sqrt() / c[0])
        .unwrap_or(f64::NAN);
    (m, s, mn, mx, h)
}

/// Phase φ that best fits displacement d ≈ s_ideal(θ + φ) − z (z free), by
/// grid search over a full turn then golden-section refinement.
fn fit_phase(geom: &Geometry, theta: &[f64], d_mm: &[f64], around: Option<f64>) -> Option<f64> {
    if theta.len() < 20 {
        return None;
    }
    let cost = |phi: f64| -> f64 {
        let r: Vec<f64> = theta
            .iter()
            .zip(d_mm)
            .map(|(th, d)| geom.stroke_at(th + phi) * 1e3 - d)
            .collect();
        let m = r.iter().sum::<f64>() / r.len() as f64;
        r.iter().map(|x| (x - m).powi(2)).sum::<f64>()
    };
    let (mut lo, mut hi) = match around {
        Some(c) => (c - 1.5f64.to_radians(), c + 1.5f64.to_radians()),
        None => {
            // Coarse search on a sub-sample, refined on all points below.
            let stride = (theta.len() / 2000).max(1);
            let th2: Vec<f64> = theta.iter().step_by(stride).copied().collect();
            let d2: Vec<f64> = d_mm.iter().step_by(stride).copied().collect();
            let coarse = |phi: f64| -> f64 {
                let r: Vec<f64> = th2
                    .iter()
                    .zip(&d2)
                    .map(|(th, d)| geom.stroke_at(th + phi) * 1e3 - d)
                    .collect();
                let m = r.iter().sum::<f64>() / r.len() as f64;
                r.iter().map(|x| (x - m).powi(2)).sum::<f64>()
            };
            let mut best = (f64::INFINITY, 0.0);
            for k in 0..360 {
                let phi = (k as f64 - 180.0).to_radians();
                let c = coarse(phi);
                if c < best.0 {
                    best = (c, phi);
                }
            }
            (best.1 - 1.5f64.to_radians(), best.1 + 1.5f64.to_radians())
        }
    };
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (cost(x1), cost(x2));
    for _ in 0..40 {
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = cost(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = cost(x2);
        }
    }
    Some(0.5 * (lo + hi))
}

struct Bound {
    index: u64,
    t0: i64,
    t1: i64,
    theta_tdc: f64,
    /// Crank angle minus TDC at the cycle's start and end marks (degrees).
    mismatch_deg: Option<f64>,
    mismatch_end_deg: Option<f64>,
}

/// Splits a loaded log into cycles and resamples them (see the module docs).
pub fn analyse(log: &RigLog, opts: &CycleOptions) -> CycleSet {
    let file = log.file.clone();
    let t_start = log.log_start_ns;
    let mut findings: Vec<Finding> = Vec::new();
    let n = opts.points_per_rev.max(8);
    let geom = opts.geometry;
    let tdc = geom.tdc_angle();
    let grid_deg: Vec<f64> = (0..n).map(|j| j as f64 * 360.0 / n as f64).collect();
    let ideal: Vec<f64> = (0..n)
        .map(|j| geom.stroke_at(tdc + j as f64 * TAU / n as f64) * 1e3)
        .collect();
    let (standoff_mm, standoff_source) = match (opts.standoff_mm, log.meta.standoff_mm) {
        (Some(s), _) => (s, ValueSource::Override),
        (None, Some(s)) => (s, ValueSource::Metadata),
        _ => (Params::paper().standoff * 1e3, ValueSource::Default),
    };
    let (gear, gear_src) = match (opts.gear_ratio, log.meta.gear_ratio) {
        (Some(g), _) => (g, Some(ValueSource::Override)),
        (None, Some(g)) => (g, Some(ValueSource::Metadata)),
        _ => (1.0, Some(ValueSource::Default)),
    };
    let unavailable = |name: &str, unit: &str, note: &str| OffsetEstimate {
        name: name.into(),
        unit: unit.into(),
        applied: 0.0,
        source: ValueSource::Unavailable,
        metadata: None,
        estimate: None,
        sigma: None,
        systematic: None,
        note: note.into(),
    };
    let mut set = CycleSet {
        file: file.clone(),
        source: CycleSource::None,
        points_per_rev: n,
        grid_deg,
        ideal_stroke_mm: ideal.clone(),
        geometry: geom,
        standoff_mm,
        standoff_source,
        crank: CrankInfo {
            gear_ratio: gear,
            gear_ratio_source: gear_src,
            motor_rpm_setpoint: log.meta.motor_rpm,
            ..Default::default()
        },
        offsets: SensorOffsets {
            angle_offset_rad: unavailable("angle offset", "rad", "no crank angle"),
            laser_zero_mm: unavailable("laser zero mark", "mm", "no displacement channel"),
            force_tare_n: unavailable("force tare", "N", "no force channel"),
            force_tare_start_n: None,
            force_tare_end_n: None,
            force_tare_start_sigma_n: None,
            force_tare_end_sigma_n: None,
            force_tare_drift_n_per_s: None,
            force_tare_drift_sigma: None,
        },
        cycles: Vec::new(),
        stroke_band: Band::default(),
        force_band: Band::default(),
        findings: Vec::new(),
    };
    let Some(angle) = log.signals.get(SignalKind::Angle).filter(|a| a.len() >= 3) else {
        set.findings.push(Finding::new(
            Severity::Warning,
            FindingCode::Cycle,
            &file,
            None,
            None,
            "no crank angle: cycles cannot be found",
        ));
        return set;
    };
    let label_angle = format!("{} (angle)", angle.topic);
    let Some((mut crank, wrapped)) = Crank::unwrap(angle) else {
        return set;
    };
    set.crank.wrapped_input = wrapped;
    set.crank.samples = angle.len() as u64;
    if let Some(nc) = detect_encoder_counts(&angle.values) {
        let half = PI / nc as f64;
        for th in crank.theta.iter_mut() {
            *th += half;
        }
        set.crank.encoder_counts = Some(nc);
        set.crank.quantisation_correction_rad = half;
        findings.push(Finding::new(
            Severity::Info,
            FindingCode::OffsetEstimated,
            &file,
            Some(&label_angle),
            None,
            format!(
                "the crank angle is quantised to 2π/{nc} (an encoder of {nc} counts per turn): half a count ({:.4}°) is added, as encoders report floor(θ/Δ)",
                half.to_degrees()
            ),
        ));
    }
    if crank.omega <= 0.0 {
        set.findings.push(Finding::new(
            Severity::Warning,
            FindingCode::Cycle,
            &file,
            Some(&label_angle),
            None,
            format!(
                "the crank angle decreases (median speed {:.1} rad/s): the crank turns backwards or the encoder counts down; cycles cannot be found",
                crank.omega
            ),
        ));
        return set;
    }
    let cyc_sig = log.signals.get(SignalKind::Cycle).filter(|c| c.len() >= 2);

    // --- angle offset ---
    let mut ao = OffsetEstimate {
        name: "angle offset".into(),
        unit: "rad".into(),
        applied: 0.0,
        source: ValueSource::Default,
        metadata: log.meta.angle_offset_rad,
        estimate: None,
        sigma: None,
        systematic: None,
        note: String::new(),
    };
    let mut est_method = "";
    if let Some(c) = cyc_sig {
        let offs: Vec<f64> = c
            .t_ns
            .iter()
            .filter_map(|&t| crank.at(t))
            .map(|th| wrap_pi(tdc - th))
            .collect();
        if !offs.is_empty() {
            // Circular mean, robust to a few outliers (clock jumps): median of wrapped values.
            let mut sorted = offs.clone();
            sorted.sort_by(|a, b| a.total_cmp(b));
            let med = sorted[sorted.len() / 2];
            let close: Vec<f64> = offs
                .iter()
                .copied()
                .filter(|o| wrap_pi(o - med).abs() < 2f64.to_radians())
                .collect();
            let (m, s) = mean_std(&close);
            // A rig sampling in step with the crank sees the same encoder
            // counts at every mark, so the spread can be ~0: the encoder's
            // quantisation (Δ/√12) is the floor of the uncertainty.
            let quantum = set
                .crank
                .encoder_counts
                .map_or(0.0, |n| TAU / n as f64 / 12f64.sqrt());
            let stat = if close.len() > 1 {
                s / (close.len() as f64).sqrt()
            } else {
                f64::NAN
            };
            ao.estimate = Some(m);
            ao.sigma = Some(stat.max(quantum));
            est_method = "from the crank angle at the /rig/cycle marks";
        }
    }
    if ao.estimate.is_none() {
        if let Some(d) = log
            .signals
            .get(SignalKind::Displacement)
            .filter(|d| d.len() > 100)
        {
            let stride = (d.len() / 20_000).max(1);
            let mut th = Vec::new();
            let mut dv = Vec::new();
            for i in (0..d.len()).step_by(stride) {
                if let Some(t) = crank.at(d.t_ns[i]) {
                    th.push(t);
                    dv.push(d.values[i]);
                }
            }
            if let Some(phi) = fit_phase(&geom, &th, &dv, None) {
                let k = 8;
                let len = th.len() / k;
                let parts: Vec<f64> = (0..k)
                    .filter_map(|b| {
                        fit_phase(
                            &geom,
                            &th[b * len..(b + 1) * len],
                            &dv[b * len..(b + 1) * len],
                            Some(phi),
                        )
                    })
                    .collect();
                let (_, s) = mean_std(&parts);
                let quantum = set
                    .crank
                    .encoder_counts
                    .map_or(0.0, |n| TAU / n as f64 / 12f64.sqrt());
                ao.estimate = Some(wrap_pi(phi));
                ao.sigma = Some((s / (parts.len().max(1) as f64).sqrt()).max(quantum));
                est_method = "from the displacement signal (phase of the best fit to the ideal stroke; biased by the sensor lag, ω·τ)";
            }
        }
    }
    let est_text = match (ao.estimate, ao.sigma) {
        (Some(e), Some(s)) => format!(
            "{:.3}° ± {:.3}° ({est_method})",
            e.to_degrees(),
            s.to_degrees()
        ),
        _ => "not estimable".to_string(),
    };
    if let Some(o) = opts.angle_offset_rad {
        ao.applied = o;
        ao.source = ValueSource::Override;
        ao.note = format!(
            "session override {:.3}°; estimate {est_text}",
            o.to_degrees()
        );
    } else if let Some(m) = log.meta.angle_offset_rad {
        ao.applied = m;
        ao.source = ValueSource::Metadata;
        ao.note = format!(
            "metadata angle_offset_rad {:.3}°; estimate {est_text}",
            m.to_degrees()
        );
        if let (Some(e), Some(s)) = (ao.estimate, ao.sigma) {
            if wrap_pi(e - m).abs() > (3.0 * s).max(1f64.to_radians()) {
                findings.push(Finding::new(
                    Severity::Warning,
                    FindingCode::OffsetEstimated,
                    &file,
                    Some(&label_angle),
                    None,
                    format!(
                        "metadata angle_offset_rad = {m} rad ({:.2}°) disagrees with the estimate {est_text}; the metadata value is used",
                        m.to_degrees()
                    ),
                ));
            }
        }
    } else if let (Some(e), Some(s)) = (ao.estimate, ao.sigma) {
        let thr = (3.0 * s).max(1f64.to_radians());
        if e.abs() > thr {
            ao.applied = e;
            ao.source = ValueSource::Estimated;
            ao.note =
                format!("no angle_offset_rad in the metadata: the estimate {est_text} is applied");
            findings.push(Finding::new(
                Severity::Warning,
                FindingCode::OffsetEstimated,
                &file,
                Some(&label_angle),
                None,
                format!("encoder zero is off: crank angle offset estimated at {est_text} and applied (no angle_offset_rad in the metadata)"),
            ));
        } else {
            ao.note = format!(
                "no angle_offset_rad in the metadata; estimate {est_text} is within max(3σ, 1°) of 0: the encoder is taken as calibrated (offset 0)"
            );
            findings.push(Finding::new(
                Severity::Info,
                FindingCode::OffsetEstimated,
                &file,
                Some(&label_angle),
                None,
                format!("crank angle offset estimated at {est_text}: consistent with a calibrated encoder, 0 used"),
            ));
        }
    } else {
        ao.note = "no metadata and no estimate: 0 used".into();
    }
    for th in crank.theta.iter_mut() {
        *th += ao.applied;
    }
    set.offsets.angle_offset_rad = ao;
    set.crank.revolutions = (crank.theta.last().copied().unwrap_or(0.0) - crank.theta[0]) / TAU;

    // --- cycle boundaries ---
    let crossings = crank.crossings(tdc);
    let mut bounds: Vec<Bound> = Vec::new();
    if let Some(c) = cyc_sig {
        set.source = CycleSource::Marks;
        let marks: Vec<(i64, u64)> = c
            .t_ns
            .iter()
            .zip(&c.values)
            .map(|(&t, &v)| (t, v.max(0.0) as u64))
            .collect();
        for w in marks.windows(2) {
            let ((ta, ia), (tb, ib)) = (w[0], w[1]);
            let (Some(tha), Some(thb)) = (crank.at(ta), crank.at(tb)) else {
                continue;
            };
            let nrev = ((tha - tdc) / TAU).round();
            let theta_tdc = tdc + nrev * TAU;
            let mismatch = (tha - theta_tdc).to_degrees();
            let mismatch_end = wrap_pi(thb - tdc).to_degrees();
            if ib == ia + 1 {
                bounds.push(Bound {
                    index: ia,
                    t0: ta,
                    t1: tb,
                    theta_tdc,
                    mismatch_deg: Some(mismatch),
                    mismatch_end_deg: Some(mismatch_end),
                });
            } else if ib > ia + 1 {
                // Missing marks: fill in from the angle when the revolutions match.
                let inner: Vec<&(i64, i64)> = crossings
                    .iter()
                    .filter(|(t, _)| {
                        *t > ta + (tb - ta) / (4 * (ib - ia) as i64)
                            && *t < tb - (tb - ta) / (4 * (ib - ia) as i64)
                    })
                    .collect();
                if inner.len() as u64 == ib - ia - 1 {
                    let mut times = vec![ta];
                    times.extend(inner.iter().map(|x| x.0));
                    times.push(tb);
                    for (k, p) in times.windows(2).enumerate() {
                        bounds.push(Bound {
                            index: ia + k as u64,
                            t0: p[0],
                            t1: p[1],
                            theta_tdc: theta_tdc + k as f64 * TAU,
                            mismatch_deg: (k == 0).then_some(mismatch),
                            mismatch_end_deg: (k + 2 == times.len()).then_some(mismatch_end),
                        });
                    }
                    findings.push(Finding::new(
                        Severity::Info,
                        FindingCode::Cycle,
                        &file,
                        Some(&c.topic),
                        Some(Place::span(ta, tb)),
                        format!("cycle marks {}..{} missing between {} and log_time {tb}: those cycles were delimited by the crank angle", ia + 1, ib - 1, fmt_time(ta, t_start)),
                    ));
                } else {
                    findings.push(Finding::new(
                        Severity::Warning,
                        FindingCode::Cycle,
                        &file,
                        Some(&c.topic),
                        Some(Place::span(ta, tb)),
                        format!("cycle marks {}..{} missing between {} and log_time {tb} and the crank angle does not resolve them: cycles {ia}..{} skipped", ia + 1, ib - 1, fmt_time(ta, t_start), ib - 1),
                    ));
                }
            }
        }
    } else {
        set.source = CycleSource::Angle;
        if let Some(&(_, n0)) = crossings.first() {
            for w in crossings.windows(2) {
                let ((ta, na), (tb, nb)) = (w[0], w[1]);
                if nb == na + 1 {
                    bounds.push(Bound {
                        index: (na - n0) as u64,
                        t0: ta,
                        t1: tb,
                        theta_tdc: tdc + na as f64 * TAU,
                        mismatch_deg: None,
                        mismatch_end_deg: None,
                    });
                }
            }
        }
    }

    // --- per-cycle resampling ---
    let disp = log
        .signals
        .get(SignalKind::Displacement)
        .filter(|s| s.len() > 1);
    let force = log.signals.get(SignalKind::Force).filter(|s| s.len() > 1);
    let speed = log.signals.get(SignalKind::Speed).filter(|s| s.len() > 1);
    set.crank.speed_source = if speed.is_some() { "channel" } else { "angle" }.into();
    let disp_dt = disp.map(median_dt).unwrap_or(1);
    let force_dt = force.map(median_dt).unwrap_or(1);
    let margin = 5f64.to_radians();
    let tol = opts.mark_tolerance_deg;
    let off_part: Vec<bool> = ideal.iter().map(|&s| s < standoff_mm - 1.0).collect();
    // Cycles are independent: resample them in parallel.
    let per_cycle: Vec<(Vec<f64>, Vec<f64>, Cycle)> = bounds
        .par_iter()
        .map(|b| {
            let dur = (b.t1 - b.t0) as f64 * 1e-9;
            let omega = TAU / dur;
            let grid_of = |sig: Option<&Signal>, dt: i64| -> Vec<f64> {
                match sig {
                    None => Vec::new(),
                    Some(s) => {
                        let pts: Vec<(f64, f64)> =
                            placed(s, &crank, b.t0, b.t1, b.theta_tdc, margin)
                                .into_iter()
                                .map(|(p, _, v)| (p, v))
                                .collect();
                        to_grid(&pts, n, 2.5 * omega * dt as f64 * 1e-9)
                    }
                }
            };
            let gd = grid_of(disp, disp_dt);
            let gf = grid_of(force, force_dt);
            // Motor speed over the cycle.
            let sp: Vec<(f64, f64)> = match speed {
                Some(s) => {
                    let i0 = s.t_ns.partition_point(|&t| t < b.t0);
                    let i1 = s.t_ns.partition_point(|&t| t < b.t1);
                    let mut hint = 0;
                    (i0..i1)
                        .filter_map(|i| {
                            crank
                                .at_from(s.t_ns[i], &mut hint)
                                .map(|th| (th - b.theta_tdc, s.values[i]))
                        })
                        .collect()
                }
                None => {
                    let i0 = crank.t_ns.partition_point(|&t| t < b.t0).max(1);
                    let i1 = crank
                        .t_ns
                        .partition_point(|&t| t < b.t1)
                        .min(crank.t_ns.len().saturating_sub(1));
                    (i0..i1)
                        .filter_map(|i| {
                            let dt = (crank.t_ns[i + 1] - crank.t_ns[i - 1]) as f64 * 1e-9;
                            (dt > 0.0).then(|| {
                                let w = (crank.theta[i + 1] - crank.theta[i - 1]) / dt;
                                (crank.theta[i] - b.theta_tdc, w * 60.0 / TAU * gear)
                            })
                        })
                        .collect()
                }
            };
            let (m, s, mn, mx, h) = speed_stats(&sp);
            let worst_mismatch = match (b.mismatch_deg, b.mismatch_end_deg) {
                (Some(a), Some(e)) => Some(if a.abs() >= e.abs() { a } else { e }),
                (a, e) => a.or(e),
            };
            let usable = worst_mismatch.is_none_or(|d| d.abs() <= tol);
            let cycle = Cycle {
                index: b.index,
                t_start_ns: b.t0,
                t_end_ns: b.t1,
                duration_s: dur,
                crank_rpm: 60.0 / dur,
                motor_rpm_mean: m,
                motor_rpm_std: s,
                motor_rpm_min: mn,
                motor_rpm_max: mx,
                ripple_rms: s / m,
                ripple_half_p2p: (mx - mn) / (2.0 * m),
                ripple_first_harmonic: h,
                mark_mismatch_deg: worst_mismatch,
                usable,
                stroke_mm: Vec::new(),
                force_n: Vec::new(),
                stroke_coverage: 0.0,
                force_coverage: 0.0,
                stroke_max_mm: f64::NAN,
                stroke_min_mm: f64::NAN,
                depth_mm: f64::NAN,
                peak_force_n: f64::NAN,
                stroke_err_tdc_mm: f64::NAN,
                stroke_err_bdc_mm: f64::NAN,
                stroke_dev_rms_mm: f64::NAN,
                stroke_dev_max_mm: f64::NAN,
            };
            (gd, gf, cycle)
        })
        .collect();
    let mut raw_disp: Vec<Vec<f64>> = Vec::with_capacity(per_cycle.len());
    let mut raw_force: Vec<Vec<f64>> = Vec::with_capacity(per_cycle.len());
    for (gd, gf, c) in per_cycle {
        raw_disp.push(gd);
        raw_force.push(gf);
        set.cycles.push(c);
    }
    let mismatched: Vec<(u64, f64, i64)> = set
        .cycles
        .iter()
        .filter(|c| !c.usable)
        .filter_map(|c| c.mark_mismatch_deg.map(|d| (c.index, d, c.t_start_ns)))
        .collect();
    if !mismatched.is_empty() {
        let worst = mismatched.iter().map(|m| m.1.abs()).fold(0.0, f64::max);
        let (first_idx, _, t) = mismatched[0];
        findings.push(Finding::new(
            Severity::Warning,
            FindingCode::AngleMismatch,
            &file,
            Some(&label_angle),
            Some(Place::time(t)),
            format!(
                "the crank angle at the cycle marks differs from top dead centre by more than {tol}° in {} cycle(s) (worst {worst:.1}°), first in cycle {first_idx} at {}: spindle clock jump or encoder slip; those cycles are left out of the ensemble statistics",
                mismatched.len(),
                fmt_time(t, t_start)
            ),
        ));
    }

    // --- laser zero mark ---
    if let Some(d) = disp {
        let label = format!("{} (displacement)", d.topic);
        let per_cycle: Vec<f64> = raw_disp
            .iter()
            .zip(&set.cycles)
            .filter(|(_, c)| c.usable)
            .filter_map(|(g, _)| {
                let v: Vec<f64> = g
                    .iter()
                    .zip(&ideal)
                    .zip(&off_part)
                    .filter(|((x, _), o)| x.is_finite() && **o)
                    .map(|((x, s), _)| s - x)
                    .collect();
                (v.len() > n / 10).then(|| v.iter().sum::<f64>() / v.len() as f64)
            })
            .collect();
        let (m, s) = mean_std(&per_cycle);
        let mut lz = OffsetEstimate {
            name: "laser zero mark".into(),
            unit: "mm".into(),
            applied: 0.0,
            source: ValueSource::Unavailable,
            metadata: log.meta.laser_zero_mm,
            estimate: m.is_finite().then_some(m),
            sigma: (per_cycle.len() > 1).then(|| s / (per_cycle.len() as f64).sqrt()),
            systematic: log.meta.clearance_mm,
            note: String::new(),
        };
        let est_text = match (lz.estimate, lz.sigma) {
            (Some(e), Some(s)) => format!(
                "{e:.4} mm ± {s:.4} mm (mean of s_ideal − displacement off the part over {} cycles; with a clearance of {} the journal's mean position biases it by up to that much)",
                per_cycle.len(),
                log.meta
                    .clearance_mm
                    .map_or("c".to_string(), |c| format!("{c} mm"))
            ),
            _ => "not estimable".into(),
        };
        if let Some(v) = opts.laser_zero_mm {
            lz.applied = v;
            lz.source = ValueSource::Override;
            lz.note = format!("session override; estimate {est_text}");
        } else if let Some(v) = log.meta.laser_zero_mm {
            lz.applied = v;
            lz.source = ValueSource::Metadata;
            lz.note = format!("metadata laser_zero_mm; estimate {est_text}");
            if let (Some(e), Some(s)) = (lz.estimate, lz.sigma) {
                let allow = 3.0 * s + log.meta.clearance_mm.unwrap_or(0.0);
                if (e - v).abs() > allow {
                    findings.push(Finding::new(
                        Severity::Warning,
                        FindingCode::OffsetEstimated,
                        &file,
                        Some(&label),
                        None,
                        format!("metadata laser_zero_mm = {} mm disagrees with the estimate {est_text}; the metadata value is used", crate::fmt::plain(v)),
                    ));
                }
            }
        } else if let Some(e) = lz.estimate {
            lz.applied = e;
            lz.source = ValueSource::Estimated;
            lz.note = format!("no laser_zero_mm in the metadata: estimate {est_text} applied");
            findings.push(Finding::new(
                Severity::Info,
                FindingCode::OffsetEstimated,
                &file,
                Some(&label),
                None,
                format!("laser zero mark (stroke at which the laser reads 0) estimated at {est_text}; applied since the metadata has no laser_zero_mm"),
            ));
        }
        set.offsets.laser_zero_mm = lz;
    }

    // --- force tare ---
    if let Some(f) = force {
        let label = format!("{} (force)", f.topic);
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        let t_ref = set.cycles.first().map(|c| c.t_start_ns).unwrap_or(0);
        for (g, c) in raw_force.iter().zip(&set.cycles) {
            if !c.usable {
                continue;
            }
            let v: Vec<f64> = g
                .iter()
                .zip(&off_part)
                .filter(|(x, o)| x.is_finite() && **o)
                .map(|(x, _)| *x)
                .collect();
            if v.len() > n / 10 {
                xs.push(((c.t_start_ns + c.t_end_ns) / 2 - t_ref) as f64 * 1e-9);
                ys.push(v.iter().sum::<f64>() / v.len() as f64);
            }
        }
        let (m, s) = mean_std(&ys);
        let fit = line_fit(&xs, &ys);
        let mut ft = OffsetEstimate {
            name: "force tare".into(),
            unit: "N".into(),
            applied: 0.0,
            source: ValueSource::Unavailable,
            metadata: log.meta.force_tare_n,
            estimate: m.is_finite().then_some(m),
            sigma: (ys.len() > 1).then(|| s / (ys.len() as f64).sqrt()),
            systematic: None,
            note: String::new(),
        };
        if let Some(lf) = fit {
            let x = |t: Option<i64>| t.map(|t| (t - t_ref) as f64 * 1e-9);
            set.offsets.force_tare_start_n = x(log.log_start_ns).map(|x| lf.at(x));
            set.offsets.force_tare_end_n = x(log.log_end_ns).map(|x| lf.at(x));
            set.offsets.force_tare_start_sigma_n = x(log.log_start_ns).map(|x| lf.sigma_at(x));
            set.offsets.force_tare_end_sigma_n = x(log.log_end_ns).map(|x| lf.sigma_at(x));
            set.offsets.force_tare_drift_n_per_s = Some(lf.b);
            set.offsets.force_tare_drift_sigma = Some(lf.sigma_b());
        }
        let est_text = match (ft.estimate, ft.sigma) {
            (Some(e), Some(s)) => format!(
                "{e:.4} N ± {s:.4} N (off-part mean over {} cycles; {:.4} N at the log start, {:.4} N at its end, drift {:.4} N/s)",
                ys.len(),
                set.offsets.force_tare_start_n.unwrap_or(e),
                set.offsets.force_tare_end_n.unwrap_or(e),
                set.offsets.force_tare_drift_n_per_s.unwrap_or(0.0)
            ),
            _ => "not estimable".into(),
        };
        let mut tare_line: Option<(f64, f64)> = None;
        if let Some(v) = opts.force_tare_n {
            ft.applied = v;
            ft.source = ValueSource::Override;
            ft.note = format!("session override (constant); estimate {est_text}");
        } else if let Some(v) = log.meta.force_tare_n {
            ft.applied = v;
            ft.source = ValueSource::Metadata;
            ft.note = format!("metadata force_tare_n (constant); estimate {est_text}");
            if let (Some(e), Some(s)) = (ft.estimate, ft.sigma) {
                if (e - v).abs() > (3.0 * s).max(0.02) {
                    findings.push(Finding::new(
                        Severity::Warning,
                        FindingCode::OffsetEstimated,
                        &file,
                        Some(&label),
                        None,
                        format!("metadata force_tare_n = {} N disagrees with the off-part reading {est_text}; the metadata value is used", crate::fmt::plain(v)),
                    ));
                }
            }
        } else if let Some(e) = ft.estimate {
            ft.applied = e;
            ft.source = ValueSource::Estimated;
            tare_line = fit.map(|lf| (lf.a, lf.b));
            ft.note = format!(
                "no force_tare_n in the metadata: the fitted tare line is subtracted cycle by cycle; estimate {est_text}"
            );
            findings.push(Finding::new(
                Severity::Info,
                FindingCode::OffsetEstimated,
                &file,
                Some(&label),
                None,
                format!("force tare estimated at {est_text}; subtracted (linear in time) since the metadata has no force_tare_n"),
            ));
        }
        // Apply the tare to the grids.
        for (g, c) in raw_force.iter_mut().zip(&set.cycles) {
            let tare = match tare_line {
                Some((a, b)) => a + b * (((c.t_start_ns + c.t_end_ns) / 2 - t_ref) as f64 * 1e-9),
                None => ft.applied,
            };
            for v in g.iter_mut() {
                *v -= tare;
            }
        }
        set.offsets.force_tare_n = ft;
    }

    // --- per-cycle figures ---
    let z = set.offsets.laser_zero_mm.applied;
    let bdc = n / 2;
    for (i, c) in set.cycles.iter_mut().enumerate() {
        if disp.is_some() {
            // In place: the raw grid becomes the stroke grid (no second copy
            // of every cycle's grid at the peak).
            let mut g = std::mem::take(&mut raw_disp[i]);
            for d in g.iter_mut() {
                *d += z;
            }
            let finite: Vec<(usize, f64)> = g
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .collect();
            c.stroke_coverage = finite.len() as f64 / n as f64;
            if !finite.is_empty() {
                c.stroke_max_mm = finite.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
                c.stroke_min_mm = finite.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
                c.depth_mm = c.stroke_max_mm - standoff_mm;
                let dev: Vec<f64> = finite.iter().map(|(j, v)| v - ideal[*j]).collect();
                c.stroke_dev_rms_mm =
                    (dev.iter().map(|d| d * d).sum::<f64>() / dev.len() as f64).sqrt();
                c.stroke_dev_max_mm = dev.iter().map(|d| d.abs()).fold(0.0, f64::max);
            }
            c.stroke_err_tdc_mm = g[0] - ideal[0];
            c.stroke_err_bdc_mm = g[bdc] - ideal[bdc];
            c.stroke_mm = g;
        }
        if force.is_some() {
            let g = std::mem::take(&mut raw_force[i]);
            let finite: Vec<f64> = g.iter().copied().filter(|v| v.is_finite()).collect();
            c.force_coverage = finite.len() as f64 / n as f64;
            c.peak_force_n = finite.iter().copied().fold(f64::NAN, f64::max);
            c.force_n = g;
        }
    }

    // --- run-level speed and bands ---
    let usable: Vec<&Cycle> = set.cycles.iter().filter(|c| c.usable).collect();
    if !usable.is_empty() {
        let means: Vec<f64> = usable
            .iter()
            .map(|c| c.motor_rpm_mean)
            .filter(|v| v.is_finite())
            .collect();
        let (m, _) = mean_std(&means);
        set.crank.motor_rpm_mean = m;
        set.crank.crank_rpm_mean =
            usable.iter().map(|c| c.crank_rpm).sum::<f64>() / usable.len() as f64;
        set.crank.motor_rpm_cycle_min = means.iter().copied().fold(f64::INFINITY, f64::min);
        set.crank.motor_rpm_cycle_max = means.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        set.crank.speed_spread_rel =
            (set.crank.motor_rpm_cycle_max - set.crank.motor_rpm_cycle_min) / m;
        let expect = set.crank.crank_rpm_mean * gear;
        if m.is_finite() && (m - expect).abs() > 0.02 * expect {
            findings.push(Finding::new(
                Severity::Warning,
                FindingCode::Cycle,
                &file,
                speed.map(|s| s.topic.as_str()),
                None,
                format!(
                    "motor speed {m:.1} rpm does not match the crank speed {:.1} rpm × gear ratio {gear} = {expect:.1} rpm: check gear_ratio",
                    set.crank.crank_rpm_mean
                ),
            ));
        }
        set.stroke_band = Band::of(
            usable
                .iter()
                .map(|c| c.stroke_mm.as_slice())
                .filter(|r| !r.is_empty()),
            n,
        );
        set.force_band = Band::of(
            usable
                .iter()
                .map(|c| c.force_n.as_slice())
                .filter(|r| !r.is_empty()),
            n,
        );
    }
    let nc = set.cycles.len();
    findings.push(Finding::new(
        Severity::Info,
        FindingCode::Cycle,
        &file,
        None,
        None,
        format!(
            "{nc} complete cycle(s) ({} usable) delimited by {}; crank {:.1} rpm, motor {:.1} rpm (cycle means {:.1}–{:.1})",
            usable.len(),
            match set.source {
                CycleSource::Marks => "the /rig/cycle marks",
                CycleSource::Angle => "the crank angle (TDC crossings)",
                CycleSource::None => "nothing",
            },
            set.crank.crank_rpm_mean,
            set.crank.motor_rpm_mean,
            set.crank.motor_rpm_cycle_min,
            set.crank.motor_rpm_cycle_max
        ),
    ));
    set.findings = findings;
    set
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signal(kind: SignalKind, t: Vec<i64>, v: Vec<f64>) -> Signal {
        Signal {
            kind,
            topic: "/t".into(),
            field: "f".into(),
            unit: kind.unit().into(),
            t_ns: t,
            values: v,
        }
    }

    #[test]
    fn unwrap_wrapped_and_unwrapped_angles() {
        // 20 Hz crank sampled at 1 kHz, wrapped to [0, 2π), starting at 1 rad.
        let t: Vec<i64> = (0..500).map(|i| i * 1_000_000).collect();
        let truth: Vec<f64> = t
            .iter()
            .map(|&x| 1.0 + TAU * 20.0 * x as f64 * 1e-9)
            .collect();
        let wrapped: Vec<f64> = truth.iter().map(|a| a.rem_euclid(TAU)).collect();
        let (c, w) = Crank::unwrap(&signal(SignalKind::Angle, t.clone(), wrapped)).unwrap();
        assert!(w);
        for (a, b) in c.theta.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-9);
        }
        let (c2, w2) = Crank::unwrap(&signal(SignalKind::Angle, t.clone(), truth.clone())).unwrap();
        assert!(!w2);
        assert!((c2.omega - TAU * 20.0).abs() < 1e-6);
        // TDC crossings at θ = π + 2πn: first at t = (π − 1)/(40π) s.
        let x = c.crossings(PI);
        let t0 = (PI - 1.0) / (TAU * 20.0);
        assert!(((x[0].0 as f64 * 1e-9) - t0).abs() < 1e-6);
        assert_eq!(x.len(), 10);
        assert_eq!(x[1].1 - x[0].1, 1);
    }

    #[test]
    fn hinted_lookup_matches_binary_search() {
        let t: Vec<i64> = (0..1000).map(|i| i * 1000 + (i % 7) * 13).collect();
        let th: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let c = Crank {
            t_ns: t,
            theta: th,
            dt_ns: 1000,
            omega: 10.0,
        };
        let mut h = 0;
        for q in [
            -5i64, 0, 1, 500, 999, 1000, 1500, 70_000, 69_000, 999_000, 999_100, 2_000_000,
        ] {
            assert_eq!(
                c.at_from(q, &mut h),
                {
                    let i = c.t_ns.partition_point(|&x| x < q);
                    if i < c.t_ns.len() && c.t_ns[i] == q {
                        Some(c.theta[i])
                    } else if i == 0 || i >= c.t_ns.len() {
                        None
                    } else {
                        let w = (q - c.t_ns[i - 1]) as f64 / (c.t_ns[i] - c.t_ns[i - 1]) as f64;
                        Some(c.theta[i - 1] + w * (c.theta[i] - c.theta[i - 1]))
                    }
                },
                "{q}"
            );
        }
    }

    #[test]
    fn grid_interpolation_and_holes() {
        let pts: Vec<(f64, f64)> = (0..=100)
            .map(|i| (i as f64 * TAU / 100.0, i as f64))
            .collect();
        let g = to_grid(&pts, 200, 0.1);
        assert!((g[1] - 0.5).abs() < 1e-9);
        assert!((g[199] - 99.5).abs() < 1e-9);
        let holey: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| !(1.0..2.0).contains(&p.0))
            .collect();
        let g2 = to_grid(&holey, 200, 0.1);
        assert!(g2[40].is_nan());
        assert!(g2[10].is_finite());
    }

    #[test]
    fn band_statistics_skip_nan() {
        let rows = [vec![1.0, f64::NAN], vec![3.0, 2.0]];
        let b = Band::of(rows.iter().map(|r| r.as_slice()), 2);
        assert_eq!(b.mean, vec![2.0, 2.0]);
        assert_eq!(b.count, vec![2, 1]);
        assert!((b.std[0] - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!((b.min[0], b.max[0]), (1.0, 3.0));
    }

    #[test]
    fn first_harmonic_ripple() {
        let s: Vec<(f64, f64)> = (0..400)
            .map(|i| {
                let phi = i as f64 * TAU / 400.0;
                (phi, 1200.0 * (1.0 + 0.005 * (phi + 0.7).cos()))
            })
            .collect();
        let (m, _, _, _, h) = speed_stats(&s);
        assert!((m - 1200.0).abs() < 1e-9);
        assert!((h - 0.005).abs() < 1e-9);
    }

    #[test]
    fn encoder_lattice_detection() {
        let q = TAU / 4096.0;
        let v: Vec<f64> = (0..3000)
            .map(|i| ((i * 82 + i / 7) % 4096) as f64 * q)
            .collect();
        assert_eq!(detect_encoder_counts(&v), Some(4096));
        // Sampling in step with the crank: the same 300 counts every turn, 13 or 14 apart.
        let s: Vec<f64> = (0..3000)
            .map(|i| (((i % 300) * 4096 / 300) as f64) * q)
            .collect();
        assert_eq!(detect_encoder_counts(&s), Some(4096));
        let w: Vec<f64> = (0..3000)
            .map(|i| (i as f64 * 0.1234567).rem_euclid(TAU))
            .collect();
        assert_eq!(detect_encoder_counts(&w), None);
    }

    #[test]
    fn phase_fit_recovers_a_known_offset() {
        let g = Geometry::of(&Params::paper());
        let th: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
        let d: Vec<f64> = th
            .iter()
            .map(|t| g.stroke_at(t + 0.3) * 1e3 - 10.0)
            .collect();
        let phi = fit_phase(&g, &th, &d, None).unwrap();
        assert!((phi - 0.3).abs() < 1e-6, "{phi}");
    }
}
