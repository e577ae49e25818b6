//! The vision jobs: one image inspected (with its annotated overlay) and
//! the batch yield over many images.
//!
//! Every face runs the yield through [`run_yield`]: `pinsight yield`, the
//! Yield pane, `render yield` and a batch `run yield`. An image that cannot
//! be read or analysed is an `error` item of the report, never dropped —
//! whichever face asked (issue 13/14: they used to differ).

use super::entries::{ImageEntry, ImageSource, RecipeEntry};
use crate::progress::Progress;
use crate::vision::InspectOptions;
use crate::vision::batch::{
    Item, ItemResult, ItemStatus, RecipeBook, Source, inspect_item, run_batch,
};
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

/// The recipes of the session as the vision library's recipe book.
///
/// `invalid` are the reasons of recipe files that did not validate: as in
/// `pinsight yield`, an image that then finds no recipe gives them as its
/// error instead of a bare "no recipe given".
pub fn recipe_book(recipes: &[RecipeEntry], invalid: Vec<String>) -> RecipeBook {
    // One recipe per part number: the first loaded wins (a log's attached
    // recipe and the same file opened by hand are the same recipe).
    let mut out: Vec<crate::vision::Recipe> = Vec::new();
    for r in recipes {
        if !out.iter().any(|x| x.part_number == r.recipe.part_number) {
            out.push(r.recipe.clone());
        }
    }
    let mut book = RecipeBook::new(out);
    book.invalid = invalid;
    book
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
/// the annotated overlay. An image that could not be loaded gives its load
/// error as the result.
pub fn inspect_image(index: usize, img: &ImageEntry, book: &RecipeBook) -> Inspected {
    let start = Instant::now();
    let (result, gray) = match yield_item(img) {
        YieldInput::Image(item) => inspect_item(&item, book, &InspectOptions::default(), true),
        YieldInput::Failed(failed) => (*failed, None),
    };
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

/// One input of the yield: an image to inspect, or an item already known
/// to be an `error` (unreadable, undecodable, a damaged log's lost images).
#[derive(Debug, Clone)]
pub enum YieldInput {
    Image(Item),
    Failed(Box<ItemResult>),
}

/// A session image as an input of the yield: the item to inspect, or
/// (an image that could not be loaded) its `error` result.
pub fn yield_item(img: &ImageEntry) -> YieldInput {
    match &img.load_error {
        None => YieldInput::Image(item_of(img)),
        Some(e) => YieldInput::Failed(Box::new(ItemResult {
            name: img.name.clone(),
            meta: img.meta.clone(),
            status: ItemStatus::Error,
            error: Some(e.clone()),
            inspection: None,
        })),
    }
}

/// Inspects every image of the session (rayon, progress, cancellation) and
/// builds the yield report; images that could not be loaded are `error`
/// items of the report.
pub fn run_yield(images: &[ImageEntry], book: &RecipeBook, progress: &Progress) -> YieldRun {
    let inputs: Vec<YieldInput> = images.iter().map(yield_item).collect();
    run_yield_inputs(
        &inputs,
        book,
        &InspectOptions::default(),
        GroupBy::Lot,
        progress,
    )
}

/// The yield over a list of inputs, in their order. The one function behind
/// `pinsight yield`, the Yield pane and batch `run yield`.
pub fn run_yield_inputs(
    inputs: &[YieldInput],
    book: &RecipeBook,
    opts: &InspectOptions,
    by: GroupBy,
    progress: &Progress,
) -> YieldRun {
    let start = Instant::now();
    let items: Vec<Item> = inputs
        .iter()
        .filter_map(|i| match i {
            YieldInput::Image(item) => Some(item.clone()),
            YieldInput::Failed(_) => None,
        })
        .collect();
    progress.set_total(items.len() as u64);
    progress.set_done(0);
    progress.set_message(format!("inspecting {} images", items.len()));
    let mut inspected = run_batch(&items, book, opts, progress).into_iter();
    let results: Vec<ItemResult> = inputs
        .iter()
        .filter_map(|i| match i {
            YieldInput::Image(_) => inspected.next(),
            YieldInput::Failed(failed) => Some((**failed).clone()),
        })
        .collect();
    let report = YieldReport::build(&results, by);
    YieldRun {
        report,
        results,
        cancelled: progress.is_cancelled(),
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}
