//! Partial results of a sharded batch, and their exact merge.
//!
//! Each shard of `pinsight yield --shard k/n --out DIR` writes, beside its
//! own report, `partial.json`: the mergeable aggregate of its items
//! ([`YieldAcc`]: counts for the yield and its Wilson interval, DPPM, the
//! Pareto, the groups, per-position counts and exact offset sums) and each
//! item's lines of the per-item outputs with its place in the whole
//! batch's order. `pinsight merge` adds the aggregates and interleaves the
//! items back into the batch's order, and writes through the single run's
//! own writer: the merged folder is byte for byte the folder one run over
//! all inputs writes (`tests/plant_shard.rs`).
//!
//! A merge is refused, naming the files, unless the partials are one job's
//! complete set: the same input list (its digest and unit count), the same
//! shard count, recipes' title and grouping, and every shard exactly once.

use super::shard::Shard;
use crate::vision::report::{ItemRecord, YieldReport};
use crate::vision::yield_acc::YieldAcc;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The partial's file name in a shard's output folder.
pub const PARTIAL_FILE: &str = "partial.json";

/// The format tag a partial carries (a newer pinsight that changes the
/// partial changes the tag, and an old merge refuses it).
pub const FORMAT: &str = "pinsight-yield-partial/1";

/// The largest partial read (a shard of ~10⁶ images with their pins).
pub const PARTIAL_MAX_BYTES: u64 = 8 << 30;

/// What one shard hands to the merge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct YieldPartial {
    pub format: String,
    pub shard: Shard,
    /// Distinct units of the whole batch and the digest of their names.
    pub units: u64,
    pub digest: String,
    /// The report's title (the recipes' part numbers).
    pub title: String,
    pub aggregate: YieldAcc,
    /// This shard's items, in batch order.
    pub items: Vec<ItemRecord>,
}

/// A merged batch: the report and the items in batch order.
#[derive(Debug, Clone)]
pub struct Merged {
    pub report: YieldReport,
    pub items: Vec<ItemRecord>,
    pub title: String,
    pub shards: u32,
}

/// Reads a partial from its file or from the shard's output folder.
pub fn read_partial(path: &Path) -> Result<YieldPartial, String> {
    let file = if path.is_dir() {
        path.join(PARTIAL_FILE)
    } else {
        path.to_path_buf()
    };
    // A device (`/dev/zero`) never ends: only a regular file is a partial.
    match std::fs::metadata(&file) {
        Ok(m) if !m.is_file() => return Err(format!("{}: not a regular file", file.display())),
        Err(e) => return Err(format!("{}: {e}", file.display())),
        Ok(_) => {}
    }
    let bytes = crate::input::read_bounded(&file, PARTIAL_MAX_BYTES)
        .map_err(|e| format!("{}: {e}", file.display()))?;
    let p: YieldPartial = serde_json::from_slice(&bytes)
        .map_err(|e| format!("{}: not a pinsight partial result: {e}", file.display()))?;
    if p.format != FORMAT {
        return Err(format!(
            "{}: partial format `{}`, this pinsight merges `{FORMAT}`",
            file.display(),
            p.format
        ));
    }
    Ok(p)
}

/// Merges one job's partials (each named by where it came from).
pub fn merge(partials: &[(String, YieldPartial)]) -> Result<Merged, String> {
    let Some((first_src, first)) = partials.first() else {
        return Err("nothing to merge".into());
    };
    let n = first.shard.n;
    let mut seen: Vec<Option<&str>> = vec![None; n as usize];
    for (src, p) in partials {
        let differs = |what: &str, a: &dyn std::fmt::Display, b: &dyn std::fmt::Display| {
            format!("{src}: {what} {a} differs from {first_src}'s {b}: not shards of one job")
        };
        if p.shard.n != n {
            return Err(differs("shard count", &p.shard.n, &n));
        }
        if p.digest != first.digest || p.units != first.units {
            return Err(differs(
                "input list",
                &format!("({} units)", p.units),
                &format!("({} units)", first.units),
            ));
        }
        if p.title != first.title {
            return Err(differs("title", &p.title, &first.title));
        }
        if p.aggregate.group_by != first.aggregate.group_by {
            return Err(differs(
                "grouping",
                &format!("{:?}", p.aggregate.group_by),
                &format!("{:?}", first.aggregate.group_by),
            ));
        }
        let slot = &mut seen[p.shard.k as usize];
        if let Some(other) = slot {
            return Err(format!("shard {} given twice: {other} and {src}", p.shard));
        }
        *slot = Some(src);
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(k, _)| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "shard(s) {} missing: a merge needs every shard of the job",
            missing.join(", ")
        ));
    }
    let mut acc = first.aggregate.clone();
    for (_, p) in &partials[1..] {
        acc.merge(&p.aggregate);
    }
    let mut items: Vec<ItemRecord> = partials
        .iter()
        .flat_map(|(_, p)| p.items.iter().cloned())
        .collect();
    items.sort_by_key(|r| r.order);
    if let Some(w) = items.windows(2).find(|w| w[0].order == w[1].order) {
        return Err(format!(
            "two items at place {} of the batch: the partials overlap",
            w[0].order
        ));
    }
    Ok(Merged {
        report: acc.report(),
        items,
        title: first.title.clone(),
        shards: n,
    })
}
