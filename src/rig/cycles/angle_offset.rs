//! The crank angle's zero: where the encoder's 0 sits relative to top dead
//! centre. Estimated from the crank angle at the `/rig/cycle` marks (or,
//! without marks, from the phase of the displacement against the ideal
//! stroke), then a session override, the metadata or the estimate is
//! applied — with a finding when they disagree or the encoder is off.

use super::crank::{Crank, wrap_pi};
use super::fit::{fit_phase, mean_std};
use super::types::{CycleOptions, OffsetEstimate, ValueSource};
use crate::rig::channel_map::SignalKind;
use crate::rig::load::RigLog;
use crate::rig::report::{Finding, Severity};
use crate::rig::signals::Signal;

/// The angle offset of a log: `cycle_marks` the `/rig/cycle` signal if
/// any, `quantum` the encoder's quantisation σ (the floor of the
/// uncertainty), `say` the finding constructor for the angle channel.
/// The caller adds `applied` to the crank angles.
pub(super) fn angle_offset(
    crank: &Crank,
    cycle_marks: Option<&Signal>,
    log: &RigLog,
    opts: &CycleOptions,
    quantum: f64,
    say: impl Fn(Severity, String) -> Finding,
    findings: &mut Vec<Finding>,
) -> OffsetEstimate {
    let geom = &opts.geometry;
    let tdc = geom.tdc_angle();
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
    if let Some(c) = cycle_marks {
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
    if ao.estimate.is_none()
        && let Some(d) = log
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
        if let Some(phi) = fit_phase(geom, &th, &dv, None) {
            let k = 8;
            let len = th.len() / k;
            let parts: Vec<f64> = (0..k)
                .filter_map(|b| {
                    fit_phase(
                        geom,
                        &th[b * len..(b + 1) * len],
                        &dv[b * len..(b + 1) * len],
                        Some(phi),
                    )
                })
                .collect();
            let (_, s) = mean_std(&parts);
            ao.estimate = Some(wrap_pi(phi));
            ao.sigma = Some((s / (parts.len().max(1) as f64).sqrt()).max(quantum));
            est_method = "from the displacement signal (phase of the best fit to the ideal stroke; biased by the sensor lag, ω·τ)";
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
        if let (Some(e), Some(s)) = (ao.estimate, ao.sigma)
            && wrap_pi(e - m).abs() > (3.0 * s).max(1f64.to_radians())
        {
            findings.push(say(
                    Severity::Warning,
                    format!(
                        "metadata angle_offset_rad = {m} rad ({:.2}°) disagrees with the estimate {est_text}; the metadata value is used",
                        m.to_degrees()
                    ),
                ));
        }
    } else if let (Some(e), Some(s)) = (ao.estimate, ao.sigma) {
        let thr = (3.0 * s).max(1f64.to_radians());
        if e.abs() > thr {
            ao.applied = e;
            ao.source = ValueSource::Estimated;
            ao.note =
                format!("no angle_offset_rad in the metadata: the estimate {est_text} is applied");
            findings.push(say(
                Severity::Warning,
                format!("encoder zero is off: crank angle offset estimated at {est_text} and applied (no angle_offset_rad in the metadata)"),
            ));
        } else {
            ao.note = format!(
                "no angle_offset_rad in the metadata; estimate {est_text} is within max(3σ, 1°) of 0: the encoder is taken as calibrated (offset 0)"
            );
            findings.push(say(
                Severity::Info,
                format!("crank angle offset estimated at {est_text}: consistent with a calibrated encoder, 0 used"),
            ));
        }
    } else {
        ao.note = "no metadata and no estimate: 0 used".into();
    }
    ao
}
