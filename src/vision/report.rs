//! Batch yield: the statistics of a set of inspected items, as plain data
//! (the TUI's Yield pane draws it; `pinsight yield` writes it as JSON, CSV,
//! Markdown and PNG charts).
//!
//! - Yield = passed / inspected connectors; items that could not be read or
//!   analysed are `error`, not inspected, and are listed beside the yield.
//! - 95 % confidence intervals are Wilson score intervals (good coverage for
//!   small n and for yields near 0 or 1, where the normal approximation
//!   fails; never outside [0, 1]).
//! - Defects per million pins (DPPM) = defective pins / inspected pins × 10⁶
//!   (extras are not pins: they are counted in the Pareto, not in DPPM).

use super::batch::{ItemResult, ItemStatus};
use crate::plot::{Band, BarChart, LineChart, Panel, Series, SeriesStyle};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// Two-sided 95 % normal quantile.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Wilson score interval for k successes in n trials (z = 1.96 for 95 %).
/// n = 0 gives the uninformative [0, 1].
pub fn wilson(k: u64, n: u64, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n_f = n as f64;
    let p = k as f64 / n_f;
    let z2 = z * z;
    let denom = 1.0 + z2 / n_f;
    let centre = (p + z2 / (2.0 * n_f)) / denom;
    let half = z * (p * (1.0 - p) / n_f + z2 / (4.0 * n_f * n_f)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Grouping of the yield table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum GroupBy {
    #[default]
    Lot,
    Part,
    Rig,
    Speed,
}

/// Yield of one group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupYield {
    pub key: String,
    /// Numeric key (speed in rpm, clearance in mm) when the grouping has one.
    pub value: Option<f64>,
    pub inspected: u64,
    pub passed: u64,
    pub errors: u64,
    pub yield_frac: Option<f64>,
    pub ci95: (f64, f64),
}

/// One defect kind in the Pareto.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParetoRow {
    pub kind: String,
    pub count: u64,
    pub share: f64,
    pub cumulative: f64,
}

/// Defect statistics of one grid position.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PositionStats {
    pub part_number: String,
    pub row: u32,
    pub col: u32,
    pub inspected: u64,
    pub defects: u64,
    pub rate: f64,
    pub missing: u64,
    pub damaged: u64,
    pub bent: u64,
    pub short: u64,
    pub high: u64,
    /// Mean and largest |offset| of the pins found there, mm.
    pub mean_offset_mm: Option<f64>,
    pub max_offset_mm: Option<f64>,
}

/// An item that could not be inspected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorRow {
    pub name: String,
    pub kind: super::error::ErrorKind,
    pub message: String,
}

/// The whole batch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct YieldReport {
    pub items: u64,
    pub inspected: u64,
    pub passed: u64,
    pub failed: u64,
    pub errors: u64,
    pub yield_frac: Option<f64>,
    pub ci95: (f64, f64),
    pub ci_method: String,
    pub pins_inspected: u64,
    pub defective_pins: u64,
    pub dppm: Option<f64>,
    pub dppm_ci95: (f64, f64),
    pub extras: u64,
    pub connectors_with_extras: u64,
    pub pareto: Vec<ParetoRow>,
    pub group_by: GroupBy,
    pub groups: Vec<GroupYield>,
    /// Yield against the motor speed set-point (rig-log images only).
    pub by_speed: Vec<GroupYield>,
    /// Yield against the joint clearance (rig-log images only).
    pub by_clearance: Vec<GroupYield>,
    /// Positions sorted by defect count (then mean offset), all of them.
    pub worst_pins: Vec<PositionStats>,
    pub error_list: Vec<ErrorRow>,
}

pub(crate) fn fmt_num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e12 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

pub(crate) fn group_key(r: &ItemResult, by: GroupBy) -> (String, Option<f64>) {
    let m = &r.meta;
    match by {
        GroupBy::Lot => (m.lot.clone().unwrap_or_else(|| "(no lot)".into()), None),
        GroupBy::Part => (
            m.part_number.clone().unwrap_or_else(|| "(no part)".into()),
            None,
        ),
        GroupBy::Rig => (m.rig_id.clone().unwrap_or_else(|| "(no rig)".into()), None),
        GroupBy::Speed => match m.motor_rpm {
            Some(v) => (format!("{} rpm", fmt_num(v)), Some(v)),
            None => ("(no speed)".into(), None),
        },
    }
}

