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
mod figures;
mod fit;
mod offsets;
mod resample;
mod types;

use angle_offset::angle_offset;
use bounds::cycle_bounds;
pub use crank::*;
use figures::{cycle_figures, run_figures};
use offsets::{OffsetContext, force_tare, laser_zero};
use resample::{Channels, mismatch_finding, resample};
pub use types::*;

use super::channel_map::SignalKind;
use super::load::RigLog;
use super::report::{Finding, FindingCode, Severity};
use super::signals::Signal;
use crate::model::Params;
use std::f64::consts::{PI, TAU};

/// Splits a loaded log into cycles and resamples them (see the module
/// docs). The stages, in order: the empty set with the grid and the ideal
/// stroke ([`start`]), the crank angle unwrapped ([`unwrap_crank`]), its offset ([`angle_offset`]), where cycles begin and end
/// ([`cycle_bounds`]), each cycle resampled ([`resample`]), the sensor
/// zeros ([`laser_zero`], [`force_tare`]), the per-cycle and run-level
/// figures ([`cycle_figures`], [`run_figures`]).
pub fn analyse(log: &RigLog, opts: &CycleOptions) -> CycleSet {
    let file = log.file.clone();
    let t_start = log.log_start_ns;
    let mut findings: Vec<Finding> = Vec::new();
    let mut set = start(log, opts);
    let (n, tdc, standoff_mm) = (
        set.points_per_rev,
        set.geometry.tdc_angle(),
        set.standoff_mm,
    );
    let gear = set.crank.gear_ratio;
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
    let Some(mut crank) = unwrap_crank(angle, &mut set, &angle_finding, &mut findings) else {
        return set;
    };
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
    let ch = Channels {
        disp: log
            .signals
            .get(SignalKind::Displacement)
            .filter(|s| s.len() > 1),
        force: log.signals.get(SignalKind::Force).filter(|s| s.len() > 1),
        speed: log.signals.get(SignalKind::Speed).filter(|s| s.len() > 1),
    };
    set.crank.speed_source = if ch.speed.is_some() {
        "channel"
    } else {
        "angle"
    }
    .into();
    let tol = opts.mark_tolerance_deg;
    let mut raw = resample(&bounds, &crank, ch, n, gear, tol);
    set.cycles = std::mem::take(&mut raw.cycles);
    findings.extend(mismatch_finding(
        &set.cycles,
        tol,
        &file,
        &label_angle,
        t_start,
    ));

    // --- sensor zeros ---
    let ideal = set.ideal_stroke_mm.clone();
    let off_part: Vec<bool> = ideal.iter().map(|&s| s < standoff_mm - 1.0).collect();
    let ctx = OffsetContext {
        ideal: &ideal,
        off_part: &off_part,
        n,
        log,
        opts,
        file: &file,
    };
    if let Some(d) = ch.disp {
        laser_zero(d, &raw.disp, &mut set, &ctx, &mut findings);
    }
    if let Some(f) = ch.force {
        force_tare(f, &mut raw.force, &mut set, &ctx, &mut findings);
    }

    // --- per-cycle and run-level figures ---
    cycle_figures(
        &mut set.cycles,
        ch.disp.map(|_| raw.disp.as_mut_slice()),
        ch.force.map(|_| raw.force.as_mut_slice()),
        set.offsets.laser_zero_mm.applied,
        &ideal,
        standoff_mm,
    );
    run_figures(
        &mut set,
        gear,
        ch.speed.map(|s| s.topic.as_str()),
        &mut findings,
    );
    set.findings = findings;
    set
}

/// The crank angle unwrapped ([`Crank::unwrap`]) with an encoder's half
/// count added (said in `findings`); None when it cannot give cycles (too
/// few samples, or it runs backwards: a warning of `set`).
fn unwrap_crank(
    angle: &Signal,
    set: &mut CycleSet,
    angle_finding: &dyn Fn(Severity, String) -> Finding,
    findings: &mut Vec<Finding>,
) -> Option<Crank> {
    let (mut crank, wrapped) = Crank::unwrap(angle)?;
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
            &set.file,
            Some(&format!("{} (angle)", angle.topic)),
            None,
            format!(
                "the crank angle decreases (median speed {:.1} rad/s): the crank turns backwards or the encoder counts down; cycles cannot be found",
                crank.omega
            ),
        ));
        return None;
    }
    Some(crank)
}

/// The cycle set before any signal is read: the crank-angle grid, the
/// ideal stroke on it, the standoff and gear ratio (override, metadata or
/// default, with their source), every sensor offset unavailable.
fn start(log: &RigLog, opts: &CycleOptions) -> CycleSet {
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
    CycleSet {
        file: log.file.clone(),
        source: CycleSource::None,
        points_per_rev: n,
        grid_deg,
        ideal_stroke_mm: ideal,
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
    }
}

#[cfg(test)]
mod tests;
