//! `yield` at plant scale: the files of a yield folder (report, per-item
//! outputs, Parquet tables) for a single run, a shard and a merge alike,
//! a shard's partial, and the exact merge of a job's partials.
//!
//! A shard's `partial.json` holds the mergeable aggregate of its items
//! ([`YieldAcc`]: counts for the yield and its Wilson interval, DPPM, the
//! Pareto, the groups, per-position counts and exact offset sums) and an
//! index of its items: each item's place in the whole batch and the byte
//! lengths of its lines in the shard's own `yield.json`, `items.csv` and
//! `pins.csv`; the Parquet rows carry their place (`item`) themselves.
//! The merge reads those files (checked against their size and CRC-32),
//! adds the aggregates, interleaves the items back into batch order and
//! builds the folder with the very functions a single run uses: the
//! merged folder is the single run's, byte for byte
//! (`tests/plant/shard.rs`, `tests/plant/parquet.rs`).

use super::partial::{FileCheck, FolderFiles, Found, Header, Partial};
use crate::export::parquet::yield_tables::{
    IMAGES, PINS, images_schema, pins_schema, yield_tables,
};
use crate::export::parquet::{PartitionKey, hive, partition_file_name, table_files};
use crate::vision::batch::{ItemResult, RecipeBook};
use crate::vision::report::{
    GroupBy, ItemFiles, ItemLines, ItemRecord, YIELD_JSON_ITEM_SEP, YIELD_JSON_ITEMS, YieldReport,
    csv_headers, yield_files,
};
use crate::vision::yield_acc::YieldAcc;
use arrow_array::RecordBatch;
use arrow_array::cast::AsArray;
use arrow_array::types::UInt64Type;
use arrow_schema::SchemaRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// What a yield folder holds besides the report.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct YieldOutputs {
    pub files: ItemFiles,
    /// The Parquet tables, partitioned by these keys (none: one file each);
    /// `None`: no Parquet.
    pub parquet: Option<Vec<PartitionKey>>,
}

impl YieldOutputs {
    /// Parses `--items` (`json,csv,parquet`, any of them, or `none`).
    pub fn parse_items(s: &str) -> Result<YieldOutputs, String> {
        let mut o = YieldOutputs {
            files: ItemFiles {
                json: false,
                csv: false,
            },
            parquet: None,
        };
        for w in s.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            match w {
                "json" => o.files.json = true,
                "csv" => o.files.csv = true,
                "parquet" => o.parquet = Some(Vec::new()),
                "none" => {}
                other => {
                    return Err(format!(
                        "--items `{other}`: expected json, csv, parquet or none"
                    ));
                }
            }
        }
        Ok(o)
    }

    /// The Parquet folder names this folder does not write (so an earlier
    /// run's are removed): both forms when there is no Parquet.
    fn stale(&self) -> Vec<String> {
        let mut v = Vec::new();
        for t in [IMAGES, PINS] {
            match &self.parquet {
                None => {
                    v.push(format!("{t}.parquet"));
                    v.push(t.to_string());
                }
                Some(k) if k.is_empty() => v.push(t.to_string()),
                Some(_) => v.push(format!("{t}.parquet")),
            }
        }
        v
    }
}

/// The settings every shard of a yield job must share, in words: the
/// recipes (their whole content), the grouping and the outputs.
pub fn settings_text(book: &RecipeBook, by: GroupBy, outs: &YieldOutputs) -> String {
    let recipes = serde_json::to_string(&book.recipes).unwrap_or_default();
    format!(
        "recipes {} ({} unusable: {}); by {by:?}; outputs {}; content {recipes}",
        book.recipes
            .iter()
            .map(|r| r.part_number.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        book.invalid.len(),
        book.invalid.join("; "),
        serde_json::to_string(outs).unwrap_or_default(),
    )
}

/// One item of a shard: its place in the batch and the byte lengths of
/// its lines in the shard's files (0 where the file is not written).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ItemIndex {
    pub order: u64,
    pub json: u64,
    pub csv: u64,
    pub pins: u64,
}

/// A yield shard's partial (after the [`Header`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct YieldBody {
    pub title: String,
    pub outputs: YieldOutputs,
    pub aggregate: YieldAcc,
    pub items: Vec<ItemIndex>,
    /// The files of the shard's folder the merge reads.
    pub checks: Vec<FileCheck>,
}

