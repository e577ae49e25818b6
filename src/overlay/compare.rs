//! Measured cycles against the predicted ensemble.
//!
//! What the comparison reports, and why (the motion is chaotic, so a single
//! predicted trajectory cannot match a measured cycle impact for impact):
//! - per crank angle: the measured band (mean, std, min, max over the
//!   measured cycles) beside the predicted band (over simulated
//!   revolutions), and the residual of the mean curves;
//! - per cycle: the residual against the predicted mean curve (RMS, max, at
//!   TDC and BDC, force RMS), the fraction of the cycle inside the predicted
//!   min–max band and inside mean ± 2σ, and the cycle's figures;
//! - per run: the mean-curve residuals, the inclusion fractions over all
//!   cycles, and measured against predicted statistics of every figure (mean,
//!   std, range, and the difference of the means in units of its standard
//!   error).
//!
//! Speed: the model runs at the logged speed. When the cycles' mean speeds
//! spread by more than `speed_threshold` (1 % by default: the inertia terms
//! scale with ω², so 1 % of speed changes them by 2 %, below what the sensors
//! resolve on this head), the cycles are grouped in bins of that relative
//! width and each group is compared with a prediction at its own mean speed.

use super::predict::{
    CycleFigures, FIGURE_NAMES, PredictOptions, Prediction, noise_sigma, predict,
};
use crate::model::kinematics::Geometry;
use crate::model::{ParamError, Params};
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::{Band, CycleSet, OffsetEstimate, ValueSource};
use crate::sim::SimError;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::TAU;

/// How to compare.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayOptions {
    pub predict: PredictOptions,
    /// Relative spread of cycle speeds above which cycles are predicted per speed group.
    pub speed_threshold: f64,
    /// Cycle indices to compare, `start..end` (end exclusive).
    pub cycles: Option<(u64, u64)>,
}

impl Default for OverlayOptions {
    fn default() -> Self {
        OverlayOptions {
            predict: PredictOptions::default(),
            speed_threshold: 0.01,
            cycles: None,
        }
    }
}

/// Errors of the comparison.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    #[error("{file}: {message}")]
    NoData { file: String, message: String },
    #[error(transparent)]
    Params(#[from] ParamError),
    #[error("{file}: the model failed at {motor_rpm:.1} rpm: {source}")]
    Sim {
        file: String,
        motor_rpm: f64,
        #[source]
        source: SimError,
    },
}

/// The model parameters for a log: the given parameter file (or the `paper`
/// preset plus the log's `rig` metadata: clearance, standoff, material,
/// gear ratio), then `--set` overrides. Returns the notes saying what came from where.
pub fn model_params(
    log: &RigLog,
    file: Option<Params>,
    sets: &[String],
) -> Result<(Params, Vec<String>), ParamError> {
    let mut notes = Vec::new();
    let mut p = match file {
        Some(p) => {
            notes.push(format!("model parameters from the parameter file (preset {} + its keys); the log's metadata does not override them", p.preset));
            p
        }
        None => {
            let mut p = Params::paper();
            let mut used = Vec::new();
            for key in ["clearance_mm", "standoff_mm", "material", "gear_ratio"] {
                if let Some(v) = log.meta.raw.get(key) {
                    match p.set_str(key, v) {
                        Ok(()) => used.push(format!("{key} = {v}")),
                        Err(e) => notes.push(format!("metadata {key} = '{v}' not used: {e}")),
                    }
                }
            }
            notes.push(format!(
                "model parameters: preset paper + the log's metadata ({})",
                if used.is_empty() {
                    "nothing usable".to_string()
                } else {
                    used.join(", ")
                }
            ));
            p
        }
    };
    if !sets.is_empty() {
        p.apply_overrides(sets)?;
        notes.push(format!("overrides: {}", sets.join(", ")));
    }
    p.validate()?;
    Ok((p, notes))
}

/// Distribution of a figure.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Stats {
    pub n: usize,
    pub mean: f64,
    pub std: f64,
    pub min: f64,
    pub max: f64,
}