impl YieldReport {
    /// One line for the terminal: counts and the yield with its interval.
    pub fn summary_line(&self) -> String {
        let y = self
            .yield_frac
            .map(|y| {
                format!(
                    "{:.2} % (95 % CI {:.2} – {:.2} %)",
                    100.0 * y,
                    100.0 * self.ci95.0,
                    100.0 * self.ci95.1
                )
            })
            .unwrap_or_else(|| "n/a".into());
        format!(
            "{} items: {} inspected, {} passed, {} failed, {} errors; yield {y}",
            self.items, self.inspected, self.passed, self.failed, self.errors
        )
    }

    /// Chart panels: Pareto, yield by group, worst positions, and yield
    /// against speed and clearance when known.
    pub fn panels(&self) -> Vec<(String, Panel)> {
        let mut out = Vec::new();
        out.push((
            "pareto".to_string(),
            Panel::Bar(BarChart {
                title: "Defects by kind (Pareto)".into(),
                x_label: "kind".into(),
                y_label: "count".into(),
                categories: self.pareto.iter().map(|p| p.kind.clone()).collect(),
                series: vec![(
                    "defects".into(),
                    self.pareto.iter().map(|p| p.count as f64).collect(),
                )],
                errors: None,
            }),
        ));
        // The Wilson interval is asymmetric: its ends are drawn as bars of
        // their own beside the yield rather than as symmetric whiskers.
        let group_bar = |title: String, groups: &[GroupYield]| {
            Panel::Bar(BarChart {
                title,
                x_label: "group".into(),
                y_label: "yield".into(),
                categories: groups.iter().map(|g| g.key.clone()).collect(),
                series: vec![
                    (
                        "95 % CI low".into(),
                        groups.iter().map(|g| g.ci95.0).collect(),
                    ),
                    (
                        "yield".into(),
                        groups
                            .iter()
                            .map(|g| g.yield_frac.unwrap_or(f64::NAN))
                            .collect(),
                    ),
                    (
                        "95 % CI high".into(),
                        groups.iter().map(|g| g.ci95.1).collect(),
                    ),
                ],
                errors: None,
            })
        };
        if !self.groups.is_empty() {
            out.push((
                "yield_by_group".to_string(),
                group_bar(
                    format!(
                        "Yield by {} with its 95 % Wilson interval",
                        format!("{:?}", self.group_by).to_lowercase()
                    ),
                    &self.groups,
                ),
            ));
        }
        let top: Vec<&PositionStats> = self
            .worst_pins
            .iter()
            .filter(|p| p.defects > 0)
            .take(10)
            .collect();
        if !top.is_empty() {
            out.push((
                "worst_pins".to_string(),
                Panel::Bar(BarChart {
                    title: "Worst pin positions (defect rate)".into(),
                    x_label: "row,col".into(),
                    y_label: "defects / inspected".into(),
                    categories: top.iter().map(|p| format!("{},{}", p.row, p.col)).collect(),
                    series: vec![("rate".into(), top.iter().map(|p| p.rate).collect())],
                    errors: None,
                }),
            ));
        }
        let curve = |title: &str, x_label: &str, g: &[GroupYield]| {
            let pts: Vec<(f64, f64)> = g
                .iter()
                .filter_map(|g| Some((g.value?, g.yield_frac?)))
                .collect();
            let with_y: Vec<&GroupYield> = g
                .iter()
                .filter(|g| g.value.is_some() && g.yield_frac.is_some())
                .collect();
            Panel::Line(LineChart {
                title: title.into(),
                x_label: x_label.into(),
                y_label: "yield".into(),
                series: vec![Series::line("yield", pts).with_style(SeriesStyle::LinePoints)],
                bands: vec![Band {
                    label: "95 % Wilson".into(),
                    x: with_y.iter().filter_map(|g| g.value).collect(),
                    lower: with_y.iter().map(|g| g.ci95.0).collect(),
                    upper: with_y.iter().map(|g| g.ci95.1).collect(),
                    color: None,
                }],
                y_range: Some((0.0, 1.0)),
                ..Default::default()
            })
        };
        if !self.by_speed.is_empty() {
            out.push((
                "yield_by_speed".to_string(),
                curve(
                    "Yield against motor speed",
                    "motor speed (rpm)",
                    &self.by_speed,
                ),
            ));
        }
        if !self.by_clearance.is_empty() {
            out.push((
                "yield_by_clearance".to_string(),
                curve(
                    "Yield against joint clearance",
                    "clearance (mm)",
                    &self.by_clearance,
                ),
            ));
        }
        out
    }

