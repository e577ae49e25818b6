//! `trend` at plant scale: each shard calibrates its part of the logs (the
//! expensive step: a model fit per log) and hands over the history points;
//! the merge groups every shard's points into heads and fits, limits and
//! forecasts them with the single run's own function
//! (`engine::trend::trend_report`). The partial holds each calibrated
//! point and each log left out, with the log's place in the job's list.
//!
//! The merged folder is the single run's, byte for byte
//! (`tests/plant/trend.rs`), except — when one log's bytes appear in two
//! shards — the split of `calibrated` and `cached` (the shards calibrated
//! both copies; the merge lists the later copy as the single run does and
//! counts one calibration less). The run's wall-clock time (`wall_ms`)
//! stays in memory for the terminal and out of `trend.json` and the
//! partial, so a re-run of a shard writes the same bytes.

use super::partial::{Found, Header, Partial};
use super::shard::{Shard, split_list};
use crate::engine::trend::{TrendCache, TrendOptions, collect_logs, trend_report};
use crate::output::json::{NOT_REPRODUCIBLE, to_vec_pretty_without};
use crate::wear::WearModel;
use crate::wear::history::HistoryPoint;
use crate::wear::report::{ItemError, TrendReport};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The options a trend's merge needs (those of the report's second half).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrendSettings {
    pub by_rig: bool,
    pub model: WearModel,
    pub limit_mm: Option<f64>,
    pub tolerance_mm: Option<f64>,
    pub level: f64,
    pub ladder_mm: Vec<f64>,
    pub limit_revs: usize,
}

impl TrendSettings {
    pub fn of(o: &TrendOptions) -> Self {
        TrendSettings {
            by_rig: o.by_rig,
            model: o.model,
            limit_mm: o.limit_mm,
            tolerance_mm: o.tolerance_mm,
            level: o.level,
            ladder_mm: o.ladder_mm.clone(),
            limit_revs: o.limit_revs,
        }
    }

    fn options(&self) -> TrendOptions {
        TrendOptions {
            by_rig: self.by_rig,
            model: self.model,
            limit_mm: self.limit_mm,
            tolerance_mm: self.tolerance_mm,
            level: self.level,
            ladder_mm: self.ladder_mm.clone(),
            limit_revs: self.limit_revs,
            ..TrendOptions::default()
        }
    }
}

/// A trend shard's partial (after the [`Header`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrendBody {
    pub settings: TrendSettings,
    pub logs: usize,
    pub calibrated: usize,
    pub cached: usize,
    /// Each calibrated log's point and each log left out, with the log's
    /// place in the job's list.
    pub points: Vec<(u64, HistoryPoint)>,
    pub errors: Vec<(u64, ItemError)>,
}

/// A shard's part of a trend's inputs: the inputs to run (its logs, and
/// the named inputs that are not logs, so each is reported by one shard),
/// every unit's place in the job's list, and the list's identity.
pub struct TrendPart {
    pub inputs: Vec<PathBuf>,
    pub places: BTreeMap<String, u64>,
    pub units: u64,
    pub digest: String,
}

/// Splits a trend's inputs: the logs found (folders' `*.mcap`, files as
/// named) then the inputs that are not there, in that order, the list the
/// single run's report follows.
pub fn split_inputs(shard: Shard, inputs: &[PathBuf]) -> TrendPart {
    let (files, errors) = collect_logs(inputs);
    let list: Vec<String> = files
        .iter()
        .map(|f| f.display().to_string())
        .chain(errors.iter().map(|e| e.file.clone()))
        .collect();
    let part = split_list(shard, list, Clone::clone);
    TrendPart {
        inputs: part.kept.iter().map(PathBuf::from).collect(),
        places: part.kept.into_iter().zip(part.orders).collect(),
        units: part.units,
        digest: part.digest,
    }
}

