//! The Yield pane: the batch's yield with its Wilson 95 % interval, DPPM,
//! the Pareto of defects, yield by lot and by speed, the worst pins, and
//! the images that could not be inspected.
//!
//! The batch itself ([`crate::vision::batch::run_batch`] and
//! [`crate::vision::report::YieldReport`]) runs on the TUI's worker with a
//! gauge and cancel ([`crate::engine::vision::run_yield`]); this view reads its
//! result from the session.

use super::PaneState;
use super::session::Session;
use crate::plot::Panel;
use crate::vision::batch::ItemStatus;
use crate::vision::report::{YieldReport, items_csv};
use serde::Serialize;

/// UI state of the Yield pane: the selected worst-pin row.
#[derive(Debug, Clone, Default, Serialize)]
pub struct YieldUi {
    pub selected: usize,
}

impl YieldUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "selected" => self.selected = super::parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One image's outcome (the item list under the figures).
#[derive(Debug, Clone, Serialize)]
pub struct ItemRow {
    pub name: String,
    pub status: String,
    pub part_number: Option<String>,
    /// Defective pins, or the error.
    pub note: String,
}

/// The Yield pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct YieldView {
    pub images: usize,
    pub recipes: usize,
    /// The batch has not run on the current images yet.
    pub pending: bool,
    pub cancelled: bool,
    pub wall_ms: Option<f64>,
    /// The library's report (yield, CI, DPPM, Pareto, groups, worst pins).
    pub report: Option<YieldReport>,
    pub items: Vec<ItemRow>,
    pub selected: usize,
    pub message: Option<String>,
    #[serde(skip)]
    csv: String,
}

impl YieldView {
    /// One row per image (the library's `items.csv`).
    pub fn to_csv(&self) -> String {
        if self.csv.is_empty() {
            items_csv(&[])
        } else {
            self.csv.clone()
        }
    }

    /// Pareto, yield by group, worst positions, by speed and clearance.
    pub fn panels(&self) -> Vec<Panel> {
        self.report
            .as_ref()
            .map(|r| r.panels().into_iter().map(|(_, p)| p).collect())
            .unwrap_or_default()
    }
}

pub fn view(s: &Session, ui: &PaneState) -> YieldView {
    let mut v = YieldView {
        images: s.images.len(),
        recipes: s.recipes.len(),
        pending: false,
        cancelled: false,
        wall_ms: None,
        report: None,
        items: Vec::new(),
        selected: 0,
        message: None,
        csv: String::new(),
    };
    if s.images.is_empty() {
        v.message = Some(
            "no connector images loaded: open images (or a rig log with camera images) and their recipes (o)"
                .into(),
        );
        return v;
    }
    let Some(run) = &s.yields else {
        v.pending = true;
        v.message = Some(format!(
            "batch yield over {} images not run yet (r runs it)",
            s.images.len()
        ));
        return v;
    };
    v.cancelled = run.cancelled;
    v.wall_ms = Some(run.wall_ms);
    v.report = Some(run.report.clone());
    v.csv = items_csv(&run.results);
    v.items = run
        .results
        .iter()
        .map(|r| ItemRow {
            name: r.name.clone(),
            status: match r.status {
                ItemStatus::Pass => "pass",
                ItemStatus::Fail => "fail",
                ItemStatus::Error => "error",
            }
            .into(),
            part_number: r.meta.part_number.clone(),
            note: match (&r.inspection, &r.error) {
                (_, Some(e)) => e.message.clone(),
                (Some(i), None) => {
                    let bad = i.pins.len() as u32 - i.counts.ok;
                    let mut n = if bad == 0 {
                        "all pins ok".to_string()
                    } else {
                        format!("{bad} defective pin(s)")
                    };
                    if !i.extras.is_empty() {
                        n.push_str(&format!(", {} extra", i.extras.len()));
                    }
                    n
                }
                (None, None) => String::new(),
            },
        })
        .collect();
    v.selected = ui.yields.selected.min(v.items.len().saturating_sub(1));
    if run.cancelled {
        v.message = Some("cancelled: the images not inspected are counted as errors".into());
    }
    v
}
