//! A monitor run over several logs: each log's verdicts, the totals, and
//! the SPC of the value checks over all logs and by lot.

use super::monitor::{Characteristic, MonitorReport, spc_of};
use super::recipe::ProcessRecipe;
use super::story::{Confusion, StoryReport};
use serde::Serialize;
use std::collections::BTreeMap;

/// One log's outcome.
#[derive(Debug, Clone, Serialize)]
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
    /// What `--learn` did, if asked.
    pub learned: Option<String>,
    /// Process NOK against vision fail over every log's connectors (when
    /// vision recipes were given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub confusion: Option<Confusion>,
}

impl MonitorRun {
    /// Totals and SPC of the logs' reports (an unreadable log counts in none).
    pub fn from_logs(recipe: &ProcessRecipe, logs: Vec<LogMonitor>) -> Self {
        let reports = || logs.iter().filter_map(|l| l.report.as_ref().ok());
        let all: Vec<_> = reports().flat_map(|r| r.cycles.iter().cloned()).collect();
        let mut lots: BTreeMap<String, Vec<_>> = BTreeMap::new();
        for l in &logs {
            if let Ok(r) = &l.report {
                lots.entry(l.lot.clone().unwrap_or_else(|| "(no lot)".into()))
                    .or_default()
                    .extend(r.cycles.iter().cloned());
            }
        }
        let stories: Vec<&StoryReport> = logs.iter().filter_map(|l| l.story.as_ref()).collect();
        let confusion = (!stories.is_empty()).then(|| {
            let mut c = Confusion::default();
            for s in &stories {
                c.merge(&s.confusion);
            }
            c
        });
        MonitorRun {
            confusion,
            part_number: recipe.part_number.clone(),
            ok: reports().map(|r| r.ok).sum(),
            nok: reports().map(|r| r.nok).sum(),
            not_evaluated: reports().map(|r| r.not_evaluated).sum(),
            spc: spc_of(recipe, &all),
            spc_by_lot: lots
                .into_iter()
                .map(|(k, v)| (k, spc_of(recipe, &v)))
                .collect(),
            logs,
            learned: None,
        }
    }
}