    /// The Markdown report; `charts` are (title, file name) of PNGs written beside it.
    pub fn markdown(&self, title: &str, charts: &[(String, String)]) -> String {
        let mut s = String::new();
        let pct = |v: f64| format!("{:.2} %", 100.0 * v);
        let _ = writeln!(s, "# {title}\n");
        let _ = writeln!(s, "| | |\n|---|---|");
        let _ = writeln!(s, "| items | {} |", self.items);
        let _ = writeln!(s, "| inspected connectors | {} |", self.inspected);
        let _ = writeln!(s, "| passed | {} |", self.passed);
        let _ = writeln!(s, "| failed | {} |", self.failed);
        let _ = writeln!(s, "| errors (not inspected) | {} |", self.errors);
        match self.yield_frac {
            Some(y) => {
                let _ = writeln!(
                    s,
                    "| yield | {} (95 % CI {} – {}, {}) |",
                    pct(y),
                    pct(self.ci95.0),
                    pct(self.ci95.1),
                    self.ci_method
                );
            }
            None => {
                let _ = writeln!(s, "| yield | n/a (nothing inspected) |");
            }
        }
        let _ = writeln!(s, "| pins inspected | {} |", self.pins_inspected);
        if let Some(d) = self.dppm {
            let _ = writeln!(
                s,
                "| defective pins | {} ({:.0} per million, 95 % CI {:.0} – {:.0}) |",
                self.defective_pins, d, self.dppm_ci95.0, self.dppm_ci95.1
            );
        }
        let _ = writeln!(
            s,
            "| extras | {} on {} connectors |\n",
            self.extras, self.connectors_with_extras
        );
        let _ = writeln!(
            s,
            "## Defects by kind (Pareto)\n\n| kind | count | share | cumulative |\n|---|---:|---:|---:|"
        );
        for p in &self.pareto {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} |",
                p.kind,
                p.count,
                pct(p.share),
                pct(p.cumulative)
            );
        }
        let table = |s: &mut String, title: &str, g: &[GroupYield]| {
            let _ = writeln!(
                s,
                "\n## {title}\n\n| group | inspected | passed | errors | yield | 95 % CI |\n|---|---:|---:|---:|---:|---|"
            );
            for g in g {
                let y = g.yield_frac.map(pct).unwrap_or_else(|| "n/a".into());
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} – {} |",
                    g.key,
                    g.inspected,
                    g.passed,
                    g.errors,
                    y,
                    pct(g.ci95.0),
                    pct(g.ci95.1)
                );
            }
        };
        table(
            &mut s,
            &format!("Yield by {}", format!("{:?}", self.group_by).to_lowercase()),
            &self.groups,
        );
        if !self.by_speed.is_empty() {
            table(&mut s, "Yield against motor speed", &self.by_speed);
        }
        if !self.by_clearance.is_empty() {
            table(&mut s, "Yield against joint clearance", &self.by_clearance);
        }
        let _ = writeln!(
            s,
            "\n## Worst pin positions\n\n| part | row | col | inspected | defects | rate | missing | damaged | bent | short | high | mean offset (mm) | max offset (mm) |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        );
        for p in self.worst_pins.iter().take(15) {
            let o = |v: Option<f64>| v.map(|v| format!("{v:.4}")).unwrap_or_else(|| "–".into());
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                p.part_number,
                p.row,
                p.col,
                p.inspected,
                p.defects,
                pct(p.rate),
                p.missing,
                p.damaged,
                p.bent,
                p.short,
                p.high,
                o(p.mean_offset_mm),
                o(p.max_offset_mm)
            );
        }
        let _ = writeln!(s, "\n## Errors ({} items not inspected)\n", self.errors);
        if self.error_list.is_empty() {
            let _ = writeln!(s, "None.");
        } else {
            let _ = writeln!(s, "| item | kind | reason |\n|---|---|---|");
            for e in &self.error_list {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} |",
                    e.name.replace('|', "\\|"),
                    e.kind.as_str(),
                    e.message.replace('|', "\\|")
                );
            }
        }
        if !charts.is_empty() {
            let _ = writeln!(s, "\n## Charts\n");
            for (t, f) in charts {
                let _ = writeln!(s, "![{t}]({f})\n");
            }
        }
        s
    }
}