/// The files of a yield folder as (name, bytes) — names may be paths
/// below the folder — and the entries an earlier run left that this one
/// does not write. `results` in batch order, each with its place in the
/// whole batch (`orders`; 0, 1, 2 … for a whole run). With `shard` (the
/// header of a shard of a job), also `partial.json`.
pub fn yield_folder(
    report: &YieldReport,
    results: &[ItemResult],
    orders: &[u64],
    title: &str,
    outputs: &YieldOutputs,
    shard: Option<(Header, YieldAcc)>,
) -> Result<FolderFiles, String> {
    let records = results
        .iter()
        .zip(orders)
        .map(|(r, &o)| ItemRecord::of(o, r))
        .collect::<Result<Vec<_>, _>>()?;
    let lines: Vec<ItemLines> = records.iter().map(ItemRecord::lines).collect();
    let mut files = yield_files(report, &lines, outputs.files, title)?;
    let parquet_from = files.len();
    if let Some(keys) = &outputs.parquet {
        let (images, pins) =
            yield_tables(orders.iter().copied().zip(results)).map_err(|e| e.to_string())?;
        let file = shard.as_ref().map_or_else(
            || partition_file_name(0, 1),
            |(h, _)| partition_file_name(h.shard.k, h.shard.n),
        );
        for (name, batch) in [(IMAGES, &images), (PINS, &pins)] {
            files.extend(table_files(name, batch, keys, &file).map_err(|e| e.to_string())?);
        }
    }
    if let Some((header, aggregate)) = shard {
        let f = outputs.files;
        let items = records
            .iter()
            .map(|r| ItemIndex {
                order: r.order,
                json: if f.json { r.json.len() as u64 } else { 0 },
                csv: if f.csv { r.csv.len() as u64 } else { 0 },
                pins: if f.csv { r.pins_csv.len() as u64 } else { 0 },
            })
            .collect();
        let read = |n: &str| {
            (n == "yield.json" && f.json) || ((n == "items.csv" || n == "pins.csv") && f.csv)
        };
        let checks = files
            .iter()
            .enumerate()
            .filter(|(i, (n, _))| read(n) || *i >= parquet_from)
            .map(|(_, (n, b))| FileCheck::of(n, b))
            .collect();
        let partial = Partial {
            header,
            body: YieldBody {
                title: title.to_string(),
                outputs: outputs.clone(),
                aggregate,
                items,
                checks,
            },
        };
        let bytes = serde_json::to_vec(&partial).map_err(|e| e.to_string())?;
        files.push((super::partial::PARTIAL_FILE.to_string(), bytes));
    }
    Ok((files, outputs.stale()))
}

/// A merged yield: its folder's files and the report.
pub struct MergedYield {
    pub report: YieldReport,
    pub files: Vec<(String, Vec<u8>)>,
    pub remove: Vec<String>,
}

/// Where each item's lines start in one shard's files.
struct ShardText {
    json: Vec<u8>,
    csv: Vec<u8>,
    pins: Vec<u8>,
}

