//! The figures of the cycle analysis, once the sensor zeros are known:
//! per cycle the stroke grid (displacement + laser zero) and its extremes,
//! depth, coverage and deviation from the ideal stroke, the force grid and
//! its peak; over the run the motor and crank speeds, the speed spread, the
//! measured bands of the usable cycles, and the summary finding.

use super::fit::mean_std;
use super::types::{Band, Cycle, CycleSet, CycleSource};
use crate::rig::report::{Finding, FindingCode, Severity};

/// Fills in each cycle's stroke and force grids and figures from the raw
/// grids (taken, not copied: the raw grid becomes the cycle's). `z` is the
/// laser zero applied; `ideal` the ideal stroke on the grid (mm).
pub(super) fn cycle_figures(
    cycles: &mut [Cycle],
    raw_disp: Option<&mut [Vec<f64>]>,
    raw_force: Option<&mut [Vec<f64>]>,
    z: f64,
    ideal: &[f64],
    standoff_mm: f64,
) {
    let n = ideal.len();
    let bdc = n / 2;
    if let Some(raw) = raw_disp {
        for (c, raw) in cycles.iter_mut().zip(raw.iter_mut()) {
            let mut g = std::mem::take(raw);
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
    }
    if let Some(raw) = raw_force {
        for (c, raw) in cycles.iter_mut().zip(raw.iter_mut()) {
            let g = std::mem::take(raw);
            let finite: Vec<f64> = g.iter().copied().filter(|v| v.is_finite()).collect();
            c.force_coverage = finite.len() as f64 / n as f64;
            c.peak_force_n = finite.iter().copied().fold(f64::NAN, f64::max);
            c.force_n = g;
        }
    }
}

/// The run's speeds and measured bands over the usable cycles (a warning
/// when the motor speed does not match the crank speed × `gear`, said on
/// `speed_topic`), and the summary finding.
pub(super) fn run_figures(
    set: &mut CycleSet,
    gear: f64,
    speed_topic: Option<&str>,
    findings: &mut Vec<Finding>,
) {
    let n = set.points_per_rev;
    let file = set.file.as_str();
    let usable: Vec<&Cycle> = set.cycles.iter().filter(|c| c.usable).collect();
    if !usable.is_empty() {
        let means: Vec<f64> = usable
            .iter()
            .map(|c| c.motor_rpm_mean)
            .filter(|v| v.is_finite())
            .collect();
        let (m, _) = mean_std(&means);
        let crank = &mut set.crank;
        crank.motor_rpm_mean = m;
        crank.crank_rpm_mean =
            usable.iter().map(|c| c.crank_rpm).sum::<f64>() / usable.len() as f64;
        crank.motor_rpm_cycle_min = means.iter().copied().fold(f64::INFINITY, f64::min);
        crank.motor_rpm_cycle_max = means.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        crank.speed_spread_rel = (crank.motor_rpm_cycle_max - crank.motor_rpm_cycle_min) / m;
        let expect = crank.crank_rpm_mean * gear;
        if m.is_finite() && (m - expect).abs() > 0.02 * expect {
            findings.push(Finding::new(
                Severity::Warning,
                FindingCode::Cycle,
                file,
                speed_topic,
                None,
                format!(
                    "motor speed {m:.1} rpm does not match the crank speed {:.1} rpm × gear ratio {gear} = {expect:.1} rpm: check gear_ratio",
                    crank.crank_rpm_mean
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
    findings.push(Finding::new(
        Severity::Info,
        FindingCode::Cycle,
        file,
        None,
        None,
        format!(
            "{} complete cycle(s) ({} usable) delimited by {}; crank {:.1} rpm, motor {:.1} rpm (cycle means {:.1}–{:.1})",
            set.cycles.len(),
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
}
