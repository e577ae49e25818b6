//! The sensor zeros of the cycle analysis, estimated and reported, never
//! silently absorbed: the laser zero mark (stroke at which the laser reads
//! 0) from the off-part stroke, the force tare (a line in time) from the
//! off-part force; metadata or a session override wins over the estimate,
//! with a warning when they disagree.

use super::fit::{line_fit, mean_std};
use super::types::{CycleOptions, CycleSet, OffsetEstimate, ValueSource};
use crate::rig::load::RigLog;
use crate::rig::report::{Finding, FindingCode, Severity};
use crate::rig::signals::Signal;

/// What both estimates read besides the grids.
pub(super) struct OffsetContext<'a> {
    /// The ideal stroke on the crank-angle grid (mm).
    pub ideal: &'a [f64],
    /// Grid points well off the part (stroke below the standoff − 1 mm).
    pub off_part: &'a [bool],
    /// Grid points per revolution.
    pub n: usize,
    pub log: &'a RigLog,
    pub opts: &'a CycleOptions,
    pub file: &'a str,
}

/// The laser zero mark from the displacement grids (before they become
/// stroke grids); sets `set.offsets.laser_zero_mm`.
pub(super) fn laser_zero(
    d: &Signal,
    raw_disp: &[Vec<f64>],
    set: &mut CycleSet,
    ctx: &OffsetContext,
    findings: &mut Vec<Finding>,
) {
    let label = format!("{} (displacement)", d.topic);
    let per_cycle: Vec<f64> = raw_disp
        .iter()
        .zip(&set.cycles)
        .filter(|(_, c)| c.usable)
        .filter_map(|(g, _)| {
            let v: Vec<f64> = g
                .iter()
                .zip(ctx.ideal)
                .zip(ctx.off_part)
                .filter(|((x, _), o)| x.is_finite() && **o)
                .map(|((x, s), _)| s - x)
                .collect();
            (v.len() > ctx.n / 10).then(|| v.iter().sum::<f64>() / v.len() as f64)
        })
        .collect();
    let (m, s) = mean_std(&per_cycle);
    let mut lz = OffsetEstimate {
        name: "laser zero mark".into(),
        unit: "mm".into(),
        applied: 0.0,
        source: ValueSource::Unavailable,
        metadata: ctx.log.meta.laser_zero_mm,
        estimate: m.is_finite().then_some(m),
        sigma: (per_cycle.len() > 1).then(|| s / (per_cycle.len() as f64).sqrt()),
        systematic: ctx.log.meta.clearance_mm,
        note: String::new(),
    };
    let est_text = match (lz.estimate, lz.sigma) {
        (Some(e), Some(s)) => format!(
            "{e:.4} mm ± {s:.4} mm (mean of s_ideal − displacement off the part over {} cycles; with a clearance of {} the journal's mean position biases it by up to that much)",
            per_cycle.len(),
            ctx.log
                .meta
                .clearance_mm
                .map_or("c".to_string(), |c| format!("{c} mm"))
        ),
        _ => "not estimable".into(),
    };
    let words = Wording {
        key: "laser_zero_mm",
        unit: "mm",
        kept: "",
        versus: "the estimate",
        estimated_note: format!("no laser_zero_mm in the metadata: estimate {est_text} applied"),
        estimated_finding: format!(
            "laser zero mark (stroke at which the laser reads 0) estimated at {est_text}; applied since the metadata has no laser_zero_mm"
        ),
    };
    let clearance = ctx.log.meta.clearance_mm.unwrap_or(0.0);
    let given = (ctx.opts.laser_zero_mm, ctx.log.meta.laser_zero_mm);
    let at = (label.as_str(), ctx.file);
    let allow = |s: f64| 3.0 * s + clearance;
    apply_source(&mut lz, given, allow, &est_text, &words, at, findings);
    set.offsets.laser_zero_mm = lz;
}

