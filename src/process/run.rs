//! A monitor run over several logs: each log's verdicts, the totals, and
//! the SPC of the value checks and of the pins' positions over all logs,
//! by lot and by speed.

use super::monitor::{Characteristic, CycleVerdict, MonitorReport, spc_of};
use super::pin_spc::{ConnectorPins, pin_characteristics};
use super::recipe::ProcessRecipe;
use super::story::{Confusion, StoryReport};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One log's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LogMonitor {
    pub file: String,
    pub lot: Option<String>,
    pub motor_rpm: Option<f64>,
    /// The log's verdicts, or why it could not be monitored.
    pub report: Result<MonitorReport, String>,
    /// Each connector's story (when vision recipes were given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub story: Option<StoryReport>,
}

impl LogMonitor {
    /// The log's lot group: its `lot` metadata, "(no lot)" when absent.
    pub fn lot_group(&self) -> String {
        self.lot.clone().unwrap_or_else(|| "(no lot)".into())
    }

    /// The log's speed group: its speed set-point (`motor_rpm` metadata),
    /// else the median of its cycles' speeds rounded to 10 rev/min; "(no
    /// speed)" when neither is known.
    pub fn speed_group(&self) -> String {
        let rpm = self.motor_rpm.filter(|r| r.is_finite()).or_else(|| {
            let r = self.report.as_ref().ok()?;
            let mut v: Vec<f64> = r
                .cycles
                .iter()
                .map(|c| c.motor_rpm)
                .filter(|x| x.is_finite())
                .collect();
            if v.is_empty() {
                return None;
            }
            v.sort_by(f64::total_cmp);
            Some((v[v.len() / 2] / 10.0).round() * 10.0)
        });
        rpm.map_or_else(|| "(no speed)".into(), |r| format!("{r:.0} rpm"))
    }
}

/// Every log's verdicts and the SPC over them.
#[derive(Debug, Clone, Serialize)]
pub struct MonitorRun {
    pub part_number: String,
    pub logs: Vec<LogMonitor>,
    pub ok: usize,
    pub nok: usize,
    pub not_evaluated: usize,
    /// Over every log's evaluated cycles, in log then cycle order.
    pub spc: Vec<Characteristic>,
    /// By the logs' `lot` metadata ("(no lot)" when absent).
    pub spc_by_lot: BTreeMap<String, Vec<Characteristic>>,
    /// By the logs' speed set-point ("1200 rpm"; see [`LogMonitor::speed_group`]).
    pub spc_by_speed: BTreeMap<String, Vec<Characteristic>>,
    /// The pins' positions on the connectors' photographs (with vision
    /// recipes): per pin and measure, over every connector in log then
    /// cycle order, with control charts (see [`super::pin_spc`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pin_spc: Vec<Characteristic>,
    /// The pins' capability by lot and by speed (no charts).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub pin_spc_by_lot: BTreeMap<String, Vec<Characteristic>>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub pin_spc_by_speed: BTreeMap<String, Vec<Characteristic>>,
    /// What `--learn` did, if asked.
    pub learned: Option<String>,
    /// Process NOK against vision fail over every log's connectors (when
    /// vision recipes were given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub confusion: Option<Confusion>,
}

/// Values grouped by a key of their log, each group in log order.
fn grouped<'a, T: 'a, I: Iterator<Item = &'a T>>(
    logs: &'a [LogMonitor],
    key: impl Fn(&LogMonitor) -> String,
    items: impl Fn(&'a LogMonitor) -> Option<I>,
) -> BTreeMap<String, Vec<&'a T>> {
    let mut out: BTreeMap<String, Vec<&T>> = BTreeMap::new();
    for l in logs {
        if let Some(it) = items(l) {
            out.entry(key(l)).or_default().extend(it);
        }
    }
    out
}

fn cycles_of(l: &LogMonitor) -> Option<std::slice::Iter<'_, CycleVerdict>> {
    l.report.as_ref().ok().map(|r| r.cycles.iter())
}

fn pins_of(l: &LogMonitor) -> Option<std::slice::Iter<'_, ConnectorPins>> {
    l.story.as_ref().map(|s| s.pins.iter())
}

impl MonitorRun {
    /// Totals and SPC of the logs' reports (an unreadable log counts in none).
    pub fn from_logs(recipe: &ProcessRecipe, logs: Vec<LogMonitor>) -> Self {
        let reports = || logs.iter().filter_map(|l| l.report.as_ref().ok());
        let all: Vec<_> = reports().flat_map(|r| r.cycles.iter().cloned()).collect();
        let spc_groups = |key: fn(&LogMonitor) -> String| -> BTreeMap<String, Vec<Characteristic>> {
            grouped(&logs, key, cycles_of)
                .into_iter()
                .map(|(k, v)| {
                    let v: Vec<_> = v.into_iter().cloned().collect();
                    (k, spc_of(recipe, &v))
                })
                .collect()
        };
        let stories: Vec<&StoryReport> = logs.iter().filter_map(|l| l.story.as_ref()).collect();
        let confusion = (!stories.is_empty()).then(|| {
            let mut c = Confusion::default();
            for s in &stories {
                c.merge(&s.confusion);
            }
            c
        });
        let connectors: Vec<&ConnectorPins> = stories.iter().flat_map(|s| &s.pins).collect();
        let pin_groups = |key: fn(&LogMonitor) -> String| -> BTreeMap<String, Vec<Characteristic>> {
            grouped(&logs, key, pins_of)
                .into_iter()
                .map(|(k, v)| (k, pin_characteristics(&v, recipe.spc.subgroup, false)))
                .filter(|(_, v)| !v.is_empty())
                .collect()
        };
        MonitorRun {
            confusion,
            part_number: recipe.part_number.clone(),
            ok: reports().map(|r| r.ok).sum(),
            nok: reports().map(|r| r.nok).sum(),
            not_evaluated: reports().map(|r| r.not_evaluated).sum(),
            spc: spc_of(recipe, &all),
            spc_by_lot: spc_groups(LogMonitor::lot_group),
            spc_by_speed: spc_groups(LogMonitor::speed_group),
            pin_spc: pin_characteristics(&connectors, recipe.spc.subgroup, true),
            pin_spc_by_lot: pin_groups(LogMonitor::lot_group),
            pin_spc_by_speed: pin_groups(LogMonitor::speed_group),
            logs,
            learned: None,
        }
    }
}
