//! `monitor`'s results as one table, `cycles`: one row per judged cycle of
//! every log, in log then cycle order (the order of `cycles.csv`).
//!
//! Columns: the log and its lot, the run's part, the cycle's index, start
//! time and measured speed, its verdict (`ok`, `nok`, `not_evaluated`),
//! the reasons, how many objects failed and the largest amount by which
//! one did (in that object's unit), every value check's value (a column
//! `value_<name>` per characteristic of the run's SPC, as `cycles.csv`),
//! and, when the connector's photograph was judged (`-r`), its verdict and
//! the model band's residuals (`--band`).

use crate::process::monitor::CycleStatus;
use crate::process::run::MonitorRun;
use crate::process::story::ConnectorStory;
use crate::vision::batch::ItemStatus;
use arrow_array::builder::{
    Float64Builder, StringBuilder, TimestampNanosecondBuilder, UInt32Builder, UInt64Builder,
};
use arrow_array::{ArrayRef, RecordBatch};
use arrow_schema::{DataType, Field, Schema, TimeUnit};
use std::collections::BTreeMap;
use std::sync::Arc;

/// The file (or partitioned folder) name.
pub const CYCLES: &str = "cycles";

/// A value check's column name: `value_` and its name, with characters
/// other than letters, digits and `_` as `_`.
pub fn value_column(name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("value_{clean}")
}

/// The table of a run's cycles.
pub fn cycles_table(run: &MonitorRun) -> Result<RecordBatch, arrow_schema::ArrowError> {
    let names: Vec<String> = run.spc.iter().map(|c| c.name.clone()).collect();
    let mut columns: Vec<String> = Vec::new();
    for n in &names {
        let mut c = value_column(n);
        // Two names that clean to one column keep both, numbered.
        let mut k = 2;
        while columns.contains(&c) {
            c = format!("{}_{k}", value_column(n));
            k += 1;
        }
        columns.push(c);
    }
    let ts = DataType::Timestamp(TimeUnit::Nanosecond, Some("UTC".into()));
    let mut fields = vec![
        Field::new("log", DataType::Utf8, false),
        Field::new("lot", DataType::Utf8, true),
        Field::new("part", DataType::Utf8, false),
        Field::new("cycle", DataType::UInt64, false),
        Field::new("t_start", ts, false),
        Field::new("motor_rpm", DataType::Float64, false),
        Field::new("status", DataType::Utf8, false),
        Field::new("reasons", DataType::Utf8, true),
        Field::new("failed_objects", DataType::UInt32, false),
        Field::new("worst_by", DataType::Float64, true),
    ];
    fields.extend(
        columns
            .iter()
            .map(|c| Field::new(c, DataType::Float64, true)),
    );
    fields.extend([
        Field::new("vision", DataType::Utf8, true),
        Field::new("stroke_in_band", DataType::Float64, true),
        Field::new("force_in_band", DataType::Float64, true),
        Field::new("stroke_rms_err_mm", DataType::Float64, true),
        Field::new("stroke_err_bdc_mm", DataType::Float64, true),
    ]);
    let schema = Arc::new(Schema::new(fields));

    let (mut log, mut lot, mut part) = (
        StringBuilder::new(),
        StringBuilder::new(),
        StringBuilder::new(),
    );
    let mut cycle = UInt64Builder::new();
    let mut t_start = TimestampNanosecondBuilder::new().with_timezone("UTC");
    let mut rpm = Float64Builder::new();
    let (mut status, mut reasons) = (StringBuilder::new(), StringBuilder::new());
    let mut failed = UInt32Builder::new();
    let mut worst = Float64Builder::new();
    let mut values: Vec<Float64Builder> = names.iter().map(|_| Float64Builder::new()).collect();
    let mut vision = StringBuilder::new();
    let mut band: Vec<Float64Builder> = (0..4).map(|_| Float64Builder::new()).collect();
    for l in &run.logs {
        let Ok(r) = &l.report else { continue };
        let stories: BTreeMap<u64, &ConnectorStory> = l
            .story
            .iter()
            .flat_map(|s| &s.connectors)
            .map(|c| (c.cycle, c))
            .collect();
        for c in &r.cycles {
            log.append_value(&l.file);
            lot.append_option(l.lot.as_deref());
            part.append_value(&run.part_number);
            cycle.append_value(c.index);
            t_start.append_value(c.t_start_ns);
            rpm.append_value(c.motor_rpm);
            status.append_value(match c.status {
                CycleStatus::Ok => "ok",
                CycleStatus::Nok => "nok",
                CycleStatus::NotEvaluated => "not_evaluated",
            });
            let why = c.reasons();
            reasons.append_option((!why.is_empty()).then(|| why.join("; ")));
            failed.append_value(c.failed.len() as u32);
            worst.append_option(c.failed.iter().map(|f| f.by).reduce(f64::max));
            for (b, n) in values.iter_mut().zip(&names) {
                b.append_option(c.values.get(n).copied());
            }
            let s = stories.get(&c.index);
            vision.append_option(s.and_then(|s| s.vision).map(|v| match v {
                ItemStatus::Pass => "pass",
                ItemStatus::Fail => "fail",
                ItemStatus::Error => "error",
            }));
            let b = s.and_then(|s| s.band);
            let vals = [
                b.map(|b| b.stroke_in_band),
                b.map(|b| b.force_in_band),
                b.map(|b| b.stroke_rms_err_mm),
                b.map(|b| b.stroke_err_bdc_mm),
            ];
            for (bb, v) in band.iter_mut().zip(vals) {
                bb.append_option(v);
            }
        }
    }
    let mut cols: Vec<ArrayRef> = vec![
        Arc::new(log.finish()),
        Arc::new(lot.finish()),
        Arc::new(part.finish()),
        Arc::new(cycle.finish()),
        Arc::new(t_start.finish()),
        Arc::new(rpm.finish()),
        Arc::new(status.finish()),
        Arc::new(reasons.finish()),
        Arc::new(failed.finish()),
        Arc::new(worst.finish()),
    ];
    cols.extend(values.iter_mut().map(|b| Arc::new(b.finish()) as ArrayRef));
    cols.push(Arc::new(vision.finish()));
    cols.extend(band.iter_mut().map(|b| Arc::new(b.finish()) as ArrayRef));
    RecordBatch::try_new(schema, cols)
}