/// The force tare from the off-part force of the usable cycles, subtracted
/// from the force grids in place; sets the tare fields of `set.offsets`.
pub(super) fn force_tare(
    f: &Signal,
    raw_force: &mut [Vec<f64>],
    set: &mut CycleSet,
    ctx: &OffsetContext,
    findings: &mut Vec<Finding>,
) {
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
            .zip(ctx.off_part)
            .filter(|(x, o)| x.is_finite() && **o)
            .map(|(x, _)| *x)
            .collect();
        if v.len() > ctx.n / 10 {
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
        metadata: ctx.log.meta.force_tare_n,
        estimate: m.is_finite().then_some(m),
        sigma: (ys.len() > 1).then(|| s / (ys.len() as f64).sqrt()),
        systematic: None,
        note: String::new(),
    };
    if let Some(lf) = fit {
        let x = |t: Option<i64>| t.map(|t| (t - t_ref) as f64 * 1e-9);
        set.offsets.force_tare_start_n = x(ctx.log.log_start_ns).map(|x| lf.at(x));
        set.offsets.force_tare_end_n = x(ctx.log.log_end_ns).map(|x| lf.at(x));
        set.offsets.force_tare_start_sigma_n = x(ctx.log.log_start_ns).map(|x| lf.sigma_at(x));
        set.offsets.force_tare_end_sigma_n = x(ctx.log.log_end_ns).map(|x| lf.sigma_at(x));
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
    let words = Wording {
        key: "force_tare_n",
        unit: "N",
        kept: " (constant)",
        versus: "the off-part reading",
        estimated_note: format!(
            "no force_tare_n in the metadata: the fitted tare line is subtracted cycle by cycle; estimate {est_text}"
        ),
        estimated_finding: format!(
            "force tare estimated at {est_text}; subtracted (linear in time) since the metadata has no force_tare_n"
        ),
    };
    let given = (ctx.opts.force_tare_n, ctx.log.meta.force_tare_n);
    let at = (label.as_str(), ctx.file);
    let allow = |s: f64| (3.0 * s).max(0.02);
    let estimated = apply_source(&mut ft, given, allow, &est_text, &words, at, findings);
    let tare_line: Option<(f64, f64)> = if estimated {
        fit.map(|lf| (lf.a, lf.b))
    } else {
        None
    };
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

/// How an offset's source is told: its metadata key and unit, what the
/// metadata is kept as, what it is compared with, and the note and finding
/// when the estimate is applied.
struct Wording {
    key: &'static str,
    unit: &'static str,
    kept: &'static str,
    versus: &'static str,
    estimated_note: String,
    estimated_finding: String,
}

/// Sets the applied value of `est` from the first source that has one: a
/// session override (`given.0`), the metadata (`given.1`, with a warning
/// when the estimate disagrees by more than `allow(σ)`), else the estimate
/// itself (said with an info finding). `at` is the (channel label, file)
/// the findings name. Returns whether the estimate was applied.
fn apply_source(
    est: &mut OffsetEstimate,
    given: (Option<f64>, Option<f64>),
    allow: impl Fn(f64) -> f64,
    est_text: &str,
    words: &Wording,
    at: (&str, &str),
    findings: &mut Vec<Finding>,
) -> bool {
    let (key, unit, kept) = (words.key, words.unit, words.kept);
    let finding = |severity, message| {
        Finding::new(
            severity,
            FindingCode::OffsetEstimated,
            at.1,
            Some(at.0),
            None,
            message,
        )
    };
    if let Some(v) = given.0 {
        est.applied = v;
        est.source = ValueSource::Override;
        est.note = format!("session override{kept}; estimate {est_text}");
    } else if let Some(v) = given.1 {
        est.applied = v;
        est.source = ValueSource::Metadata;
        est.note = format!("metadata {key}{kept}; estimate {est_text}");
        if let (Some(e), Some(s)) = (est.estimate, est.sigma)
            && (e - v).abs() > allow(s)
        {
            findings.push(finding(
                    Severity::Warning,
                    format!(
                        "metadata {key} = {} {unit} disagrees with {} {est_text}; the metadata value is used",
                        crate::fmt::plain(v),
                        words.versus
                    ),
                ));
        }
    } else if let Some(e) = est.estimate {
        est.applied = e;
        est.source = ValueSource::Estimated;
        est.note = words.estimated_note.clone();
        findings.push(finding(Severity::Info, words.estimated_finding.clone()));
        return true;
    }
    false
}