impl Stats {
    pub fn of(v: &[f64]) -> Self {
        let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let n = v.len();
        if n == 0 {
            return Stats {
                n: 0,
                mean: f64::NAN,
                std: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Stats {
            n,
            mean,
            std,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// Measured against predicted statistics of one figure.
#[derive(Debug, Clone, Serialize)]
pub struct FigureComparison {
    pub figure: String,
    pub unit: String,
    pub measured: Stats,
    pub predicted: Stats,
    /// Measured mean − predicted mean.
    pub difference: f64,
    /// The difference in units of its standard error (|z| > 3: the model and the rig disagree).
    pub z: f64,
}

/// One measured cycle against its group's prediction.
#[derive(Debug, Clone, Serialize)]
pub struct CycleResidual {
    pub index: u64,
    pub t_start_ns: i64,
    pub motor_rpm: f64,
    /// Index into [`OverlayReport::groups`].
    pub group: usize,
    pub stroke_rms_err_mm: f64,
    pub stroke_max_err_mm: f64,
    pub stroke_err_tdc_mm: f64,
    pub stroke_err_bdc_mm: f64,
    pub force_rms_err_n: f64,
    /// Fractions of the cycle's grid points inside the predicted min–max band and mean ± 2σ.
    pub stroke_in_band: f64,
    pub stroke_in_2sigma: f64,
    pub force_in_band: f64,
    pub force_in_2sigma: f64,
    pub measured: CycleFigures,
}

/// One speed group.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedGroup {
    pub motor_rpm: f64,
    pub cycles: usize,
    pub prediction: Prediction,
}

/// Whole-run figures.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RunResiduals {
    pub cycles: usize,
    /// Residual of the mean curves (measured mean − predicted mean): RMS and max |·|.
    pub stroke_mean_rms_mm: f64,
    pub stroke_mean_max_mm: f64,
    pub force_mean_rms_n: f64,
    pub force_mean_max_n: f64,
    /// Per-cycle residuals against the predicted mean, RMS over all cycles.
    pub stroke_rms_err_mm: f64,
    pub force_rms_err_n: f64,
    /// Fractions of all measured grid samples inside the predicted bands.
    pub stroke_in_band: f64,
    pub stroke_in_2sigma: f64,
    pub force_in_band: f64,
    pub force_in_2sigma: f64,
}

/// At most this many measured cycles are kept one by one in the report (for
/// charts: evenly spaced over the run); the bands cover every cycle.
pub const MAX_SAMPLE_CYCLES: usize = 12;

/// One measured cycle on the grid, kept for drawing.
#[derive(Debug, Clone, Serialize)]
pub struct SampleCycle {
    pub index: u64,
    /// Stroke (mm, with the laser zero used for the report) and force (N; empty without a force channel).
    pub stroke_mm: Vec<f64>,
    pub force_n: Vec<f64>,
}

/// The overlay of a run.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayReport {
    pub file: String,
    pub params_notes: Vec<String>,
    pub clearance_mm: f64,
    pub standoff_mm: f64,
    pub level: String,
    pub speed_threshold: f64,
    pub groups: Vec<SpeedGroup>,
    pub grid_deg: Vec<f64>,
    pub ideal_stroke_mm: Vec<f64>,
    pub measured_stroke: Band,
    pub measured_force: Band,
    /// Pooled over the groups' revolutions.
    pub predicted_stroke: Band,
    pub predicted_force: Band,
    pub residual_stroke_mm: Vec<f64>,
    pub residual_force_n: Vec<f64>,
    pub run: RunResiduals,
    /// White-noise levels of the displacement (mm) and force (N) sensors.
    pub noise_stroke_mm: f64,
    pub noise_force_n: f64,
    pub cycles: Vec<CycleResidual>,
    pub figures: Vec<FigureComparison>,
    /// The laser zero mark used for the measured stroke (re-estimated against
    /// the predicted mean when the log gives none).
    pub laser_zero: OffsetEstimate,
    /// Up to [`MAX_SAMPLE_CYCLES`] measured cycles, evenly spaced over the run.
    pub sample_cycles: Vec<SampleCycle>,
    pub notes: Vec<String>,
}

fn rms(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        (f.iter().map(|x| x * x).sum::<f64>() / f.len() as f64).sqrt()
    }
}

/// [`rms`] accumulated value by value (the same sum in the same order).
#[derive(Default)]
struct RmsAcc {
    sum: f64,
    n: usize,
}

impl RmsAcc {
    #[inline]
    fn add(&mut self, x: f64) {
        if x.is_finite() {
            self.sum += x * x;
            self.n += 1;
        }
    }