/// Cuts a shard's files into its items' lines (by the index's lengths),
/// each checked to land where the file's layout says.
fn slice_items<'a>(
    found: &Found,
    body: &YieldBody,
    text: &'a ShardText,
) -> Result<Vec<ItemLines<'a>>, String> {
    let f = body.outputs.files;
    let bad = |file: &str, what: &str| {
        format!(
            "{}: {what} does not match its partial.json's index of items",
            found.dir.join(file).display()
        )
    };
    let as_str = |b: &'a [u8], file: &str| {
        std::str::from_utf8(b).map_err(|_| bad(file, "the text is not UTF-8"))
    };
    let json = as_str(&text.json, "yield.json")?;
    let csv = as_str(&text.csv, "items.csv")?;
    let pins = as_str(&text.pins, "pins.csv")?;
    let mut jp = if f.json {
        let at = json
            .find(YIELD_JSON_ITEMS)
            .ok_or_else(|| bad("yield.json", "the items list"))?;
        at + YIELD_JSON_ITEMS.len() + "\n    ".len()
    } else {
        0
    };
    let (ch, ph) = csv_headers();
    let (mut cp, mut pp) = if f.csv { (ch.len(), ph.len()) } else { (0, 0) };
    let mut out = Vec::with_capacity(body.items.len());
    let take = |s: &'a str, at: &mut usize, n: u64, file: &str| -> Result<&'a str, String> {
        let end = at
            .checked_add(n as usize)
            .filter(|&e| e <= s.len() && s.is_char_boundary(*at) && s.is_char_boundary(e))
            .ok_or_else(|| bad(file, "its length"))?;
        let piece = &s[*at..end];
        *at = end;
        Ok(piece)
    };
    for (i, it) in body.items.iter().enumerate() {
        let j = if f.json {
            if i > 0 {
                let sep = take(
                    json,
                    &mut jp,
                    YIELD_JSON_ITEM_SEP.len() as u64,
                    "yield.json",
                )?;
                if sep != YIELD_JSON_ITEM_SEP {
                    return Err(bad("yield.json", "the items list"));
                }
            }
            take(json, &mut jp, it.json, "yield.json")?
        } else {
            ""
        };
        let c = take(csv, &mut cp, it.csv, "items.csv")?;
        let p = take(pins, &mut pp, it.pins, "pins.csv")?;
        out.push(ItemLines {
            json: j,
            csv: c,
            pins_csv: p,
        });
    }
    if f.csv && (cp != csv.len() || pp != pins.len()) {
        return Err(bad("items.csv / pins.csv", "the number of rows"));
    }
    Ok(out)
}

