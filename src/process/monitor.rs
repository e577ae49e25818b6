//! Monitoring a log's cycles against a process recipe: per cycle OK, NOK
//! (with every failed object and by how much) or not evaluated (with why);
//! envelopes learned from good cycles; SPC of every value check.

use super::curve::CycleCurve;
use super::objects::{self, ObjectResult};
use super::recipe::{Axis, EnvelopeMode, ProcessRecipe};
use super::spc::{Capability, ControlChart, capability, control_chart};
use crate::rig::cycles::CycleSet;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Least fraction of a cycle's grid with data for it to be evaluated.
pub const MIN_COVERAGE: f64 = 0.5;
/// Points of a learned stroke-axis envelope.
pub const STROKE_ENVELOPE_POINTS: usize = 200;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CycleStatus {
    Ok,
    Nok,
    NotEvaluated,
}

impl CycleStatus {
    pub fn name(self) -> &'static str {
        match self {
            CycleStatus::Ok => "ok",
            CycleStatus::Nok => "nok",
            CycleStatus::NotEvaluated => "not_evaluated",
        }
    }
}

/// One cycle's verdict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CycleVerdict {
    pub index: u64,
    pub t_start_ns: i64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub motor_rpm: f64,
    pub status: CycleStatus,
    /// Why the cycle was not evaluated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why_not: Option<String>,
    /// The objects that failed, with the reason and by how much.
    pub failed: Vec<ObjectResult>,
    /// Every value check's value (by its name); absent when not computable.
    #[serde(deserialize_with = "super::serde_back::map_nan")]
    pub values: BTreeMap<String, f64>,
}

impl CycleVerdict {
    /// Why the cycle is not OK: every failed object with its reason
    /// ("threshold seated: …"), or why it was not evaluated.
    pub fn reasons(&self) -> Vec<String> {
        match self.status {
            CycleStatus::NotEvaluated => self.why_not.iter().cloned().collect(),
            _ => self
                .failed
                .iter()
                .map(|f| {
                    format!(
                        "{} {}: {}",
                        f.kind,
                        f.name,
                        f.reason.as_deref().unwrap_or("")
                    )
                })
                .collect(),
        }
    }
}

/// SPC of one characteristic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Characteristic {
    pub name: String,
    /// What is measured: a process value's quantity (`peak_force_n` …) or a
    /// pin measure (`pin_dx_mm` …); the Q-DAS characteristic number.
    #[serde(deserialize_with = "super::serde_back::name")]
    pub quantity: super::serde_back::Name,
    #[serde(deserialize_with = "super::serde_back::name")]
    pub unit: super::serde_back::Name,
    pub capability: Option<Capability>,
    pub chart: Option<ControlChart>,
}

/// NOK counts per object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectCount {
    #[serde(deserialize_with = "super::serde_back::name")]
    pub kind: super::serde_back::Name,
    pub name: String,
    pub nok: usize,
}

/// A log's cycles against the recipe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MonitorReport {
    pub file: String,
    pub part_number: String,
    pub cycles: Vec<CycleVerdict>,
    pub ok: usize,
    pub nok: usize,
    pub not_evaluated: usize,
    pub by_object: Vec<ObjectCount>,
    pub spc: Vec<Characteristic>,
    pub notes: Vec<String>,
}

fn needs_force(r: &ProcessRecipe) -> bool {
    !(r.window.is_empty() && r.threshold.is_empty() && r.envelope.is_empty())
        || r.value.iter().any(|v| v.quantity.needs_force())
}

/// Why a cycle cannot be judged, if it cannot.
fn not_evaluable(curve: &CycleCurve, force_needed: bool) -> Option<String> {
    let c = curve.cycle;
    if c.stroke_coverage < MIN_COVERAGE {
        return Some(format!(
            "stroke data on {:.0} % of the cycle",
            100.0 * c.stroke_coverage
        ));
    }
    if force_needed && (!curve.has_force() || c.force_coverage < MIN_COVERAGE) {
        return Some(if curve.has_force() {
            format!(
                "force data on {:.0} % of the cycle",
                100.0 * c.force_coverage
            )
        } else {
            "no force data".to_string()
        });
    }
    None
}

/// Every object on one cycle, in recipe order (envelopes optional: not
/// while learning them).
fn evaluate_objects(r: &ProcessRecipe, curve: &CycleCurve, envelopes: bool) -> Vec<ObjectResult> {
    let mut out = Vec::with_capacity(r.object_count());
    out.extend(r.window.iter().map(|w| objects::window(w, curve)));
    out.extend(r.threshold.iter().map(|t| objects::threshold(t, curve)));
    if envelopes {
        out.extend(r.envelope.iter().map(|e| objects::envelope(e, curve)));
    }
    out.extend(r.value.iter().map(|v| objects::value(v, curve)));
    out
}

