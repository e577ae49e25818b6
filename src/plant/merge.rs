//! `pinsight merge`: the partials of a sharded job merged into the report
//! one run over all inputs writes.
//!
//! Every partial is read and its header checked first: one job, one
//! pinsight version, one input list, one shard count, the same settings
//! (recipes, options), every shard exactly once (`partial::check_set`),
//! each refusal naming the files. Then the job's own merge reads and
//! checks the shards' files and builds the merged folder's files in
//! memory; nothing is written until all of that succeeded, and then in one
//! commit (`crate::output`): a refused or failed merge never leaves a half
//! merged report.

use super::partial::{self, Found, Header, Job, Partial};
use std::path::PathBuf;

/// A merged job: its folder's files, what to remove of an earlier run,
/// and what to say.
pub struct Merged {
    pub job: Job,
    pub shards: u32,
    pub files: Vec<(String, Vec<u8>)>,
    pub remove: Vec<String>,
    /// One line for the terminal.
    pub summary: String,
    /// The report printed without `--out` (Markdown or text), and as JSON.
    pub text: String,
    pub json: String,
    /// The exit status a single run of the job would give (0, 1 or 3).
    pub exit: u8,
}

/// Reads, checks and merges the partials named (files or shards' folders).
pub fn merge_paths(paths: &[PathBuf]) -> Result<Merged, String> {
    let mut heads: Vec<(Found, Header)> = Vec::new();
    let mut bytes = Vec::new();
    for p in paths {
        let found = partial::locate(p)?;
        let b = partial::read_bytes(&found)?;
        let h = partial::read_header(&found, &b)?;
        heads.push((found, h));
        bytes.push(b);
    }
    let ordered = partial::check_set(&heads)?;
    let at = |e: &(Found, Header)| {
        heads
            .iter()
            .position(|x| std::ptr::eq(x, e))
            .expect("an entry of the set")
    };
    let idx: Vec<usize> = ordered.iter().map(|e| at(e)).collect();
    let job = heads[idx[0]].1.job;
    let shards = heads[idx[0]].1.shard.n;
    fn bodies<'a, B: serde::de::DeserializeOwned>(
        heads: &'a [(Found, Header)],
        bytes: &[Vec<u8>],
        idx: &[usize],
    ) -> Result<Vec<(&'a Found, Partial<B>)>, String> {
        idx.iter()
            .map(|&i| Ok((&heads[i].0, partial::read_body(&heads[i].0, &bytes[i])?)))
            .collect()
    }
    match job {
        Job::Yield => {
            let set = bodies(&heads, &bytes, &idx)?;
            drop(bytes);
            let m = super::yields::merge_yield(&set)?;
            let title = set[0].1.body.title.clone();
            Ok(Merged {
                job,
                shards,
                summary: m.report.summary_line(),
                text: m.report.markdown(&title, &[]),
                json: serde_json::to_string_pretty(&m.report).map_err(|e| e.to_string())?,
                exit: if m.report.errors > 0 { 3 } else { 0 },
                files: m.files,
                remove: m.remove,
            })
        }
        Job::Monitor => {
            let set = bodies(&heads, &bytes, &idx)?;
            drop(bytes);
            let m = super::monitor::merge_monitor(set)?;
            let r = &m.run;
            Ok(Merged {
                job,
                shards,
                summary: format!(
                    "{} logs: {} cycles OK, {} NOK, {} not evaluated",
                    r.logs.len(),
                    r.ok,
                    r.nok,
                    r.not_evaluated
                ),
                text: crate::process::report::summary_text(r),
                json: serde_json::to_string_pretty(r).map_err(|e| e.to_string())?,
                exit: super::monitor::exit_status(r),
                files: m.files,
                remove: m.remove,
            })
        }
        Job::Trend => {
            let set = bodies(&heads, &bytes, &idx)?;
            drop(bytes);
            let m = super::trend::merge_trend(set)?;
            let r = &m.report;
            Ok(Merged {
                job,
                shards,
                summary: format!(
                    "{} logs, {} heads, {} left out",
                    r.logs,
                    r.heads.len(),
                    r.errors.len()
                ),
                text: r.to_markdown(),
                json: serde_json::to_string_pretty(r).map_err(|e| e.to_string())?,
                exit: if r.errors.is_empty() { 0 } else { 3 },
                files: m.files,
                remove: Vec::new(),
            })
        }
        Job::Sweep => {
            let set = bodies(&heads, &bytes, &idx)?;
            drop(bytes);
            let m = super::sweep::merge_sweep(set)?;
            let r = &m.result;
            Ok(Merged {
                job,
                shards,
                summary: format!("{} cases, {} failed", r.cases.len(), r.failed),
                text: String::from_utf8_lossy(&m.files[0].1).into_owned(),
                json: String::from_utf8_lossy(&m.files[1].1).into_owned(),
                exit: u8::from(r.failed > 0),
                files: m.files,
                remove: Vec::new(),
            })
        }
    }
}
