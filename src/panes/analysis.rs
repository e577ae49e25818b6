//! The session's vision, yield and overlay runs: plain functions from the
//! session's data to results the Vision, Yield and Overlay panes show.
//!
//! They take a [`Progress`] (gauge and cancellation) and never panic on bad
//! input: an image that cannot be read or analysed, a log without usable
//! cycles, a model failure all become a result that says why. The TUI runs
//! them on its worker thread; `render` and `batch` run them in line
//! ([`Session::inspect_now`], [`Session::run_yield_now`],
//! [`Session::run_overlay_now`]). Their results enter the session through
//! [`Session::set_inspection`], [`Session::set_yield`] and
//! [`Session::set_overlay`], so the panes stay pure functions of the
//! session.

use super::session::{ImageEntry, ImageSource, LogEntry, RecipeEntry, Session};
use crate::overlay::compare::{OverlayOptions, OverlayReport, model_params, overlay};
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::CycleSet;
use crate::vision::InspectOptions;
use crate::vision::batch::{Item, ItemResult, RecipeBook, Source, inspect_item, run_batch};
use crate::vision::overlay::{OverlayOptions as DrawOptions, draw_overlay};
use crate::vision::report::{GroupBy, YieldReport};
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// One image inspected: the library's result (pass, fail or error with its
/// reason) and the annotated picture (vision's overlay: grid, pins by
/// verdict, magnified offsets, tolerance circles).
#[derive(Debug, Clone, Serialize)]
pub struct Inspected {
    /// Index of the image in the session.
    pub image: usize,
    pub result: ItemResult,
    /// Which recipe was used and how it was chosen.
    pub recipe_note: String,
    pub wall_ms: f64,
    #[serde(skip)]
    pub annotated: Option<Arc<image::RgbImage>>,
}

/// The batch yield over the session's images.
#[derive(Debug, Clone, Serialize)]
pub struct YieldRun {
    pub report: YieldReport,
    #[serde(skip)]
    pub results: Vec<ItemResult>,
    /// Cancelled part-way: the images not inspected are `error` (cancelled).
    pub cancelled: bool,
    pub wall_ms: f64,
}

/// Measured against predicted for one log.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayRun {
    /// Index of the log in the session.
    pub log: usize,
    pub report: Result<OverlayReport, String>,
    pub wall_ms: f64,
}

/// The recipes of the session as the vision library's recipe book.
pub fn recipe_book(recipes: &[RecipeEntry]) -> RecipeBook {
    // One recipe per part number: the first loaded wins (a log's attached
    // recipe and the same file opened by hand are the same recipe).
    let mut out: Vec<crate::vision::Recipe> = Vec::new();
    for r in recipes {
        if !out.iter().any(|x| x.part_number == r.recipe.part_number) {
            out.push(r.recipe.clone());
        }
    }
    RecipeBook::new(out)
}

/// An image of the session as a vision batch item.
pub fn item_of(img: &ImageEntry) -> Item {
    Item {
        name: img.name.clone(),
        source: match &img.source {
            ImageSource::File(p) => Source::Path(p.clone()),
            ImageSource::Bytes(b) => Source::Bytes(b.clone()),
        },
        meta: img.meta.clone(),
    }
}

/// How the recipe of an item is chosen (said on the Vision pane).
fn recipe_note(img: &ImageEntry, book: &RecipeBook, r: &ItemResult) -> String {
    let used = r
        .inspection
        .as_ref()
        .map(|i| i.part_number.clone())
        .or_else(|| r.meta.part_number.clone());
    match (&img.meta.part_number, used) {
        (Some(p), _) => format!("{p} (the part number of the image's log)"),
        (None, Some(u)) if book.recipes.len() > 1 => format!(
            "{u} (recognised among {} recipes: most positions holding a pin)",
            book.recipes.len()
        ),
        (None, Some(u)) => format!("{u} (the only recipe loaded)"),
        (None, None) => "none".into(),
    }
}

/// Inspects one image of the session against the matching recipe and draws
/// the annotated overlay.
pub fn inspect_image(index: usize, img: &ImageEntry, book: &RecipeBook) -> Inspected {
    let start = Instant::now();
    let item = item_of(img);
    let (result, gray) = inspect_item(&item, book, &InspectOptions::default(), true);
    let annotated = match (&result.inspection, &gray) {
        (Some(ins), Some(g)) => Some(Arc::new(draw_overlay(g, ins, &DrawOptions::default()))),
        _ => None,
    };
    Inspected {
        image: index,
        recipe_note: recipe_note(img, book, &result),
        result,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        annotated,
    }
}