/// The rows of one table from every shard's Parquet files (as checked),
/// in batch order (`item`; rows of one item keep their order).
///
/// Each file is a run already in batch order (a shard writes its rows in
/// its items' order; a partition file keeps that order), so the runs are
/// read in parallel and merged k-way by `item` into one list of (run,
/// row) that `interleave` copies once: no sort of every row, no
/// intermediate concatenation. A run out of order is refused.
fn merged_table(
    shards: &[(&Found, &YieldBody)],
    name: &str,
    schema: &SchemaRef,
) -> Result<RecordBatch, String> {
    let mut files = Vec::new();
    for (found, body) in shards {
        for c in &body.checks {
            let rel = if c.name == format!("{name}.parquet") {
                None
            } else if let Some(rest) = c.name.strip_prefix(&format!("{name}/")) {
                Some(rest.rsplit_once('/').map_or("", |(d, _)| d))
            } else {
                continue;
            };
            files.push((found.dir.join(&c.name), rel));
        }
    }
    let runs: Vec<RecordBatch> = files
        .par_iter()
        .map(|(path, rel)| {
            match rel {
                None => crate::export::parquet::read_file(path, schema),
                Some(rel) => hive::read_partition_file(path, rel, schema),
            }
            .map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    let items: Vec<&[u64]> = runs
        .iter()
        .map(|b| b.column(0).as_primitive::<UInt64Type>().values().as_ref())
        .collect();
    let mut heap: BinaryHeap<Reverse<(u64, usize)>> = items
        .iter()
        .enumerate()
        .filter_map(|(r, it)| it.first().map(|&v| Reverse((v, r))))
        .collect();
    let mut at = vec![0usize; runs.len()];
    let mut idx = Vec::with_capacity(items.iter().map(|i| i.len()).sum());
    while let Some(Reverse((v, r))) = heap.pop() {
        let it = items[r];
        let mut i = at[r];
        while i < it.len() && it[i] == v {
            idx.push((r, i));
            i += 1;
        }
        at[r] = i;
        if let Some(&next) = it.get(i) {
            if next < v {
                return Err(format!(
                    "{}: its rows are not in batch order (item {next} after {v}): not a shard's table",
                    files[r].0.display()
                ));
            }
            heap.push(Reverse((next, r)));
        }
    }
    if runs.is_empty() {
        return Ok(RecordBatch::new_empty(schema.clone()));
    }
    let refs: Vec<&RecordBatch> = runs.iter().collect();
    arrow_select::interleave::interleave_record_batch(&refs, &idx).map_err(|e| e.to_string())
}

/// The merged Parquet tables' files (none without `--items parquet`):
/// the shards' rows in batch order, written as a single run writes them.
fn merged_tables(
    set: &[(&Found, Partial<YieldBody>)],
    outputs: &YieldOutputs,
    order: &[(u64, usize, usize)],
) -> Result<Vec<(String, Vec<u8>)>, String> {
    let Some(keys) = &outputs.parquet else {
        return Ok(Vec::new());
    };
    let shards: Vec<(&Found, &YieldBody)> = set.iter().map(|(f, p)| (*f, &p.body)).collect();
    let (images, pins) = rayon::join(
        || merged_table(&shards, IMAGES, &images_schema()),
        || merged_table(&shards, PINS, &pins_schema()),
    );
    let (images, pins) = (images?, pins?);
    let want = order.iter().map(|o| o.0);
    let have = images.column(0).as_primitive::<UInt64Type>().values();
    if have.len() != order.len() || !have.iter().copied().eq(want) {
        return Err(
            "the shards' images tables do not hold exactly the items their partials index".into(),
        );
    }
    let file = partition_file_name(0, 1);
    let (a, b) = rayon::join(
        || table_files(IMAGES, &images, keys, &file),
        || table_files(PINS, &pins, keys, &file),
    );
    let mut files = a.map_err(|e| e.to_string())?;
    files.extend(b.map_err(|e| e.to_string())?);
    Ok(files)
}

/// Merges one job's yield partials (checked to be one complete set, in
/// shard order): the merged folder's files.
pub fn merge_yield(set: &[(&Found, Partial<YieldBody>)]) -> Result<MergedYield, String> {
    let (f0, p0) = set.first().ok_or("nothing to merge")?;
    for (f, p) in set {
        if p.body.title != p0.body.title || p.body.outputs != p0.body.outputs {
            return Err(format!(
                "{}: its report's title or outputs differ from {}'s: not shards of one job",
                f.shown, f0.shown
            ));
        }
        if p.body.aggregate.group_by != p0.body.aggregate.group_by {
            return Err(format!(
                "{}: grouped by {:?}, {} by {:?}: not shards of one job",
                f.shown, p.body.aggregate.group_by, f0.shown, p0.body.aggregate.group_by
            ));
        }
    }
    // Every file is read and checked before anything is merged.
    let texts = set
        .par_iter()
        .map(|(f, p)| {
            let mut t = ShardText {
                json: Vec::new(),
                csv: Vec::new(),
                pins: Vec::new(),
            };
            for c in &p.body.checks {
                match c.name.as_str() {
                    "yield.json" => t.json = c.read(&f.dir)?,
                    "items.csv" => t.csv = c.read(&f.dir)?,
                    "pins.csv" => t.pins = c.read(&f.dir)?,
                    _ => c.verify(&f.dir)?,
                }
            }
            Ok(t)
        })
        .collect::<Result<Vec<_>, String>>()?;
    let outputs = p0.body.outputs.clone();
    let mut slices = Vec::with_capacity(set.len());
    for ((f, p), t) in set.iter().zip(&texts) {
        slices.push(slice_items(f, &p.body, t)?);
    }
    let mut order: Vec<(u64, usize, usize)> = set
        .iter()
        .enumerate()
        .flat_map(|(s, (_, p))| {
            p.body
                .items
                .iter()
                .enumerate()
                .map(move |(i, it)| (it.order, s, i))
        })
        .collect();
    order.sort_unstable();
    if let Some(w) = order.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "{} and {} both hold the item at place {} of the batch: the partials overlap",
            set[w[0].1].0.shown, set[w[1].1].0.shown, w[0].0
        ));
    }
    let mut acc = p0.body.aggregate.clone();
    for (_, p) in &set[1..] {
        acc.merge(&p.body.aggregate);
    }
    if acc.items != order.len() as u64 {
        return Err(format!(
            "the partials count {} items but index {}: a corrupt partial",
            acc.items,
            order.len()
        ));
    }
    let report = acc.report();
    let lines: Vec<ItemLines> = order.iter().map(|&(_, s, i)| slices[s][i]).collect();
    // The report's files (text, charts) and the tables are independent:
    // built side by side.
    let (files, tables) = rayon::join(
        || yield_files(&report, &lines, outputs.files, &p0.body.title),
        || merged_tables(set, &outputs, &order),
    );
    let mut files = files?;
    files.extend(tables?);
    Ok(MergedYield {
        report,
        files,
        remove: outputs.stale(),
    })
}
