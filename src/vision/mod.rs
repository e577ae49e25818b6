//! Connector vision: pin position and defect inspection against a recipe,
//! and batch yield (spec/vision.md). Library only: no terminal code.
//!
//! Entry points:
//! - [`Recipe::load`] — a part number's recipe (TOML).
//! - [`inspect_path`] / [`inspect_bytes`] / [`inspect_gray`] — one image to an
//!   [`Inspection`] (verdict, per-pin rows, fitted grid, extras) or a
//!   [`VisionError`] that says why the image could not be inspected.
//!
//! Module map:
//!
//! | module | holds |
//! |---|---|
//! | [`recipe`] | recipe format and validation |
//! | [`image_io`] | decoding PNG/JPEG/BMP/TIFF, 8/16 bit, grey/colour, with size limits |
//! | [`gray`] | grey images at native precision, block-mean coarse image |
//! | [`morph`] | O(1)-per-pixel opening / top-hat |
//! | [`label`] | run-length connected components with statistics |
//! | [`detect`] | coarse blob search shared by both views |
//! | [`measure`] | sub-pixel blob measurement (localisers, area) |
//! | [`fit`] | robust similarity and line fits |
//! | [`grid`] | lattice estimation and window placement |
//! | [`scale`] | the scale from the pins' lattice when the recipe has no `mm_per_px` |
//! | [`top`], [`side`] | the two views' pipelines |
//! | [`result`] | plain serialisable results |
//! | [`envelope`] | the promised imaging envelope (ranges) |
//! | [`synth`], [`synth_envelope`] | synthetic images with exact truth: fixed scenes, and random draws over the whole envelope |

// Comparisons are written `!(a > b)` on purpose throughout: they are true
// for NaN too, so a degenerate measurement takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod backlight;
pub mod batch;
mod blur_model;
mod blur_tip;
pub mod detect;
pub mod disc;
mod end_level;
pub mod envelope;
pub mod error;
pub mod fit;
pub mod gray;
pub mod grid;
mod housing;
mod housing_pose;
pub mod image_io;
pub mod lab;
pub mod label;
pub mod measure;
pub mod morph;
pub mod overlay;
pub mod recipe;
pub mod report;
pub mod result;
pub mod scale;
mod scale_blobs;
mod scale_one_tip;
mod scale_period;
pub mod side;
mod side_bar;
mod side_edge;
mod side_end;
mod side_place;
mod side_row;
mod surround;
pub mod synth;
pub mod synth_envelope;
pub mod tip_levels;
pub mod top;
mod top_candidates;
mod top_extras;
mod top_faint;
mod top_first_fit;
mod top_fixture;
mod top_noisy;
mod top_not_proven;
mod top_off_hole;
mod top_outline;
mod top_ridge;
mod top_shoulder;
mod top_window;
pub mod truth;
pub mod yield_acc;

pub use error::{ErrorKind, VisionError};
pub use gray::{Gray, GrayData, ImageInfo, Plane};
pub use measure::Localiser;
pub use recipe::{PinShape, Polarity, Recipe, View};
pub use result::{
    ExtraResult, GridFit, Housing, Inspection, PinResult, PinStatus, StatusCounts, Verdict,
};

use std::path::Path;

/// Knobs of the pipeline (defaults are what the CLI uses).
#[derive(Debug, Clone, Default)]
pub struct InspectOptions {
    /// Centre estimator for top-view tips.
    pub localiser: Localiser,
}

/// Inspects a decoded grey image.
pub fn inspect_gray(
    recipe: &Recipe,
    gray: &Gray,
    info: ImageInfo,
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    let (w, h) = (gray.width as usize, gray.height as usize);
    let fs = gray.full_scale();
    match &gray.data {
        GrayData::U8(d) => {
            let p = Plane {
                w,
                h,
                data: d.as_slice(),
            };
            dispatch(recipe, &p, info, fs, opts)
        }
        GrayData::U16(d) => {
            let p = Plane {
                w,
                h,
                data: d.as_slice(),
            };
            dispatch(recipe, &p, info, fs, opts)
        }
    }
}

fn dispatch<P: gray::Px>(
    recipe: &Recipe,
    p: &Plane<P>,
    info: ImageInfo,
    full_scale: f32,
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    let mut ins = match recipe.view {
        View::Top => scale_one_tip::inspect_top(recipe, p, info, full_scale, opts),
        View::Side => side::inspect_side(recipe, p, info, full_scale, opts),
    }?;
    ins.warnings.extend(envelope::notes(&ins));
    Ok(ins)
}

/// Decodes and inspects an image held in memory.
pub fn inspect_bytes(
    recipe: &Recipe,
    bytes: &[u8],
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    let (g, info) = image_io::decode_bytes(bytes)?;
    inspect_gray(recipe, &g, info, opts)
}

/// Reads, decodes and inspects an image file.
pub fn inspect_path(
    recipe: &Recipe,
    path: &Path,
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    let (g, info) = image_io::load_path(path)?;
    inspect_gray(recipe, &g, info, opts)
}