/// Inspects every image of the session (rayon, progress, cancellation) and
/// builds the yield report (Wilson 95 % interval, DPPM, Pareto, by lot and
/// speed, worst positions).
pub fn run_yield(images: &[ImageEntry], book: &RecipeBook, progress: &Progress) -> YieldRun {
    let start = Instant::now();
    progress.set_total(images.len() as u64);
    progress.set_done(0);
    progress.set_message(format!("inspecting {} images", images.len()));
    let items: Vec<Item> = images.iter().map(item_of).collect();
    let results = run_batch(&items, book, &InspectOptions::default(), progress);
    let report = YieldReport::build(&results, GroupBy::Lot);
    YieldRun {
        report,
        results,
        cancelled: progress.is_cancelled(),
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

/// Compares a log's cycles with the model's predicted ensemble
/// (`pinsight::overlay`): parameters from the `paper` preset plus the log's
/// `rig` metadata (clearance, standoff, material, gear ratio), the
/// clearance level, each speed group at its logged speed.
pub fn run_overlay(
    index: usize,
    log: &RigLog,
    cycles: &CycleSet,
    progress: &Progress,
) -> OverlayRun {
    let start = Instant::now();
    progress.set_message(format!("overlay: predicting {}", log.file));
    let report = model_params(log, None, &[])
        .map_err(|e| format!("model parameters from the log's metadata: {e}"))
        .and_then(|(params, notes)| {
            overlay(
                log,
                cycles,
                &params,
                notes,
                &OverlayOptions::default(),
                progress,
            )
            .map_err(|e| e.to_string())
        });
    let report = if progress.is_cancelled() && report.is_err() {
        Err("cancelled".into())
    } else {
        report
    };
    OverlayRun {
        log: index,
        report,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

impl Session {
    /// Runs, in line, the analysis a pane shows when it has not run yet:
    /// Vision the inspection of its image, Yield the batch, Overlay the
    /// comparison of its log (what the TUI's worker does when the pane is
    /// shown). Returns what ran, for batch reports.
    pub fn prepare_pane(&mut self, pane: super::PaneId, ui: &super::PaneState) -> Option<String> {
        use super::PaneId;
        match pane {
            PaneId::Vision if !self.images.is_empty() => {
                let i = ui.vision.image.min(self.images.len() - 1);
                if self.inspection(i).is_none() {
                    self.inspect_now(i);
                    return Some(format!("inspected image {i}"));
                }
            }
            PaneId::Yield if !self.images.is_empty() && self.yields.is_none() => {
                self.run_yield_now();
                return Some(format!("yield over {} images", self.images.len()));
            }
            PaneId::Overlay if !self.logs.is_empty() => {
                let i = ui.overlay.log.min(self.logs.len() - 1);
                if self.overlay_of(i).is_none() {
                    self.run_overlay_now(i);
                    return Some(format!("overlay of log {i}"));
                }
            }
            _ => {}
        }
        None
    }

    /// The recipe book of the session.
    pub fn recipe_book(&self) -> RecipeBook {
        recipe_book(&self.recipes)
    }

    /// Records an inspection (replacing an older one of the same image).
    pub fn set_inspection(&mut self, r: Inspected) {
        self.inspections.insert(r.image, r);
    }

    /// The inspection of image `i`, if it ran.
    pub fn inspection(&self, i: usize) -> Option<&Inspected> {
        self.inspections.get(&i)
    }

    /// Inspects image `i` now (batch mode, `render`, tests).
    pub fn inspect_now(&mut self, i: usize) {
        if let Some(img) = self.images.get(i) {
            let r = inspect_image(i, img, &self.recipe_book());
            self.set_inspection(r);
        }
    }

    pub fn set_yield(&mut self, r: YieldRun) {
        self.yields = Some(r);
    }

    /// Runs the batch yield now.
    pub fn run_yield_now(&mut self) {
        let r = run_yield(&self.images, &self.recipe_book(), &Progress::hidden());
        self.set_yield(r);
    }

    pub fn set_overlay(&mut self, r: OverlayRun) {
        self.overlays.insert(r.log, r);
    }

    /// The overlay of log `i`, if it ran.
    pub fn overlay_of(&self, i: usize) -> Option<&OverlayRun> {
        self.overlays.get(&i)
    }

    /// Runs the overlay of log `i` now.
    pub fn run_overlay_now(&mut self, i: usize) {
        let r = match self.logs.get(i) {
            Some(LogEntry {
                rig: Some((log, cycles)),
                ..
            }) => run_overlay(i, log, cycles, &Progress::hidden()),
            Some(l) => OverlayRun {
                log: i,
                report: Err(format!("{}: not a rig log (no cycles to compare)", l.path)),
                wall_ms: 0.0,
            },
            None => return,
        };
        self.set_overlay(r);
    }
}