/// RFC 4180 field quoting.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

const ITEMS_CSV_HEADER: &str = "name,status,part_number,lot,rig_id,motor_rpm,clearance_mm,cycle,ok,missing,damaged,bent,short,high,extras,error_kind,error,failed_because\n";
const PINS_CSV_HEADER: &str = "name,row,col,status,x_px,y_px,nominal_x_px,nominal_y_px,dx_mm,dy_mm,offset_mm,area_ratio,height_mm,reason\n";

/// One row per item.
pub fn items_csv(results: &[ItemResult]) -> String {
    let mut s = String::from(ITEMS_CSV_HEADER);
    for r in results {
        s.push_str(&items_csv_row(r));
    }
    s
}

/// An item's row of `items.csv` (with its line end).
pub fn items_csv_row(r: &ItemResult) -> String {
    let mut s = String::new();
    {
        let m = &r.meta;
        let c = r.inspection.as_ref().map(|i| &i.counts);
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            csv_field(&r.name),
            match r.status {
                ItemStatus::Pass => "pass",
                ItemStatus::Fail => "fail",
                ItemStatus::Error => "error",
            },
            csv_field(&opt(m.part_number.clone())),
            csv_field(&opt(m.lot.clone())),
            csv_field(&opt(m.rig_id.clone())),
            opt(m.motor_rpm),
            opt(m.clearance_mm),
            opt(m.cycle),
            opt(c.map(|c| c.ok)),
            opt(c.map(|c| c.missing)),
            opt(c.map(|c| c.damaged)),
            opt(c.map(|c| c.bent)),
            opt(c.map(|c| c.short)),
            opt(c.map(|c| c.high)),
            opt(r.inspection.as_ref().map(|i| i.extras.len())),
            opt(r.error.as_ref().map(|e| e.kind.as_str())),
            csv_field(&opt(r.error.as_ref().map(|e| e.message.clone()))),
            csv_field(
                &r.inspection
                    .as_ref()
                    .map(|i| i.failed_because.join("; "))
                    .unwrap_or_default()
            ),
        );
    }
    s
}

/// One row per inspected pin.
pub fn pins_csv(results: &[ItemResult]) -> String {
    let mut s = String::from(PINS_CSV_HEADER);
    for r in results {
        s.push_str(&pins_csv_rows(r));
    }
    s
}

/// An item's rows of `pins.csv` (with their line ends; none without an
/// inspection).
pub fn pins_csv_rows(r: &ItemResult) -> String {
    let mut s = String::new();
    let f = |v: Option<f64>, d: usize| v.map(|v| format!("{v:.d$}")).unwrap_or_default();
    {
        let Some(ins) = &r.inspection else { return s };
        for p in &ins.pins {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{:.3},{:.3},{},{},{},{},{},{}",
                csv_field(&r.name),
                p.row,
                p.col,
                p.status.as_str(),
                f(p.x_px, 3),
                f(p.y_px, 3),
                p.nominal_x_px,
                p.nominal_y_px,
                f(p.dx_mm, 5),
                f(p.dy_mm, 5),
                f(p.offset_mm, 5),
                f(p.area_ratio, 4),
                f(p.height_mm, 5),
                csv_field(p.reason.as_deref().unwrap_or("")),
            );
        }
    }
    s
}

