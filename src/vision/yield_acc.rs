//! The yield report's aggregate, mergeable: what [`YieldReport`] is computed
//! from, kept as counts and exact sums so that the aggregates of any split
//! of a batch, added, give the very report of the whole batch (plant scale,
//! `pinsight merge`).
//!
//! Everything here is a count except the pins' offset sums, which are kept
//! in fixed point (integer units of 2⁻⁶⁰ mm, `i128`): integer addition is
//! associative, so the mean offset does not depend on the order or the
//! grouping of the sums, as a floating-point sum would (by the last bits).
//! The rounding to 2⁻⁶⁰ mm (10⁻¹⁸ mm) is far below any measurement.

use super::batch::{ItemResult, ItemStatus};
use super::report::{ErrorRow, GroupBy, GroupYield, ParetoRow, PositionStats, YieldReport, Z95};
use super::report::{fmt_num, group_key, wilson};
use super::result::PinStatus;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Fixed-point units per mm of the offset sums.
const FIXED_PER_MM: f64 = (1u64 << 60) as f64;

/// One group's counts (a lot, a speed …) and the number its key was made of.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GroupAcc {
    pub value: Option<f64>,
    pub inspected: u64,
    pub passed: u64,
    pub errors: u64,
}

impl GroupAcc {
    fn add(&mut self, status: ItemStatus) {
        match status {
            ItemStatus::Pass => {
                self.inspected += 1;
                self.passed += 1;
            }
            ItemStatus::Fail => self.inspected += 1,
            ItemStatus::Error => self.errors += 1,
        }
    }

    fn merge(&mut self, o: &GroupAcc) {
        self.value = self.value.or(o.value);
        self.inspected += o.inspected;
        self.passed += o.passed;
        self.errors += o.errors;
    }
}

/// One pin position's counts and offset sums.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PositionAcc {
    pub part_number: String,
    pub row: u32,
    pub col: u32,
    pub inspected: u64,
    pub missing: u64,
    pub damaged: u64,
    pub bent: u64,
    pub short: u64,
    pub high: u64,
    /// Pins with an offset, and the sum of their offsets in 2⁻⁶⁰ mm.
    pub offsets: u64,
    pub offset_sum_fixed: i128,
    pub max_offset_mm: Option<f64>,
}

impl PositionAcc {
    fn defects(&self) -> u64 {
        self.missing + self.damaged + self.bent + self.short + self.high
    }

    fn merge(&mut self, o: &PositionAcc) {
        self.inspected += o.inspected;
        self.missing += o.missing;
        self.damaged += o.damaged;
        self.bent += o.bent;
        self.short += o.short;
        self.high += o.high;
        self.offsets += o.offsets;
        self.offset_sum_fixed += o.offset_sum_fixed;
        self.max_offset_mm = max_opt(self.max_offset_mm, o.max_offset_mm);
    }
}

fn max_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.max(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// An error item and where it stands in the batch's order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderedError {
    pub order: u64,
    pub row: ErrorRow,
}

/// The aggregate of a batch's results (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct YieldAcc {
    pub group_by: GroupBy,
    pub items: u64,
    pub passed: u64,
    pub failed: u64,
    pub errors: u64,
    pub pins: u64,
    pub defective_pins: u64,
    /// Defective pins by status name.
    pub kinds: BTreeMap<String, u64>,
    pub extras: u64,
    pub connectors_with_extras: u64,
    pub groups: BTreeMap<String, GroupAcc>,
    pub by_speed: BTreeMap<String, GroupAcc>,
    pub by_clearance: BTreeMap<String, GroupAcc>,
    /// By "part\u{1f}row\u{1f}col" (a map key JSON can carry), in that order.
    pub positions: BTreeMap<String, PositionAcc>,
    pub error_list: Vec<OrderedError>,
}

impl YieldAcc {
    pub fn new(group_by: GroupBy) -> Self {
        YieldAcc {
            group_by,
            items: 0,
            passed: 0,
            failed: 0,
            errors: 0,
            pins: 0,
            defective_pins: 0,
            kinds: BTreeMap::new(),
            extras: 0,
            connectors_with_extras: 0,
            groups: BTreeMap::new(),
            by_speed: BTreeMap::new(),
            by_clearance: BTreeMap::new(),
            positions: BTreeMap::new(),
            error_list: Vec::new(),
        }
    }