    fn rms(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            (self.sum / self.n as f64).sqrt()
        }
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter()
        .copied()
        .filter(|x| x.is_finite())
        .map(f64::abs)
        .fold(f64::NAN, f64::max)
}

/// Counts of grid samples inside the min–max band widened by ±2σ_noise and
/// inside mean ± 2·√(σ² + σ_noise²) (the prediction seen through a sensor of
/// white noise σ_noise).
fn inside(x: &[f64], b: &Band, noise: f64) -> (usize, usize, usize) {
    let (mut n, mut in_band, mut in_2s) = (0, 0, 0);
    for (j, &v) in x.iter().enumerate() {
        if !v.is_finite() || !b.mean[j].is_finite() {
            continue;
        }
        n += 1;
        if v >= b.min[j] - 2.0 * noise && v <= b.max[j] + 2.0 * noise {
            in_band += 1;
        }
        if (v - b.mean[j]).abs() <= 2.0 * (b.std[j].powi(2) + noise * noise).sqrt() {
            in_2s += 1;
        }
    }
    (n, in_band, in_2s)
}

fn frac(a: usize, n: usize) -> f64 {
    if n == 0 {
        f64::NAN
    } else {
        a as f64 / n as f64
    }
}

/// Groups cycle speeds: one group when their relative spread ≤ threshold,
/// else bins of relative width `threshold`. Returns (group mean speed, member indices).
pub fn speed_groups(speeds: &[f64], threshold: f64) -> Vec<(f64, Vec<usize>)> {
    let fin: Vec<(usize, f64)> = speeds
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, s)| s.is_finite() && *s > 0.0)
        .collect();
    if fin.is_empty() {
        return Vec::new();
    }
    let mean = fin.iter().map(|x| x.1).sum::<f64>() / fin.len() as f64;
    let lo = fin.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
    let hi = fin.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
    if (hi - lo) / mean <= threshold || threshold <= 0.0 {
        return vec![(mean, fin.iter().map(|x| x.0).collect())];
    }
    let mut bins: std::collections::BTreeMap<i64, Vec<usize>> = Default::default();
    for &(i, s) in &fin {
        let k = ((s / lo).ln() / (1.0 + threshold).ln()).floor() as i64;
        bins.entry(k).or_default().push(i);
    }
    bins.into_values()
        .map(|m| {
            (
                m.iter().map(|&i| speeds[i]).sum::<f64>() / m.len() as f64,
                m,
            )
        })
        .collect()
}