/// The files of a trend folder (`trend.json`, `history.csv`, `trend.md`,
/// `trend.png` when there is a head); with `shard`, also `partial.json`.
pub fn trend_folder(
    report: &TrendReport,
    shard: Option<(Header, &TrendPart, &TrendSettings)>,
) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (
            "trend.json".into(),
            to_vec_pretty_without(report, NOT_REPRODUCIBLE).map_err(|e| e.to_string())?,
        ),
        ("history.csv".into(), report.to_csv().into_bytes()),
        ("trend.md".into(), report.to_markdown().into_bytes()),
    ];
    if !report.heads.is_empty() {
        files.push((
            "trend.png".into(),
            report.to_png().map_err(|e| e.to_string())?,
        ));
    }
    if let Some((header, part, settings)) = shard {
        let place = |file: &str| {
            part.places
                .get(file)
                .copied()
                .ok_or_else(|| format!("{file}: not among the shard's inputs"))
        };
        let points = report
            .heads
            .iter()
            .flat_map(|h| &h.points)
            .map(|p| Ok((place(&p.file)?, p.clone())))
            .collect::<Result<Vec<_>, String>>()?;
        let errors = report
            .errors
            .iter()
            .map(|e| Ok((place(&e.file)?, e.clone())))
            .collect::<Result<Vec<_>, String>>()?;
        let partial = Partial {
            header,
            body: TrendBody {
                settings: settings.clone(),
                logs: report.logs,
                calibrated: report.calibrated,
                cached: report.cached,
                points,
                errors,
            },
        };
        files.push((
            super::partial::PARTIAL_FILE.into(),
            serde_json::to_vec(&partial).map_err(|e| e.to_string())?,
        ));
    }
    Ok(files)
}

/// A merged trend: the report, its folder's files (with the calibration
/// cache of every point, as a single run with `--out` keeps it).
pub struct MergedTrend {
    pub report: TrendReport,
    pub files: Vec<(String, Vec<u8>)>,
}

/// Merges one job's trend partials (one complete set, in shard order).
pub fn merge_trend(set: Vec<(&Found, Partial<TrendBody>)>) -> Result<MergedTrend, String> {
    let start = std::time::Instant::now();
    let (f0, p0) = set.first().ok_or("nothing to merge")?;
    let settings = p0.body.settings.clone();
    for (f, p) in &set {
        if p.body.settings != settings {
            return Err(format!(
                "{}: its trend options differ from {}'s: not shards of one job",
                f.shown, f0.shown
            ));
        }
    }
    let (mut logs, mut calibrated, mut cached) = (0, 0, 0);
    let mut points: Vec<(u64, &str, HistoryPoint)> = Vec::new();
    let mut errors: Vec<(u64, ItemError)> = Vec::new();
    for (f, p) in set {
        logs += p.body.logs;
        calibrated += p.body.calibrated;
        cached += p.body.cached;
        points.extend(
            p.body
                .points
                .into_iter()
                .map(|(o, x)| (o, f.shown.as_str(), x)),
        );
        errors.extend(p.body.errors);
    }
    points.sort_by_key(|p| p.0);
    let mut all = points.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>();
    all.extend(errors.iter().map(|e| (e.0, "")));
    all.sort_by_key(|x| x.0);
    if let Some(w) = all.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "two shards hold the log at place {} of the job's list: the partials overlap{}",
            w[0].0,
            [w[0].1, w[1].1]
                .iter()
                .filter(|s| !s.is_empty())
                .map(|s| format!(" ({s})"))
                .collect::<String>()
        ));
    }
    // One log's bytes in two shards: the later copy is left out, as the
    // single run leaves it out.
    let mut seen: BTreeMap<String, String> = BTreeMap::new();
    let mut kept = Vec::new();
    for (o, _, p) in points {
        match seen.get(&p.sha256) {
            Some(first) => {
                errors.push((
                    o,
                    ItemError {
                        file: p.file.clone(),
                        error: format!("the same bytes as {first}: counted once"),
                    },
                ));
                calibrated = calibrated.saturating_sub(1);
            }
            None => {
                seen.insert(p.sha256.clone(), p.file.clone());
                kept.push(p);
            }
        }
    }
    errors.sort_by_key(|e| e.0);
    let opts = settings.options();
    let cache = TrendCache {
        version: 0,
        entries: kept.iter().map(|p| (p.sha256.clone(), p.clone())).collect(),
    };
    let report = trend_report(
        kept,
        errors.into_iter().map(|e| e.1).collect(),
        logs,
        calibrated,
        cached,
        &opts,
        start,
    );
    let mut files = trend_folder(&report, None)?;
    if report.calibrated > 0 {
        files.push(("trend-cache.json".into(), cache.to_json()));
    }
    Ok(MergedTrend { report, files })
}