/// One item's part of the per-item outputs (its element of `yield.json`'s
/// `items`, its row of `items.csv`, its rows of `pins.csv`) and where it
/// stands in the batch: what a shard hands to `pinsight merge` besides the
/// aggregate, so the merged files are the single run's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemRecord {
    pub order: u64,
    /// The item as compact JSON.
    pub json: String,
    pub csv: String,
    pub pins_csv: String,
}

impl ItemRecord {
    pub fn of(order: u64, r: &ItemResult) -> Result<Self, String> {
        Ok(ItemRecord {
            order,
            json: serde_json::to_string(r).map_err(|e| e.to_string())?,
            csv: items_csv_row(r),
            pins_csv: pins_csv_rows(r),
        })
    }
}

impl ItemRecord {
    /// The record's lines, borrowed.
    pub fn lines(&self) -> ItemLines<'_> {
        ItemLines {
            json: &self.json,
            csv: &self.csv,
            pins_csv: &self.pins_csv,
        }
    }
}

/// One item's lines of the per-item outputs, borrowed: from an
/// [`ItemRecord`], or sliced from a shard's files by a merge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItemLines<'a> {
    pub json: &'a str,
    pub csv: &'a str,
    pub pins_csv: &'a str,
}

/// Which per-item outputs a report folder holds besides the report: the
/// items in `yield.json`, `items.csv` + `pins.csv`. (Parquet tables are
/// the caller's `extra` files.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ItemFiles {
    pub json: bool,
    pub csv: bool,
}

impl Default for ItemFiles {
    fn default() -> Self {
        ItemFiles {
            json: true,
            csv: true,
        }
    }
}

/// The marker before the first item in `yield.json` (the items' own
/// lines are compact, so it occurs once).
pub const YIELD_JSON_ITEMS: &str = "\n  \"items\": [";

/// Between two items of `yield.json`, and before the first.
pub const YIELD_JSON_ITEM_SEP: &str = ",\n    ";

/// `yield.json`: the report (indented) and the items, one compact JSON
/// object per line, in batch order.
pub fn yield_json(report: &YieldReport, items: &[ItemRecord]) -> Result<String, String> {
    yield_json_lines(report, Some(items.iter().map(|r| r.json.as_str())))
}

/// [`yield_json`] from the items' JSON texts; `None`: the report only
/// (no `items` key: the items are in another form, e.g. Parquet).
pub fn yield_json_lines<'a>(
    report: &YieldReport,
    items: Option<impl Iterator<Item = &'a str>>,
) -> Result<String, String> {
    let rep = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    let mut s = String::from("{\n  \"report\": ");
    s.push_str(&rep.replace('\n', "\n  "));
    let Some(items) = items else {
        s.push_str("\n}\n");
        return Ok(s);
    };
    s.push(',');
    s.push_str(YIELD_JSON_ITEMS);
    let mut any = false;
    for (i, it) in items.enumerate() {
        s.push_str(if i == 0 {
            "\n    "
        } else {
            YIELD_JSON_ITEM_SEP
        });
        s.push_str(it);
        any = true;
    }
    s.push_str(if any { "\n  ]\n}\n" } else { "]\n}\n" });
    Ok(s)
}

/// Writes `yield.json`, `items.csv`, `pins.csv`, the charts and `yield.md`
/// into `dir` (created if needed); returns the files written.
pub fn write_all(
    dir: &Path,
    report: &YieldReport,
    results: &[ItemResult],
    title: &str,
) -> Result<Vec<String>, String> {
    let records = results
        .iter()
        .enumerate()
        .map(|(i, r)| ItemRecord::of(i as u64, r))
        .collect::<Result<Vec<_>, _>>()?;
    write_records(dir, report, &records, title, &[])
}