/// Compares a log's cycles with the model.
pub fn overlay(
    log: &RigLog,
    cs: &CycleSet,
    params: &Params,
    params_notes: Vec<String>,
    opts: &OverlayOptions,
    progress: &Progress,
) -> Result<OverlayReport, OverlayError> {
    let file = log.file.clone();
    let n = cs.points_per_rev;
    let mut notes = Vec::new();
    let selected: Vec<&crate::rig::Cycle> = cs
        .usable()
        .filter(|c| opts.cycles.is_none_or(|(a, b)| c.index >= a && c.index < b))
        .filter(|c| !c.stroke_mm.is_empty())
        .collect();
    if selected.is_empty() {
        return Err(OverlayError::NoData {
            file,
            message: format!(
                "no usable cycle with a displacement signal{} ({} cycles found)",
                opts.cycles
                    .map_or(String::new(), |(a, b)| format!(" in {a}..{b}")),
                cs.cycles.len()
            ),
        });
    }
    let gear = cs.crank.gear_ratio;
    let motor: Vec<f64> = selected.iter().map(|c| c.crank_rpm * gear).collect();
    let groups_idx = speed_groups(&motor, opts.speed_threshold);
    if groups_idx.len() > 1 {
        notes.push(format!(
            "cycle speeds spread by more than {:.1} %: {} speed groups, each predicted at its mean speed",
            opts.speed_threshold * 100.0,
            groups_idx.len()
        ));
    }
    progress.set_total(groups_idx.len() as u64);
    let mut popts = opts.predict.clone();
    popts.points_per_rev = n;
    let mut groups = Vec::new();
    let mut group_of = vec![0usize; selected.len()];
    for (g, (rpm, members)) in groups_idx.iter().enumerate() {
        let pr = predict(params, *rpm, &popts, progress).map_err(|source| OverlayError::Sim {
            file: file.clone(),
            motor_rpm: *rpm,
            source,
        })?;
        progress.inc(1);
        for &m in members {
            group_of[m] = g;
        }
        groups.push(SpeedGroup {
            motor_rpm: *rpm,
            cycles: members.len(),
            prediction: pr,
        });
    }

    // Laser zero: re-estimated against the predicted mean when the log has none.
    let mut lz = cs.offsets.laser_zero_mm.clone();
    let mut shift = 0.0;
    if lz.source == ValueSource::Estimated {
        let off_part: Vec<bool> = cs
            .ideal_stroke_mm
            .iter()
            .map(|&s| s < params.standoff * 1e3 - 1.0)
            .collect();
        let mut acc = Vec::new();
        for (i, c) in selected.iter().enumerate() {
            let pm = &groups[group_of[i]].prediction.stroke.mean;
            for j in 0..n {
                if off_part[j] && c.stroke_mm[j].is_finite() && pm[j].is_finite() {
                    acc.push(pm[j] - c.stroke_mm[j]);
                }
            }
        }
        if !acc.is_empty() {
            shift = acc.iter().sum::<f64>() / acc.len() as f64;
            let kin = lz.applied;
            lz.applied += shift;
            lz.note = format!(
                "no laser_zero_mm in the metadata: estimated against the predicted mean stroke off the part ({:.4} mm; the kinematic estimate was {kin:.4} mm)",
                lz.applied
            );
            notes.push(format!(
                "laser zero mark estimated against the model's mean stroke: {:.4} mm (the ideal-mechanism estimate {kin:.4} mm is biased by the clearance); set it with --meta laser_zero_mm=… when known",
                lz.applied
            ));
        }
    }
    let stroke_of =
        |c: &crate::rig::Cycle| -> Vec<f64> { c.stroke_mm.iter().map(|s| s + shift).collect() };

    // Sensor noise (white), from the raw samples.
    let noise_s = log
        .signals
        .displacement
        .as_ref()
        .map_or(0.0, |s| noise_sigma(&s.values));
    let noise_f = log
        .signals
        .force
        .as_ref()
        .map_or(0.0, |s| noise_sigma(&s.values));
    notes.push(format!(
        "sensor noise estimated from the raw samples: displacement {:.4} mm, force {:.4} N (added to the predicted bands and figures)",
        noise_s, noise_f
    ));

    // Per-cycle residuals.
    let geom = Geometry::of(params);
    let standoff_mm = params.standoff * 1e3;
    // Cycles are independent: compared in parallel, merged in cycle order
    // (the counts are integers, so the totals do not depend on the order).
    // The residual vectors are not kept: the run's RMS is accumulated in the
    // merge, in cycle order (the same sums as over one concatenated vector,
    // without holding cycles × grid residuals).
    struct PerCycle {
        row: CycleResidual,
        stroke: (usize, usize, usize),
        force: (usize, usize, usize),
    }
    let grid = super::predict::crank_grid(&geom, n);
    let per_cycle: Vec<PerCycle> = selected
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let g = group_of[i];
            let pr = &groups[g].prediction;
            let s = stroke_of(c);
            let r: Vec<f64> = s.iter().zip(&pr.stroke.mean).map(|(a, b)| a - b).collect();
            let rf: Vec<f64> = if c.force_n.is_empty() {
                Vec::new()
            } else {
                c.force_n
                    .iter()
                    .zip(&pr.force.mean)
                    .map(|(a, b)| a - b)
                    .collect()
            };
            let (a, b1, b2) = inside(&s, &pr.stroke, noise_s);
            let (fa, fb1, fb2) = if c.force_n.is_empty() {
                (0, 0, 0)
            } else {
                inside(&c.force_n, &pr.force, noise_f)
            };
            let omega = TAU * c.crank_rpm / 60.0;
            let (ideal_s, ideal_v) = super::predict::ideal_curves_on(&geom, &grid, omega);
            let empty = vec![f64::NAN; n];
            let force = if c.force_n.is_empty() {
                &empty
            } else {
                &c.force_n
            };
            let row = CycleResidual {
                index: c.index,
                t_start_ns: c.t_start_ns,
                motor_rpm: c.crank_rpm * gear,
                group: g,
                stroke_rms_err_mm: rms(&r),
                stroke_max_err_mm: max_abs(&r),
                stroke_err_tdc_mm: r[0],
                stroke_err_bdc_mm: r[n / 2],
                force_rms_err_n: rms(&rf),
                stroke_in_band: frac(b1, a),
                stroke_in_2sigma: frac(b2, a),
                force_in_band: frac(fb1, fa),
                force_in_2sigma: frac(fb2, fa),
                measured: CycleFigures::of(&s, force, &ideal_s, &ideal_v, omega, standoff_mm),
            };
            PerCycle {
                row,
                stroke: (a, b1, b2),
                force: (fa, fb1, fb2),
            }
        })
        .collect();
    let mut rows = Vec::with_capacity(per_cycle.len());
    let (mut ns, mut sb, mut s2) = (0usize, 0usize, 0usize);
    let (mut nf, mut fb, mut f2) = (0usize, 0usize, 0usize);
    let mut all_sr = RmsAcc::default();
    let mut all_fr = RmsAcc::default();
    for (c, pc) in selected.iter().zip(per_cycle) {
        let pr = &groups[pc.row.group].prediction;
        for (a, b) in c.stroke_mm.iter().zip(&pr.stroke.mean) {
            all_sr.add((a + shift) - b);
        }
        for (a, b) in c.force_n.iter().zip(&pr.force.mean) {
            all_fr.add(a - b);
        }
        ns += pc.stroke.0;
        sb += pc.stroke.1;
        s2 += pc.stroke.2;
        nf += pc.force.0;
        fb += pc.force.1;
        f2 += pc.force.2;
        rows.push(pc.row);
    }

    // Bands and mean-curve residuals.
    let measured_stroke =
        Band::of_mapped(selected.iter().map(|c| c.stroke_mm.as_slice()), n, |s| {
            s + shift
        });
    let measured_force = Band::of(
        selected
            .iter()
            .map(|c| c.force_n.as_slice())
            .filter(|f| !f.is_empty()),
        n,
    );
    let predicted_stroke = Band::of(
        groups
            .iter()
            .flat_map(|g| g.prediction.stroke_revs.iter().map(Vec::as_slice)),
        n,
    );
    let predicted_force = Band::of(
        groups
            .iter()
            .flat_map(|g| g.prediction.force_revs.iter().map(Vec::as_slice)),
        n,
    );
    let residual_stroke_mm: Vec<f64> = measured_stroke
        .mean
        .iter()
        .zip(&predicted_stroke.mean)
        .map(|(a, b)| a - b)
        .collect();
    let residual_force_n: Vec<f64> = measured_force
        .mean
        .iter()
        .zip(&predicted_force.mean)
        .map(|(a, b)| a - b)
        .collect();
    let run = RunResiduals {
        cycles: rows.len(),
        stroke_mean_rms_mm: rms(&residual_stroke_mm),
        stroke_mean_max_mm: max_abs(&residual_stroke_mm),
        force_mean_rms_n: rms(&residual_force_n),
        force_mean_max_n: max_abs(&residual_force_n),
        stroke_rms_err_mm: all_sr.rms(),
        force_rms_err_n: all_fr.rms(),
        stroke_in_band: frac(sb, ns),
        stroke_in_2sigma: frac(s2, ns),
        force_in_band: frac(fb, nf),
        force_in_2sigma: frac(f2, nf),
    };

    // Figure statistics: measured cycles against predicted revolutions.
    let pred_figs: Vec<CycleFigures> = groups
        .iter()
        .enumerate()
        .flat_map(|(k, g)| {
            g.prediction
                .figures_with_noise(noise_s, noise_f, 7 + k as u64)
        })
        .collect();
    let figures = FIGURE_NAMES
        .iter()
        .enumerate()
        .filter(|(k, _)| !(log.signals.force.is_none() && *k == 3))
        .map(|(k, (name, unit))| {
            let m = Stats::of(
                &rows
                    .iter()
                    .map(|r| r.measured.values()[k])
                    .collect::<Vec<_>>(),
            );
            let p = Stats::of(&pred_figs.iter().map(|f| f.values()[k]).collect::<Vec<_>>());
            let se = (m.std.powi(2) / m.n.max(1) as f64 + p.std.powi(2) / p.n.max(1) as f64).sqrt();
            let d = m.mean - p.mean;
            FigureComparison {
                figure: name.to_string(),
                unit: unit.to_string(),
                measured: m,
                predicted: p,
                difference: d,
                z: if se > 0.0 { d / se } else { f64::NAN },
            }
        })
        .collect();
    if log.signals.force.is_none() {
        notes.push("no force channel: force residuals are not available".into());
    }
    let k = selected.len();
    let sample_idx: Vec<usize> = if k <= MAX_SAMPLE_CYCLES {
        (0..k).collect()
    } else {
        (0..MAX_SAMPLE_CYCLES)
            .map(|i| i * (k - 1) / (MAX_SAMPLE_CYCLES - 1))
            .collect()
    };
    let sample_cycles = sample_idx
        .iter()
        .map(|&i| SampleCycle {
            index: selected[i].index,
            stroke_mm: stroke_of(selected[i]),
            force_n: selected[i].force_n.clone(),
        })
        .collect();
    Ok(OverlayReport {
        file,
        params_notes,
        clearance_mm: params.clearance * 1e3,
        standoff_mm,
        level: opts.predict.level.name().into(),
        speed_threshold: opts.speed_threshold,
        groups,
        grid_deg: cs.grid_deg.clone(),
        ideal_stroke_mm: cs.ideal_stroke_mm.clone(),
        measured_stroke,
        measured_force,
        predicted_stroke,
        predicted_force,
        residual_stroke_mm,
        residual_force_n,
        run,
        noise_stroke_mm: noise_s,
        noise_force_n: noise_f,
        cycles: rows,
        figures,
        laser_zero: lz,
        sample_cycles,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_grouping() {
        assert_eq!(speed_groups(&[1200.0, 1201.0, 1199.0], 0.01).len(), 1);
        let g = speed_groups(&[1000.0, 1001.0, 1200.0, 1202.0, 1500.0], 0.01);
        assert_eq!(g.len(), 3);
        assert_eq!(g[0].1, vec![0, 1]);
        assert!((g[2].0 - 1500.0).abs() < 1e-9);
        assert!(speed_groups(&[], 0.01).is_empty());
    }

    #[test]
    fn stats_and_inclusion() {
        let s = Stats::of(&[1.0, 2.0, 3.0, f64::NAN]);
        assert_eq!((s.n, s.mean, s.min, s.max), (3, 2.0, 1.0, 3.0));
        let b = Band {
            mean: vec![0.0, 0.0],
            std: vec![1.0, 1.0],
            min: vec![-1.0, -1.0],
            max: vec![1.0, 1.0],
            count: vec![2, 2],
        };
        assert_eq!(inside(&[0.5, 1.5], &b, 0.0), (2, 1, 2));
        // Noise widens both bands: 1.5 is inside [−1.6, 1.6] and within 2·√(1 + 0.09).
        assert_eq!(inside(&[0.5, 1.5], &b, 0.3), (2, 2, 2));
        assert_eq!(inside(&[2.2, -1.7], &b, 0.3), (2, 0, 1));
    }
}
