//! The tip-sized blobs the scale search ([`super::scale`]) and the
//! one-tip fallback ([`super::scale_one_tip`]) read the scale from: the
//! coarse search's blobs at a trial tip width, measured as footprints.

use super::detect::{self, CoarseBlob, Smoothing};
use super::gray::Coarse;
use super::recipe::{PinShape, Recipe};

/// The smallest share of a tip's area a blob of the search may have.
const MIN_TIP_SHARE: f64 = 0.3;

/// From this coarse factor up (tips tried ≥ 17.5 px wide) the usual
/// passes grow a blob cut below [`MIN_TIP_SHARE`] of a tip to its half
/// peak ([`detect::at_half_peak`]). At such factors a block averages 16
/// pixels or more, so pixel noise no longer cuts cores: a core there is a
/// tip under a noise floor that fixture texture, blotchy at the tips' own
/// scale, lifted to the tips' peak (Python renderer seed 590 094: 41 px
/// tips at contrast 0.32 came through as 0.2–0.3 of a tip, and a lattice
/// of texture blobs at 10 px won the scale). Below it, noise cores
/// grown to tip size formed false lattices (Rust seeds 910 317, 915 247
/// lost pins), so small widths take blobs as found.
const GROW_CORES_FROM_K: usize = 4;

/// Smallest tip width tried, px.
pub(super) const W_MIN: f64 = 3.5;

pub(super) fn width_of_area(a: f64, shape: PinShape) -> f64 {
    match shape {
        PinShape::Square => a.sqrt(),
        PinShape::Round => (4.0 * a / std::f64::consts::PI).sqrt(),
    }
}

/// The area (px²) of a tip `w` px wide: [`width_of_area`]'s inverse.
pub(super) fn area_of_width(w: f64, shape: PinShape) -> f64 {
    match shape {
        PinShape::Square => w * w,
        PinShape::Round => std::f64::consts::PI / 4.0 * w * w,
    }
}

/// A blob touching the frame's edge is no whole tip (the part lies inside
/// the frame), and the top-hat leaves a ridge along an edge the image
/// rises towards (vignetting in a dark-polarity image, a gradient): noise
/// cuts that ridge into blobs evenly spaced along the edge, a lattice at
/// whatever width is tried, which ended the ladder at 2.5–5 × the tip.
pub(super) fn touches_frame(b: &super::label::Blob, coarse: &Coarse) -> bool {
    b.x_min == 0
        || b.y_min == 0
        || b.x_max as usize + 1 >= coarse.w
        || b.y_max as usize + 1 >= coarse.h
}

/// A tip-sized blob of the coarse search: centre, width, top-hat peak and
/// bounding box (full px).
pub(super) type TipBlob = (f64, f64, f64, f64, [f64; 4]);

/// The coarse search at tip width `w` (smoothing box of `smoothing`): the
/// blobs of about a tip's area not touching the frame, as found (not grown:
/// the one-tip fallback takes the strongest blob over the ladder, and a
/// grown core, the strongest part of anything, would win it).
pub(super) fn tip_blobs(
    recipe: &Recipe,
    coarse: &Coarse,
    w: f64,
    smoothing: Smoothing,
) -> Vec<TipBlob> {
    blobs_of(recipe, coarse, w, w, smoothing, false, None)
}

/// The blobs of about the area of a tip `w` px wide, not touching the
/// frame, found by the coarse search run for tips `w_search` px wide
/// (`coarse` built for that width), with the tips' contrast taken from
/// the `strongest` blobs when given (else from them all; see
/// [`super::scale::estimate`]).
///
/// A search narrower than the width scored is the last pass for tips whose
/// own-width search finds nothing: fixture texture blotchy at the tips'
/// scale lifts the top-hat's noise floor to their peak there, while a
/// top-hat a few steps narrower still passes a tip whole and the larger
/// blotches less. Its blobs are grown to half their peak
/// ([`detect::at_half_peak`]): their cores clear the floor, and a core is
/// no tip-sized blob. The usual passes (`w_search == w`) grow only cores
/// at large widths ([`GROW_CORES_FROM_K`]): growing every blob there
/// changed which lattice won on images judged right before (Rust 830 287,
/// a 2 × 2 part with two pins missing, became an error).
pub(super) fn tip_blobs_searched_at(
    recipe: &Recipe,
    coarse: &Coarse,
    w_search: f64,
    w: f64,
    smoothing: Smoothing,
    strongest: Option<usize>,
) -> Vec<TipBlob> {
    blobs_of(
        recipe,
        coarse,
        w_search,
        w,
        smoothing,
        w_search < w,
        strongest,
    )
}

/// [`tip_blobs_searched_at`], its blobs grown to half their peak
/// (`grow`) or only its cores at the coarse factors of large tips
/// ([`GROW_CORES_FROM_K`]).
fn blobs_of(
    recipe: &Recipe,
    coarse: &Coarse,
    w_search: f64,
    w: f64,
    smoothing: Smoothing,
    grow: bool,
    strongest: Option<usize>,
) -> Vec<TipBlob> {
    let found = detect::search_coarse_smoothed(coarse, w_search, None, strongest, smoothing);
    let k = coarse.k as f64;
    let tip_area = area_of_width(w, recipe.pin_shape);
    let reach = (1.5 * w / k).ceil() as usize;
    let size = (coarse.w, coarse.h);
    // (Where 0.35 of the tips' contrast set the threshold, a blob cut
    // small is small: debris, not a tip's core.)
    let grow_cores = coarse.k >= GROW_CORES_FROM_K && found.threshold == found.noise_floor;
    found
        .blobs
        .iter()
        .filter_map(|b: &CoarseBlob| {
            let is_core = (b.blob.area as f64 * k * k) < MIN_TIP_SHARE * tip_area;
            let grown;
            let bb = if grow || (grow_cores && is_core) {
                grown = detect::at_half_peak(&found.tophat, found.threshold, b, size, reach);
                &grown
            } else {
                &b.blob
            };
            let a = bb.area as f64 * k * k;
            let r = a / tip_area;
            let dim = bb.width().max(bb.height()) as f64 * k;
            ((MIN_TIP_SHARE..3.0).contains(&r)
                && dim < 2.5 * w + 2.0 * k
                && !touches_frame(bb, coarse))
            .then(|| {
                let (x, y) = coarse.to_full(bb.cx, bb.cy);
                let bx = [
                    bb.x_min as f64 * k,
                    bb.y_min as f64 * k,
                    (bb.x_max as f64 + 1.0) * k - 1.0,
                    (bb.y_max as f64 + 1.0) * k - 1.0,
                ];
                (x, y, width_of_area(a, recipe.pin_shape), b.peak as f64, bx)
            })
        })
        .collect()
}
