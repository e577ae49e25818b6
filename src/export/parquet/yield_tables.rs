//! `yield`'s results as two tables: `images` (one row per image) and
//! `pins` (one row per inspected pin), joined by `item`, the image's place
//! in the batch (the order of `yield.json`'s items and `items.csv`).
//!
//! `part`, `lot` and `rig` are in both tables (so either can be partitioned
//! by them, and a query of pins by lot needs no join); `part` is the part
//! number the image's log names, else the part of the recipe it was
//! inspected with (`items.csv`'s `part_number` is only the former). Pin
//! measures are 32-bit floats: 7 significant digits, far finer than the
//! measurement (~0.01 px, ~0.001 mm) and half the size of 64-bit ones
//! (BENCHMARKS.md); the image's process values are 64-bit, as logged.

use crate::vision::batch::{ItemResult, ItemStatus};
use crate::vision::recipe::View;
use arrow_array::builder::{
    Float32Builder, Float64Builder, StringBuilder, TimestampNanosecondBuilder, UInt32Builder,
    UInt64Builder,
};
use arrow_array::{ArrayRef, RecordBatch};
use arrow_schema::{DataType, Field, Schema, SchemaRef, TimeUnit};
use std::sync::{Arc, OnceLock};

/// The file (or partitioned folder) names of the two tables.
pub const IMAGES: &str = "images";
pub const PINS: &str = "pins";

/// The schema of `images`.
pub fn images_schema() -> SchemaRef {
    static S: OnceLock<SchemaRef> = OnceLock::new();
    S.get_or_init(|| {
        let u32f = |n: &str| Field::new(n, DataType::UInt32, true);
        let f64f = |n: &str| Field::new(n, DataType::Float64, true);
        let txt = |n: &str| Field::new(n, DataType::Utf8, true);
        Arc::new(Schema::new(vec![
            Field::new("item", DataType::UInt64, false),
            Field::new("name", DataType::Utf8, false),
            Field::new("verdict", DataType::Utf8, false),
            txt("part"),
            txt("lot"),
            txt("rig"),
            f64f("motor_rpm"),
            f64f("clearance_mm"),
            Field::new("cycle", DataType::UInt64, true),
            txt("log"),
            Field::new(
                "log_time",
                DataType::Timestamp(TimeUnit::Nanosecond, Some("UTC".into())),
                true,
            ),
            txt("view"),
            u32f("pins"),
            u32f("ok"),
            u32f("missing"),
            u32f("damaged"),
            u32f("bent"),
            u32f("short"),
            u32f("high"),
            u32f("extras"),
            f64f("mm_per_px"),
            f64f("rotation_deg"),
            f64f("fit_rms_px"),
            txt("error_kind"),
            txt("error"),
        ]))
    })
    .clone()
}

/// The schema of `pins`.
pub fn pins_schema() -> SchemaRef {
    static S: OnceLock<SchemaRef> = OnceLock::new();
    S.get_or_init(|| {
        let f32f = |n: &str| Field::new(n, DataType::Float32, true);
        Arc::new(Schema::new(vec![
            Field::new("item", DataType::UInt64, false),
            Field::new("part", DataType::Utf8, true),
            Field::new("lot", DataType::Utf8, true),
            Field::new("rig", DataType::Utf8, true),
            Field::new("row", DataType::UInt32, false),
            Field::new("col", DataType::UInt32, false),
            Field::new("status", DataType::Utf8, false),
            f32f("x_px"),
            f32f("y_px"),
            f32f("dx_mm"),
            f32f("dy_mm"),
            f32f("offset_mm"),
            f32f("area_ratio"),
            f32f("height_mm"),
        ]))
    })
    .clone()
}

fn verdict(s: ItemStatus) -> &'static str {
    match s {
        ItemStatus::Pass => "pass",
        ItemStatus::Fail => "fail",
        ItemStatus::Error => "error",
    }
}

/// The part an image is of: its log's, else its recipe's.
fn part_of(r: &ItemResult) -> Option<&str> {
    r.meta
        .part_number
        .as_deref()
        .or(r.inspection.as_ref().map(|i| i.part_number.as_str()))
}

