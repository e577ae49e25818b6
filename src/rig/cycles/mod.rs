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

mod angle_offset;
mod bounds;
mod crank;
mod fit;
mod offsets;
mod types;

use angle_offset::angle_offset;
use bounds::cycle_bounds;
pub use crank::*;
use fit::*;
use offsets::{OffsetContext, force_tare, laser_zero};
pub use types::*;

use super::channel_map::SignalKind;
use super::load::RigLog;
use super::report::{Finding, FindingCode, Place, Severity, fmt_time};
use super::signals::Signal;
use crate::model::Params;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

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
    // What the crank angle's offsets and quantisation are said with.
    let angle_finding = |severity, text: String| {
        Finding::new(
            severity,
            FindingCode::OffsetEstimated,
            &file,
            Some(&label_angle),
            None,
            text,
        )
    };
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
        findings.push(angle_finding(
            Severity::Info,
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
    let quantum = set.crank.encoder_quantum_rad();
    let ao = angle_offset(
        &crank,
        cyc_sig,
        log,
        opts,
        quantum,
        angle_finding,
        &mut findings,
    );
    for th in crank.theta.iter_mut() {
        *th += ao.applied;
    }
    set.offsets.angle_offset_rad = ao;
    set.crank.revolutions = (crank.theta.last().copied().unwrap_or(0.0) - crank.theta[0]) / TAU;

    // --- cycle boundaries ---
    let (source, bounds) = cycle_bounds(&crank, tdc, cyc_sig, &file, t_start, &mut findings);
    set.source = source;

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

    let ctx = OffsetContext {
        ideal: &ideal,
        off_part: &off_part,
        n,
        log,
        opts,
        file: &file,
    };
    if let Some(d) = disp {
        laser_zero(d, &raw_disp, &mut set, &ctx, &mut findings);
    }
    if let Some(f) = force {
        force_tare(f, &mut raw_force, &mut set, &ctx, &mut findings);
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
mod tests;
