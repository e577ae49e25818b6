//! Each connector's whole story (issue 16): the cycle that made it judged
//! by the process recipe, its photograph judged by the vision recipe, and
//! (when asked) the model's predicted band for that cycle, joined by the
//! cycle index the camera writes in `frame_id` (`cycle-<index>`).
//!
//! The confusion of process NOK against vision fail answers "does the force
//! curve predict the defect?"; the connectors where the two disagree are
//! listed with both sides' reasons, so an engineer can read why.

use super::monitor::{CycleStatus, CycleVerdict};
use super::pin_spc::{ConnectorPins, observations};
use crate::vision::batch::{ItemResult, ItemStatus};
use crate::vision::result::PinStatus;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Process verdict against vision verdict, counted over connectors with
/// both (a cycle not evaluated or an image in error counts in neither).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Confusion {
    pub process_ok_vision_pass: usize,
    pub process_ok_vision_fail: usize,
    pub process_nok_vision_pass: usize,
    pub process_nok_vision_fail: usize,
}

impl Confusion {
    pub fn add(&mut self, process_nok: bool, vision_fail: bool) {
        match (process_nok, vision_fail) {
            (false, false) => self.process_ok_vision_pass += 1,
            (false, true) => self.process_ok_vision_fail += 1,
            (true, false) => self.process_nok_vision_pass += 1,
            (true, true) => self.process_nok_vision_fail += 1,
        }
    }

    /// Of the connectors vision failed, the fraction the process flagged.
    pub fn process_recall_of_vision_fails(&self) -> Option<f64> {
        let fails = self.process_nok_vision_fail + self.process_ok_vision_fail;
        (fails > 0).then(|| self.process_nok_vision_fail as f64 / fails as f64)
    }

    /// Adds another count (connectors of another log).
    pub fn merge(&mut self, o: &Confusion) {
        self.process_ok_vision_pass += o.process_ok_vision_pass;
        self.process_ok_vision_fail += o.process_ok_vision_fail;
        self.process_nok_vision_pass += o.process_nok_vision_pass;
        self.process_nok_vision_fail += o.process_nok_vision_fail;
    }

    pub fn total(&self) -> usize {
        self.process_ok_vision_pass
            + self.process_ok_vision_fail
            + self.process_nok_vision_pass
            + self.process_nok_vision_fail
    }
}

/// The model's predicted band for one cycle (the overlay's ensemble at the
/// cycle's speed, see `overlay::compare`): how much of the measured stroke
/// and force lies inside the band, and the stroke's residuals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BandFit {
    /// Fraction of the cycle's crank-angle grid inside the predicted min–max band.
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub stroke_in_band: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub force_in_band: f64,
    /// RMS of measured − predicted mean stroke over the cycle, mm.
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub stroke_rms_err_mm: f64,
    /// Measured − predicted stroke at bottom dead centre (insertion depth), mm.
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub stroke_err_bdc_mm: f64,
}

impl BandFit {
    /// The band fit of one cycle of an overlay.
    pub fn of(r: &crate::overlay::compare::CycleResidual) -> Self {
        BandFit {
            stroke_in_band: r.stroke_in_band,
            force_in_band: r.force_in_band,
            stroke_rms_err_mm: r.stroke_rms_err_mm,
            stroke_err_bdc_mm: r.stroke_err_bdc_mm,
        }
    }

    /// Every cycle's band fit of an overlay, by cycle index.
    pub fn of_overlay(r: &crate::overlay::compare::OverlayReport) -> BTreeMap<u64, BandFit> {
        r.cycles.iter().map(|c| (c.index, BandFit::of(c))).collect()
    }
}

/// One connector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConnectorStory {
    pub log: String,
    pub cycle: u64,
    /// The cycle's verdict (None: the log has no such complete cycle).
    pub process: Option<CycleStatus>,
    /// The failed objects ("threshold seated: crossed at 14.02 mm, 0.18 mm
    /// before the range"), or why the cycle was not evaluated.
    pub process_reasons: Vec<String>,
    /// The photograph's verdict (None: no image of this cycle).
    pub vision: Option<ItemStatus>,
    /// The pins and extras that failed, with their reasons.
    pub vision_reasons: Vec<String>,
    /// The model's band for this cycle, when a prediction was run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band: Option<BandFit>,
    /// Both sides judged and of one mind (NOK with fail, OK with pass).
    pub agree: Option<bool>,
}

impl ConnectorStory {
    /// Both sides' reasons, process first, joined for one line.
    pub fn why(&self) -> String {
        let all: Vec<&str> = self
            .process_reasons
            .iter()
            .chain(&self.vision_reasons)
            .map(String::as_str)
            .collect();
        all.join("; ")
    }
}

/// The stories of one log's connectors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoryReport {
    pub connectors: Vec<ConnectorStory>,
    pub confusion: Confusion,
    /// Cycles of the log with no photograph, and photographs naming no
    /// cycle of the log (or no cycle at all).
    pub cycles_without_image: usize,
    pub images_without_cycle: Vec<String>,
    /// The pins each photograph measured, for the pin-position SPC (not
    /// written out per connector: the run's `pin_spc` holds them).
    #[serde(skip)]
    pub pins: Vec<ConnectorPins>,
}

impl StoryReport {
    /// The connectors where process and vision disagree.
    pub fn disagreements(&self) -> impl Iterator<Item = &ConnectorStory> {
        self.connectors.iter().filter(|c| c.agree == Some(false))
    }
}

