//! `monitor` at plant scale: the files of a monitor folder for a single
//! run, a shard and a merge alike, a shard's partial, and the exact merge.
//!
//! A monitor run's aggregates are its SPC: capability per characteristic
//! over all logs, by lot and by speed, and the X̄/R or I-MR charts with the
//! Western Electric rules, which read the values *in order* (a run of
//! eight on one side of the centre line). Per-characteristic sums would
//! give the capability but not the charts' rules, so a shard's partial
//! carries what the SPC is computed from: each of its logs' verdicts with
//! every cycle's values, and the pins its photographs measured (the same
//! per-log results `monitor.json` holds), each with the log's place in the
//! job's input list. The merge puts the logs back in that order and builds
//! the run with the single run's own function (`MonitorRun::from_logs`)
//! and writes it with the single run's writer: the merged folder is the
//! single run's, byte for byte (`tests/plant/monitor.rs`). The monitor
//! reports no quantiles, so no sketch is needed.

use super::partial::{FileCheck, FolderFiles, Found, Header, Partial};
use crate::export::parquet::cycles::{CYCLES, cycles_table};
use crate::export::parquet::{PartitionKey, partition_file_name, table_files};
use crate::process::ProcessRecipe;
use crate::process::charts::chart_files;
use crate::process::pin_spc::ConnectorPins;
use crate::process::report::{connectors_csv, cycles_csv, spc_csv};
use crate::process::run::{LogMonitor, MonitorRun};
use serde::{Deserialize, Serialize};

/// What a monitor folder holds besides its reports.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MonitorOutputs {
    /// The `cycles` table, partitioned by these keys (none: one file);
    /// `None`: no Parquet.
    pub parquet: Option<Vec<PartitionKey>>,
}

impl MonitorOutputs {
    fn stale(&self) -> Vec<String> {
        match &self.parquet {
            None => vec![format!("{CYCLES}.parquet"), CYCLES.to_string()],
            Some(k) if k.is_empty() => vec![CYCLES.to_string()],
            Some(_) => vec![format!("{CYCLES}.parquet")],
        }
    }
}

/// One log of a shard: its place in the job's list, its result, and the
/// pins its photographs measured (not in the log's JSON).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MonitorLog {
    pub order: u64,
    pub log: LogMonitor,
    pub pins: Vec<ConnectorPins>,
}

/// A monitor shard's partial (after the [`Header`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MonitorBody {
    pub recipe: ProcessRecipe,
    pub outputs: MonitorOutputs,
    pub logs: Vec<MonitorLog>,
    /// The shard's own files the merge checks (its Parquet), so a merge
    /// never mixes a partial with tables of another run.
    pub checks: Vec<FileCheck>,
}

/// The files of a monitor folder (names may be paths below it) and the
/// entries an earlier run left that this one does not write. With
/// `shard` (a shard's header and its logs' places in the job's list),
/// also `partial.json`.
pub fn monitor_folder(
    run: &MonitorRun,
    recipe: &ProcessRecipe,
    outputs: &MonitorOutputs,
    shard: Option<(Header, &[u64])>,
) -> Result<FolderFiles, String> {
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (
            "monitor.json".into(),
            serde_json::to_vec_pretty(run).map_err(|e| e.to_string())?,
        ),
        ("cycles.csv".into(), cycles_csv(run).into_bytes()),
        ("spc.csv".into(), spc_csv(run).into_bytes()),
    ];
    if run.confusion.is_some() {
        files.push(("connectors.csv".into(), connectors_csv(run).into_bytes()));
    }
    files.extend(chart_files(run).map_err(|e| e.to_string())?);
    let parquet_from = files.len();
    if let Some(keys) = &outputs.parquet {
        let t = cycles_table(run).map_err(|e| e.to_string())?;
        let file = shard.as_ref().map_or_else(
            || partition_file_name(0, 1),
            |(h, _)| partition_file_name(h.shard.k, h.shard.n),
        );
        files.extend(table_files(CYCLES, &t, keys, &file).map_err(|e| e.to_string())?);
    }
    if let Some((header, orders)) = shard {
        if orders.len() != run.logs.len() {
            return Err("a place in the job's list for every log is needed".into());
        }
        let logs = run
            .logs
            .iter()
            .zip(orders)
            .map(|(l, &order)| MonitorLog {
                order,
                log: l.clone(),
                pins: l.story.as_ref().map(|s| s.pins.clone()).unwrap_or_default(),
            })
            .collect();
        let checks = files[parquet_from..]
            .iter()
            .map(|(n, b)| FileCheck::of(n, b))
            .collect();
        let partial = Partial {
            header,
            body: MonitorBody {
                recipe: recipe.clone(),
                outputs: outputs.clone(),
                logs,
                checks,
            },
        };
        files.push((
            super::partial::PARTIAL_FILE.into(),
            serde_json::to_vec(&partial).map_err(|e| e.to_string())?,
        ));
    }
    Ok((files, outputs.stale()))
}

/// The exit status of a monitor run: 3 a log could not be monitored, 1 a
/// cycle is NOK or not evaluated, else 0.
pub fn exit_status(run: &MonitorRun) -> u8 {
    if run.logs.iter().any(|l| l.report.is_err()) {
        3
    } else if run.nok > 0 || run.not_evaluated > 0 {
        1
    } else {
        0
    }
}

/// A merged monitor run and its folder's files.
pub struct MergedMonitor {
    pub run: MonitorRun,
    pub files: Vec<(String, Vec<u8>)>,
    pub remove: Vec<String>,
}

/// Merges one job's monitor partials (one complete set, in shard order).
pub fn merge_monitor(set: Vec<(&Found, Partial<MonitorBody>)>) -> Result<MergedMonitor, String> {
    let (f0, p0) = set.first().ok_or("nothing to merge")?;
    let (recipe, outputs) = (p0.body.recipe.clone(), p0.body.outputs.clone());
    for (f, p) in &set {
        if p.body.recipe != recipe || p.body.outputs != outputs {
            return Err(format!(
                "{}: its process recipe or outputs differ from {}'s: not shards of one job",
                f.shown, f0.shown
            ));
        }
        for c in &p.body.checks {
            c.verify(&f.dir)?;
        }
    }
    let mut logs: Vec<(u64, &str, MonitorLog)> = Vec::new();
    for (f, p) in set {
        logs.extend(
            p.body
                .logs
                .into_iter()
                .map(|l| (l.order, f.shown.as_str(), l)),
        );
    }
    logs.sort_by_key(|l| l.0);
    if let Some(w) = logs.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "{} and {} both hold the log at place {} of the job's list ({}): the partials overlap",
            w[0].1, w[1].1, w[0].0, w[0].2.log.file
        ));
    }
    let logs: Vec<LogMonitor> = logs
        .into_iter()
        .map(|(_, _, mut l)| {
            if let Some(s) = &mut l.log.story {
                s.pins = l.pins;
            }
            l.log
        })
        .collect();
    let run = MonitorRun::from_logs(&recipe, logs);
    let (files, remove) = monitor_folder(&run, &recipe, &outputs, None)?;
    Ok(MergedMonitor { run, files, remove })
}