/// Both tables of the results, each item with its place in the batch.
pub fn yield_tables<'a>(
    items: impl IntoIterator<Item = (u64, &'a ItemResult)>,
) -> Result<(RecordBatch, RecordBatch), arrow_schema::ArrowError> {
    let mut item = UInt64Builder::new();
    let mut name = StringBuilder::new();
    let mut verd = StringBuilder::new();
    let (mut part, mut lot, mut rig, mut log) = (
        StringBuilder::new(),
        StringBuilder::new(),
        StringBuilder::new(),
        StringBuilder::new(),
    );
    let (mut rpm, mut clearance) = (Float64Builder::new(), Float64Builder::new());
    let mut cycle = UInt64Builder::new();
    let mut log_time = TimestampNanosecondBuilder::new().with_timezone("UTC");
    let mut view = StringBuilder::new();
    let mut counts: Vec<UInt32Builder> = (0..8).map(|_| UInt32Builder::new()).collect();
    let (mut scale, mut rot, mut rms) = (
        Float64Builder::new(),
        Float64Builder::new(),
        Float64Builder::new(),
    );
    let (mut ekind, mut emsg) = (StringBuilder::new(), StringBuilder::new());

    let mut p_item = UInt64Builder::new();
    let (mut p_part, mut p_lot, mut p_rig) = (
        StringBuilder::new(),
        StringBuilder::new(),
        StringBuilder::new(),
    );
    let (mut p_row, mut p_col) = (UInt32Builder::new(), UInt32Builder::new());
    let mut p_status = StringBuilder::new();
    let mut p_f: Vec<Float32Builder> = (0..7).map(|_| Float32Builder::new()).collect();

    for (order, r) in items {
        let m = &r.meta;
        item.append_value(order);
        name.append_value(&r.name);
        verd.append_value(verdict(r.status));
        part.append_option(part_of(r));
        lot.append_option(m.lot.as_deref());
        rig.append_option(m.rig_id.as_deref());
        rpm.append_option(m.motor_rpm);
        clearance.append_option(m.clearance_mm);
        cycle.append_option(m.cycle);
        log.append_option(m.log.as_deref());
        log_time.append_option(m.log_time_ns.and_then(|t| i64::try_from(t).ok()));
        let ins = r.inspection.as_ref();
        view.append_option(ins.map(|i| match i.view {
            View::Top => "top",
            View::Side => "side",
        }));
        let c = ins.map(|i| &i.counts);
        let vals = [
            ins.map(|i| i.pins.len() as u32),
            c.map(|c| c.ok),
            c.map(|c| c.missing),
            c.map(|c| c.damaged),
            c.map(|c| c.bent),
            c.map(|c| c.short),
            c.map(|c| c.high),
            ins.map(|i| i.extras.len() as u32),
        ];
        for (b, v) in counts.iter_mut().zip(vals) {
            b.append_option(v);
        }
        scale.append_option(ins.map(|i| i.grid.mm_per_px));
        rot.append_option(ins.map(|i| i.grid.rotation_deg));
        rms.append_option(ins.map(|i| i.grid.fit_rms_px));
        ekind.append_option(r.error.as_ref().map(|e| e.kind.as_str()));
        emsg.append_option(r.error.as_ref().map(|e| e.message.as_str()));
        let Some(ins) = ins else { continue };
        for p in &ins.pins {
            p_item.append_value(order);
            p_part.append_option(part_of(r));
            p_lot.append_option(m.lot.as_deref());
            p_rig.append_option(m.rig_id.as_deref());
            p_row.append_value(p.row);
            p_col.append_value(p.col);
            p_status.append_value(p.status.as_str());
            let vals = [
                p.x_px,
                p.y_px,
                p.dx_mm,
                p.dy_mm,
                p.offset_mm,
                p.area_ratio,
                p.height_mm,
            ];
            for (b, v) in p_f.iter_mut().zip(vals) {
                b.append_option(v.map(|v| v as f32));
            }
        }
    }
    let mut cols: Vec<ArrayRef> = vec![
        Arc::new(item.finish()),
        Arc::new(name.finish()),
        Arc::new(verd.finish()),
        Arc::new(part.finish()),
        Arc::new(lot.finish()),
        Arc::new(rig.finish()),
        Arc::new(rpm.finish()),
        Arc::new(clearance.finish()),
        Arc::new(cycle.finish()),
        Arc::new(log.finish()),
        Arc::new(log_time.finish()),
        Arc::new(view.finish()),
    ];
    cols.extend(counts.iter_mut().map(|b| Arc::new(b.finish()) as ArrayRef));
    cols.extend([
        Arc::new(scale.finish()) as ArrayRef,
        Arc::new(rot.finish()),
        Arc::new(rms.finish()),
        Arc::new(ekind.finish()),
        Arc::new(emsg.finish()),
    ]);
    let images = RecordBatch::try_new(images_schema(), cols)?;
    let mut pcols: Vec<ArrayRef> = vec![
        Arc::new(p_item.finish()),
        Arc::new(p_part.finish()),
        Arc::new(p_lot.finish()),
        Arc::new(p_rig.finish()),
        Arc::new(p_row.finish()),
        Arc::new(p_col.finish()),
        Arc::new(p_status.finish()),
    ];
    pcols.extend(p_f.iter_mut().map(|b| Arc::new(b.finish()) as ArrayRef));
    let pins = RecordBatch::try_new(pins_schema(), pcols)?;
    Ok((images, pins))
}