/// [`write_all`] from the items' records (in batch order), with `extra`
/// files (name, bytes) beside the report.
pub fn write_records(
    dir: &Path,
    report: &YieldReport,
    records: &[ItemRecord],
    title: &str,
    extra: &[(String, Vec<u8>)],
) -> Result<Vec<String>, String> {
    let lines: Vec<ItemLines> = records.iter().map(ItemRecord::lines).collect();
    let mut files = yield_files(report, &lines, ItemFiles::default(), title)?;
    files.extend(extra.iter().cloned());
    write_files(dir, &files, &[])
}

/// The files of a yield folder — of a single run, a shard and a merge
/// alike: `yield.json` (with the items when `files.json`), `items.csv` and
/// `pins.csv` (when `files.csv`), the charts and `yield.md`, as (name,
/// bytes) in that order, the items' lines in batch order.
pub fn yield_files(
    report: &YieldReport,
    lines: &[ItemLines],
    files: ItemFiles,
    title: &str,
) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut out = Vec::new();
    let items = files.json.then(|| lines.iter().map(|l| l.json));
    out.push((
        "yield.json".to_string(),
        yield_json_lines(report, items)?.into_bytes(),
    ));
    if files.csv {
        let mut csv = String::from(ITEMS_CSV_HEADER);
        let mut pins = String::from(PINS_CSV_HEADER);
        for r in lines {
            csv.push_str(r.csv);
            pins.push_str(r.pins_csv);
        }
        out.push(("items.csv".to_string(), csv.into_bytes()));
        out.push(("pins.csv".to_string(), pins.into_bytes()));
    }
    let mut charts = Vec::new();
    for (name, panel) in report.panels() {
        let file = format!("{name}.png");
        let png = crate::plot::render_png(std::slice::from_ref(&panel), 1, 900, 500)
            .map_err(|e| e.to_string())?;
        out.push((file.clone(), png));
        charts.push((name.replace('_', " "), file));
    }
    out.push((
        "yield.md".to_string(),
        report.markdown(title, &charts).into_bytes(),
    ));
    Ok(out)
}

/// The header line of `items.csv` and of `pins.csv` (with its line end).
pub fn csv_headers() -> (&'static str, &'static str) {
    (ITEMS_CSV_HEADER, PINS_CSV_HEADER)
}

/// Writes a report folder's files (names may be paths below `dir`) in one
/// commit (`crate::output::Report`: the old folder is replaced only when
/// all are staged); `remove`: entries of `dir` the commit deletes (an
/// earlier run's outputs this run does not write). Returns the files
/// written.
pub fn write_files(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    remove: &[String],
) -> Result<Vec<String>, String> {
    let mut out = crate::output::Report::new_in(dir).map_err(|e| e.to_string())?;
    for (name, bytes) in files {
        out.add(name, bytes).map_err(|e| e.to_string())?;
    }
    for r in remove {
        out.remove(r);
    }
    Ok(out
        .commit()
        .map_err(|e| e.to_string())?
        .iter()
        .map(|p| p.display().to_string())
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_reference_values() {
        // Reference: Newcombe (1998), Table I, method 3: 81/263 → 0.2553–0.3662,
        // 15/148 → 0.0624–0.1605, 0/20 → 0–0.1611, 1/29 → 0.0061–0.1718.
        let cases = [
            (81, 263, 0.2553, 0.3662),
            (15, 148, 0.0624, 0.1605),
            (0, 20, 0.0, 0.1611),
            (1, 29, 0.0061, 0.1718),
        ];
        for (k, n, lo, hi) in cases {
            let (a, b) = wilson(k, n, Z95);
            assert!(
                (a - lo).abs() < 6e-5 && (b - hi).abs() < 6e-5,
                "{k}/{n}: {a} {b}"
            );
        }
        assert_eq!(wilson(0, 0, Z95), (0.0, 1.0));
        let (a, b) = wilson(20, 20, Z95);
        assert!(b == 1.0 && a > 0.83 && a < 0.84);
    }

    #[test]
    fn csv_quoting() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("plain"), "plain");
    }
}