    /// The aggregate of results in batch order (`order` = their index).
    pub fn of(results: &[ItemResult], by: GroupBy) -> Self {
        let mut a = YieldAcc::new(by);
        for (i, r) in results.iter().enumerate() {
            a.add(i as u64, r);
        }
        a
    }

    /// Adds one result standing at `order` in the batch.
    pub fn add(&mut self, order: u64, r: &ItemResult) {
        self.items += 1;
        match r.status {
            ItemStatus::Pass => self.passed += 1,
            ItemStatus::Fail => self.failed += 1,
            ItemStatus::Error => self.errors += 1,
        }
        let (k, v) = group_key(r, self.group_by);
        let g = self.groups.entry(k).or_default();
        g.value = g.value.or(v);
        g.add(r.status);
        if let Some(v) = r.meta.motor_rpm {
            let g = self
                .by_speed
                .entry(format!("{} rpm", fmt_num(v)))
                .or_default();
            g.value = Some(v);
            g.add(r.status);
        }
        if let Some(v) = r.meta.clearance_mm {
            let g = self
                .by_clearance
                .entry(format!("{} mm", fmt_num(v)))
                .or_default();
            g.value = Some(v);
            g.add(r.status);
        }
        if let Some(e) = &r.error {
            self.error_list.push(OrderedError {
                order,
                row: ErrorRow {
                    name: r.name.clone(),
                    kind: e.kind,
                    message: e.message.clone(),
                },
            });
        }
        let Some(ins) = &r.inspection else { return };
        self.extras += ins.extras.len() as u64;
        if !ins.extras.is_empty() {
            self.connectors_with_extras += 1;
        }
        for p in &ins.pins {
            self.pins += 1;
            let key = format!("{}\u{1f}{:010}\u{1f}{:010}", ins.part_number, p.row, p.col);
            let e = self.positions.entry(key).or_insert_with(|| PositionAcc {
                part_number: ins.part_number.clone(),
                row: p.row,
                col: p.col,
                ..PositionAcc::default()
            });
            e.inspected += 1;
            if let Some(o) = p.offset_mm.filter(|o| o.is_finite()) {
                e.offsets += 1;
                e.offset_sum_fixed += (o * FIXED_PER_MM).round() as i128;
                e.max_offset_mm = max_opt(e.max_offset_mm, Some(o));
            }
            if p.status != PinStatus::Ok {
                self.defective_pins += 1;
                *self.kinds.entry(p.status.as_str().to_string()).or_default() += 1;
                match p.status {
                    PinStatus::Missing => e.missing += 1,
                    PinStatus::Damaged => e.damaged += 1,
                    PinStatus::Bent => e.bent += 1,
                    PinStatus::Short => e.short += 1,
                    PinStatus::High => e.high += 1,
                    PinStatus::Ok => {}
                }
            }
        }
    }

    /// Adds another part of the batch (its error rows keep their order).
    pub fn merge(&mut self, o: &YieldAcc) {
        self.items += o.items;
        self.passed += o.passed;
        self.failed += o.failed;
        self.errors += o.errors;
        self.pins += o.pins;
        self.defective_pins += o.defective_pins;
        for (k, v) in &o.kinds {
            *self.kinds.entry(k.clone()).or_default() += v;
        }
        self.extras += o.extras;
        self.connectors_with_extras += o.connectors_with_extras;
        for (mine, theirs) in [
            (&mut self.groups, &o.groups),
            (&mut self.by_speed, &o.by_speed),
            (&mut self.by_clearance, &o.by_clearance),
        ] {
            for (k, g) in theirs {
                mine.entry(k.clone()).or_default().merge(g);
            }
        }
        for (k, p) in &o.positions {
            match self.positions.get_mut(k) {
                Some(m) => m.merge(p),
                None => {
                    self.positions.insert(k.clone(), p.clone());
                }
            }
        }
        self.error_list.extend(o.error_list.iter().cloned());
        self.error_list.sort_by_key(|e| e.order);
    }