fn vision_reasons(r: &ItemResult) -> Vec<String> {
    if let Some(e) = &r.error {
        return vec![e.message.clone()];
    }
    let Some(ins) = &r.inspection else {
        return Vec::new();
    };
    let pins = ins
        .pins
        .iter()
        .filter(|p| p.status != PinStatus::Ok)
        .map(|p| {
            format!(
                "pin r{}c{} {}{}",
                p.row,
                p.col,
                p.status.as_str(),
                p.reason
                    .as_deref()
                    .map(|s| format!(" ({s})"))
                    .unwrap_or_default()
            )
        });
    let extras = ins.extras.iter().map(|e| {
        format!(
            "extra at ({:.0}, {:.0}) px{}",
            e.x_px,
            e.y_px,
            e.reason
                .as_deref()
                .map(|s| format!(" ({s})"))
                .unwrap_or_default()
        )
    });
    pins.chain(extras).collect()
}

/// Joins one log's cycle verdicts with the inspections of its photographs
/// (and, optionally, each cycle's band fit), in cycle order.
pub fn join(
    log: &str,
    cycles: &[CycleVerdict],
    images: &[ItemResult],
    bands: &BTreeMap<u64, BandFit>,
) -> StoryReport {
    let mut by_cycle: BTreeMap<u64, &ItemResult> = BTreeMap::new();
    let mut images_without_cycle = Vec::new();
    let known: BTreeMap<u64, &CycleVerdict> = cycles.iter().map(|c| (c.index, c)).collect();
    for r in images {
        match r.meta.cycle {
            Some(k) if known.contains_key(&k) => {
                // The first photograph of a cycle tells its story; a second is listed.
                if by_cycle.insert(k, r).is_some() {
                    images_without_cycle.push(format!("{} (a second image of cycle {k})", r.name));
                }
            }
            Some(k) => images_without_cycle.push(format!("{} (cycle {k} not in the log)", r.name)),
            None => images_without_cycle.push(format!("{} (no cycle in frame_id)", r.name)),
        }
    }
    let mut confusion = Confusion::default();
    let mut cycles_without_image = 0;
    let mut pins = Vec::new();
    let connectors = cycles
        .iter()
        .map(|c| {
            let img = by_cycle.get(&c.index).copied();
            match img.and_then(|r| r.inspection.as_ref()) {
                Some(ins) => pins.push(ConnectorPins {
                    cycle: c.index,
                    t_start_ns: c.t_start_ns,
                    pins: observations(ins),
                }),
                None if img.is_none() => cycles_without_image += 1,
                None => {}
            }
            let vision = img.map(|r| r.status);
            let nok = match c.status {
                CycleStatus::Ok => Some(false),
                CycleStatus::Nok => Some(true),
                CycleStatus::NotEvaluated => None,
            };
            let fail = match vision {
                Some(ItemStatus::Pass) => Some(false),
                Some(ItemStatus::Fail) => Some(true),
                _ => None,
            };
            let agree = nok.zip(fail).map(|(n, f)| {
                confusion.add(n, f);
                n == f
            });
            ConnectorStory {
                log: log.to_string(),
                cycle: c.index,
                process: Some(c.status),
                process_reasons: c.reasons(),
                vision,
                vision_reasons: img.map(vision_reasons).unwrap_or_default(),
                band: bands.get(&c.index).copied(),
                agree,
            }
        })
        .collect();
    StoryReport {
        connectors,
        confusion,
        cycles_without_image,
        images_without_cycle,
        pins,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::batch::ItemMeta;

    fn cycle(index: u64, status: CycleStatus) -> CycleVerdict {
        CycleVerdict {
            index,
            t_start_ns: 0,
            motor_rpm: 1200.0,
            status,
            why_not: (status == CycleStatus::NotEvaluated).then(|| "no force data".into()),
            failed: Vec::new(),
            values: BTreeMap::new(),
        }
    }

    fn image(cycle: Option<u64>, status: ItemStatus) -> ItemResult {
        ItemResult {
            name: format!("log#cycle-{cycle:?}"),
            meta: ItemMeta {
                cycle,
                ..ItemMeta::default()
            },
            status,
            error: None,
            inspection: None,
        }
    }

    #[test]
    fn joins_by_cycle_and_counts_only_what_both_sides_judged() {
        use CycleStatus::*;
        use ItemStatus::*;
        let cycles = [
            cycle(3, Ok),
            cycle(4, Nok),
            cycle(5, Nok),
            cycle(6, NotEvaluated),
            cycle(7, Ok),
            cycle(8, Ok),
        ];
        let images = [
            image(Some(3), Pass),
            image(Some(4), Fail),
            image(Some(5), Pass),
            image(Some(6), Fail),
            image(Some(7), Error),
            image(Some(99), Fail),
            image(None, Pass),
        ];
        let r = join("l", &cycles, &images, &BTreeMap::new());
        assert_eq!(
            r.confusion,
            Confusion {
                process_ok_vision_pass: 1,
                process_ok_vision_fail: 0,
                process_nok_vision_pass: 1,
                process_nok_vision_fail: 1,
            }
        );
        let dis: Vec<u64> = r.disagreements().map(|c| c.cycle).collect();
        assert_eq!(dis, [5]);
        assert_eq!(r.cycles_without_image, 1);
        assert_eq!(r.images_without_cycle.len(), 2);
        assert_eq!(r.connectors[3].process_reasons, ["no force data"]);
        assert_eq!(r.connectors[3].agree, None);
    }
}
