//! Per-cycle resampling: each cycle's displacement and force placed by
//! crank angle φ = θ2 − θ_TDC and interpolated onto the grid (a grid point
//! between two samples further apart than 2.5 nominal sample intervals is
//! NaN), its motor speed over the cycle (from the speed channel, else the
//! crank angle's derivative × the gear ratio), and whether its marks agree
//! with top dead centre. The grids are still raw here: the sensor zeros
//! ([`super::offsets`]) and the figures ([`super::figures`]) come after.

use super::bounds::Bound;
use super::crank::Crank;
use super::fit::{median_dt, placed, speed_stats, to_grid};
use super::types::Cycle;
use crate::rig::report::{Finding, FindingCode, Place, Severity, fmt_time};
use crate::rig::signals::Signal;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// The channels a cycle is resampled from (each absent, or with ≥ 2 samples).
#[derive(Clone, Copy)]
pub(super) struct Channels<'a> {
    pub disp: Option<&'a Signal>,
    pub force: Option<&'a Signal>,
    pub speed: Option<&'a Signal>,
}

/// The cycles with their speed figures and their raw grids, in cycle order
/// (a grid is empty when its channel is absent).
pub(super) struct Resampled {
    pub cycles: Vec<Cycle>,
    pub disp: Vec<Vec<f64>>,
    pub force: Vec<Vec<f64>>,
}

/// Resamples every cycle of `bounds` on a grid of `n` points per
/// revolution (in parallel: cycles are independent). A cycle whose marks
/// differ from TDC by more than `tol_deg` is not usable.
pub(super) fn resample(
    bounds: &[Bound],
    crank: &Crank,
    ch: Channels<'_>,
    n: usize,
    gear: f64,
    tol_deg: f64,
) -> Resampled {
    let disp_dt = ch.disp.map(median_dt).unwrap_or(1);
    let force_dt = ch.force.map(median_dt).unwrap_or(1);
    let margin = 5f64.to_radians();
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
                            placed(s, crank, b.t0, b.t1, b.theta_tdc, margin)
                                .into_iter()
                                .map(|(p, _, v)| (p, v))
                                .collect();
                        to_grid(&pts, n, 2.5 * omega * dt as f64 * 1e-9)
                    }
                }
            };
            let gd = grid_of(ch.disp, disp_dt);
            let gf = grid_of(ch.force, force_dt);
            let sp = speed_over(b, crank, ch.speed, gear);
            (gd, gf, cycle_of(b, dur, &sp, tol_deg))
        })
        .collect();
    let mut out = Resampled {
        cycles: Vec::with_capacity(per_cycle.len()),
        disp: Vec::with_capacity(per_cycle.len()),
        force: Vec::with_capacity(per_cycle.len()),
    };
    for (gd, gf, c) in per_cycle {
        out.disp.push(gd);
        out.force.push(gf);
        out.cycles.push(c);
    }
    out
}

/// Motor speed over a cycle: (crank angle from TDC, rpm) samples.
fn speed_over(b: &Bound, crank: &Crank, speed: Option<&Signal>, gear: f64) -> Vec<(f64, f64)> {
    match speed {
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
    }
}

/// A cycle with its timing and speed figures; the stroke and force figures
/// are NaN until [`super::figures::cycle_figures`] fills them in.
fn cycle_of(b: &Bound, dur: f64, speed: &[(f64, f64)], tol_deg: f64) -> Cycle {
    let (m, s, mn, mx, h) = speed_stats(speed);
    let worst_mismatch = match (b.mismatch_deg, b.mismatch_end_deg) {
        (Some(a), Some(e)) => Some(if a.abs() >= e.abs() { a } else { e }),
        (a, e) => a.or(e),
    };
    let usable = worst_mismatch.is_none_or(|d| d.abs() <= tol_deg);
    Cycle {
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
    }
}

/// The warning for cycles whose marks disagree with the crank angle by
/// more than `tol_deg` (None when there are none).
pub(super) fn mismatch_finding(
    cycles: &[Cycle],
    tol_deg: f64,
    file: &str,
    label_angle: &str,
    t_start: Option<i64>,
) -> Option<Finding> {
    let mismatched: Vec<(u64, f64, i64)> = cycles
        .iter()
        .filter(|c| !c.usable)
        .filter_map(|c| c.mark_mismatch_deg.map(|d| (c.index, d, c.t_start_ns)))
        .collect();
    let &(first_idx, _, t) = mismatched.first()?;
    let worst = mismatched.iter().map(|m| m.1.abs()).fold(0.0, f64::max);
    Some(Finding::new(
        Severity::Warning,
        FindingCode::AngleMismatch,
        file,
        Some(label_angle),
        Some(Place::time(t)),
        format!(
            "the crank angle at the cycle marks differs from top dead centre by more than {tol_deg}° in {} cycle(s) (worst {worst:.1}°), first in cycle {first_idx} at {}: spindle clock jump or encoder slip; those cycles are left out of the ensemble statistics",
            mismatched.len(),
            fmt_time(t, t_start)
        ),
    ))
}
