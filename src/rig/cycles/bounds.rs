//! Where each cycle begins and ends: at the `/rig/cycle` marks when the rig
//! writes them (a gap in the marks filled in from the crank angle when the
//! revolutions match, else reported and skipped), otherwise at the crank
//! angle's crossings of top dead centre.

use super::crank::{Crank, wrap_pi};
use super::types::CycleSource;
use crate::rig::report::{Finding, FindingCode, Place, Severity, fmt_time};
use crate::rig::signals::Signal;
use std::f64::consts::TAU;

/// One cycle's extent.
pub(super) struct Bound {
    pub(super) index: u64,
    pub(super) t0: i64,
    pub(super) t1: i64,
    pub(super) theta_tdc: f64,
    /// Crank angle minus TDC at the cycle's start and end marks (degrees).
    pub(super) mismatch_deg: Option<f64>,
    pub(super) mismatch_end_deg: Option<f64>,
}

/// The cycles' extents and where they came from: the marks of
/// `cycle_marks` if given, else the crossings of `tdc` (rad) by `crank`.
/// Gaps in the marks are findings of `file` (times from `t_start`).
pub(super) fn cycle_bounds(
    crank: &Crank,
    tdc: f64,
    cycle_marks: Option<&Signal>,
    file: &str,
    t_start: Option<i64>,
    findings: &mut Vec<Finding>,
) -> (CycleSource, Vec<Bound>) {
    let crossings = crank.crossings(tdc);
    let mut bounds: Vec<Bound> = Vec::new();
    let source = if let Some(c) = cycle_marks {
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
                        file,
                        Some(&c.topic),
                        Some(Place::span(ta, tb)),
                        format!("cycle marks {}..{} missing between {} and log_time {tb}: those cycles were delimited by the crank angle", ia + 1, ib - 1, fmt_time(ta, t_start)),
                    ));
                } else {
                    findings.push(Finding::new(
                        Severity::Warning,
                        FindingCode::Cycle,
                        file,
                        Some(&c.topic),
                        Some(Place::span(ta, tb)),
                        format!("cycle marks {}..{} missing between {} and log_time {tb} and the crank angle does not resolve them: cycles {ia}..{} skipped", ia + 1, ib - 1, fmt_time(ta, t_start), ib - 1),
                    ));
                }
            }
        }
        CycleSource::Marks
    } else {
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
        CycleSource::Angle
    };
    (source, bounds)
}