    /// The report.
    pub fn report(&self) -> YieldReport {
        let inspected = self.passed + self.failed;
        // Pareto over pin defect kinds and extras.
        let mut pareto: Vec<(String, u64)> =
            self.kinds.iter().map(|(k, v)| (k.clone(), *v)).collect();
        if self.extras > 0 {
            pareto.push(("extra".into(), self.extras));
        }
        pareto.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let total: u64 = pareto.iter().map(|p| p.1).sum();
        let mut cum = 0u64;
        let pareto = pareto
            .into_iter()
            .map(|(kind, count)| {
                cum += count;
                ParetoRow {
                    kind,
                    count,
                    share: count as f64 / total.max(1) as f64,
                    cumulative: cum as f64 / total.max(1) as f64,
                }
            })
            .collect();
        let mut worst: Vec<PositionStats> = self
            .positions
            .values()
            .map(|p| PositionStats {
                part_number: p.part_number.clone(),
                row: p.row,
                col: p.col,
                inspected: p.inspected,
                defects: p.defects(),
                rate: p.defects() as f64 / p.inspected.max(1) as f64,
                missing: p.missing,
                damaged: p.damaged,
                bent: p.bent,
                short: p.short,
                high: p.high,
                mean_offset_mm: (p.offsets > 0)
                    .then(|| p.offset_sum_fixed as f64 / FIXED_PER_MM / p.offsets as f64),
                max_offset_mm: p.max_offset_mm,
            })
            .collect();
        worst.sort_by(|a, b| {
            b.defects
                .cmp(&a.defects)
                .then(b.rate.total_cmp(&a.rate))
                .then(
                    b.mean_offset_mm
                        .unwrap_or(0.0)
                        .total_cmp(&a.mean_offset_mm.unwrap_or(0.0)),
                )
        });
        let dp = wilson(self.defective_pins, self.pins, Z95);
        let pins = self.pins;
        YieldReport {
            items: self.items,
            inspected,
            passed: self.passed,
            failed: self.failed,
            errors: self.errors,
            yield_frac: (inspected > 0).then(|| self.passed as f64 / inspected as f64),
            ci95: wilson(self.passed, inspected, Z95),
            ci_method: "Wilson score interval, 95 %".into(),
            pins_inspected: pins,
            defective_pins: self.defective_pins,
            dppm: (pins > 0).then(|| self.defective_pins as f64 / pins as f64 * 1e6),
            dppm_ci95: (dp.0 * 1e6, dp.1 * 1e6),
            extras: self.extras,
            connectors_with_extras: self.connectors_with_extras,
            pareto,
            group_by: self.group_by,
            groups: groups(&self.groups),
            by_speed: groups(&self.by_speed),
            by_clearance: groups(&self.by_clearance),
            worst_pins: worst,
            error_list: self.error_list.iter().map(|e| e.row.clone()).collect(),
        }
    }
}

impl YieldReport {
    /// Computes the report from the batch results (through their mergeable
    /// aggregate, so that a report merged from shards is this very report).
    /// Written here, beside the aggregate, so that `report` (the report's
    /// types and forms) does not import this room.
    pub fn build(results: &[ItemResult], by: GroupBy) -> YieldReport {
        YieldAcc::of(results, by).report()
    }
}

/// The groups with their yield and interval, by key (by value when every
/// group has one).
fn groups(map: &BTreeMap<String, GroupAcc>) -> Vec<GroupYield> {
    let mut v: Vec<GroupYield> = map
        .iter()
        .map(|(k, g)| GroupYield {
            key: k.clone(),
            value: g.value,
            inspected: g.inspected,
            passed: g.passed,
            errors: g.errors,
            yield_frac: (g.inspected > 0).then(|| g.passed as f64 / g.inspected as f64),
            ci95: wilson(g.passed, g.inspected, Z95),
        })
        .collect();
    if v.iter().all(|g| g.value.is_some()) {
        v.sort_by(|a, b| a.value.unwrap_or(0.0).total_cmp(&b.value.unwrap_or(0.0)));
    }
    v
}