/// Judges every cycle of the set.
pub fn monitor(r: &ProcessRecipe, cs: &CycleSet) -> MonitorReport {
    let force_needed = needs_force(r);
    // Cycles are independent: judged in parallel, counted in order.
    let judged: Vec<(CycleVerdict, Vec<bool>)> = cs
        .cycles
        .par_iter()
        .map(|c| {
            let curve = CycleCurve::new(cs, c);
            let mut v = CycleVerdict {
                index: c.index,
                t_start_ns: c.t_start_ns,
                motor_rpm: c.motor_rpm_mean,
                status: CycleStatus::NotEvaluated,
                why_not: not_evaluable(&curve, force_needed),
                failed: Vec::new(),
                values: BTreeMap::new(),
            };
            let mut nok = Vec::new();
            if v.why_not.is_none() {
                let results = evaluate_objects(r, &curve, true);
                nok = results.iter().map(|o| !o.ok).collect();
                for o in &results {
                    if let (Some(x), "value") = (o.value, o.kind) {
                        v.values.insert(o.name.clone(), x);
                    }
                }
                v.failed = results.into_iter().filter(|o| !o.ok).collect();
                v.status = if v.failed.is_empty() {
                    CycleStatus::Ok
                } else {
                    CycleStatus::Nok
                };
            }
            (v, nok)
        })
        .collect();
    let mut nok_by: Vec<usize> = vec![0; r.object_count()];
    let mut cycles = Vec::with_capacity(judged.len());
    for (v, nok) in judged {
        for (k, bad) in nok.into_iter().enumerate() {
            nok_by[k] += usize::from(bad);
        }
        cycles.push(v);
    }
    let names = r
        .window
        .iter()
        .map(|w| ("window", &w.name))
        .chain(r.threshold.iter().map(|t| ("threshold", &t.name)))
        .chain(r.envelope.iter().map(|e| ("envelope", &e.name)))
        .chain(r.value.iter().map(|v| ("value", &v.name)));
    let by_object = names
        .zip(nok_by)
        .map(|((kind, name), nok)| ObjectCount {
            kind,
            name: name.clone(),
            nok,
        })
        .collect();
    let count = |s: CycleStatus| cycles.iter().filter(|c| c.status == s).count();
    let (ok, nok, not_evaluated) = (
        count(CycleStatus::Ok),
        count(CycleStatus::Nok),
        count(CycleStatus::NotEvaluated),
    );
    let spc = spc_of(r, &cycles);
    MonitorReport {
        file: cs.file.clone(),
        part_number: r.part_number.clone(),
        cycles,
        ok,
        nok,
        not_evaluated,
        by_object,
        spc,
        notes: Vec::new(),
    }
}

/// SPC of every value check over the evaluated cycles, in cycle order.
pub fn spc_of(r: &ProcessRecipe, cycles: &[CycleVerdict]) -> Vec<Characteristic> {
    r.value
        .iter()
        .map(|v| {
            let series: Vec<f64> = cycles
                .iter()
                .filter_map(|c| c.values.get(&v.name).copied())
                .collect();
            Characteristic {
                name: v.name.clone(),
                quantity: v.quantity.name(),
                unit: v.quantity.unit(),
                capability: capability(&series, r.spc.subgroup, v.min, v.max),
                chart: control_chart(&series, r.spc.subgroup),
            }
        })
        .collect()
}

/// Learns every envelope of the recipe from the first `n` good cycles
/// (evaluable, and passing every window, threshold and value check).
/// Returns the recipe with the bands filled in, and what was done.
pub fn learn(
    r: &ProcessRecipe,
    cs: &CycleSet,
    n: usize,
) -> Result<(ProcessRecipe, String), String> {
    if r.envelope.is_empty() {
        return Err("the recipe has no [[envelope]] to learn".into());
    }
    let force_needed = needs_force(r);
    let good: Vec<CycleCurve> = cs
        .cycles
        .iter()
        .map(|c| CycleCurve::new(cs, c))
        .filter(|cur| {
            not_evaluable(cur, force_needed).is_none()
                && evaluate_objects(r, cur, false).iter().all(|o| o.ok)
        })
        .take(n)
        .collect();
    if good.len() < 2 {
        return Err(format!(
            "only {} good cycle(s) in {} to learn from (at least 2 needed)",
            good.len(),
            cs.file
        ));
    }
    let mut out = r.clone();
    for e in &mut out.envelope {
        let grid: Vec<f64> = match e.x {
            Axis::Angle => cs
                .grid_deg
                .iter()
                .copied()
                .filter(|a| *a >= e.x_range[0] && *a <= e.x_range[1])
                .collect(),
            Axis::Stroke => (0..STROKE_ENVELOPE_POINTS)
                .map(|i| {
                    e.x_range[0]
                        + (e.x_range[1] - e.x_range[0]) * i as f64
                            / (STROKE_ENVELOPE_POINTS - 1) as f64
                })
                .collect(),
        };
        let (mut xs, mut lo, mut hi) = (Vec::new(), Vec::new(), Vec::new());
        let per_cycle: Vec<Vec<Option<f64>>> = good
            .iter()
            .map(|c| c.forces_at(e.x, e.branch, &grid))
            .collect();
        for (i, x) in grid.into_iter().enumerate() {
            let f: Vec<f64> = per_cycle.iter().filter_map(|v| v[i]).collect();
            if f.len() * 2 < good.len() || f.len() < 2 {
                continue;
            }
            let (a, b) = match e.mode {
                EnvelopeMode::Sigma => {
                    let m = f.iter().sum::<f64>() / f.len() as f64;
                    let sd = (f.iter().map(|v| (v - m) * (v - m)).sum::<f64>()
                        / (f.len() - 1) as f64)
                        .sqrt();
                    (m - e.k * sd, m + e.k * sd)
                }
                EnvelopeMode::Minmax => (
                    f.iter().copied().fold(f64::INFINITY, f64::min),
                    f.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ),
            };
            xs.push(x);
            lo.push(a - e.margin);
            hi.push(b + e.margin);
        }
        if xs.is_empty() {
            return Err(format!(
                "envelope '{}': the good cycles have no force data in x {}–{}",
                e.name, e.x_range[0], e.x_range[1]
            ));
        }
        e.learned_from = good.len();
        e.x_grid = xs;
        e.lo = lo;
        e.hi = hi;
    }
    let first = good.first().map_or(0, |c| c.cycle.index);
    let last = good.last().map_or(0, |c| c.cycle.index);
    Ok((
        out,
        format!(
            "learned {} envelope(s) from {} good cycles ({first}..={last}) of {}",
            r.envelope.len(),
            good.len(),
            cs.file
        ),
    ))
}
