//! The tip-sized blobs the scale search ([`super::scale`]) and the
//! one-tip fallback ([`super::scale_one_tip`]) read the scale from: the
//! coarse search's blobs at a trial tip width, measured as footprints.

use super::detect::{self, CoarseBlob, Smoothing};
use super::gray::Coarse;
use super::recipe::{PinShape, Recipe};

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
/// blobs of about a tip's area not touching the frame.
pub(super) fn tip_blobs(
    recipe: &Recipe,
    coarse: &Coarse,
    w: f64,
    smoothing: Smoothing,
) -> Vec<TipBlob> {
    tip_blobs_searched_at(recipe, coarse, w, w, smoothing)
}

/// The blobs of about the area of a tip `w` px wide, not touching the
/// frame, found by the coarse search run for tips `w_search` px wide
/// (`coarse` built for that width). Blobs the search's threshold cut above
/// their half peak are grown to it ([`detect::at_half_peak`]), so a blob's
/// area is its footprint, not how far it clears the noise floor.
///
/// A search narrower than the width scored is the fallback for tips whose
/// own-width search finds nothing: fixture texture blotchy at the tips'
/// scale lifts the top-hat's noise floor above their peak there, while a
/// top-hat a few steps narrower still passes a tip whole and the larger
/// blotches less.
pub(super) fn tip_blobs_searched_at(
    recipe: &Recipe,
    coarse: &Coarse,
    w_search: f64,
    w: f64,
    smoothing: Smoothing,
) -> Vec<TipBlob> {
    let found = detect::search_coarse_smoothed(coarse, w_search, None, None, smoothing);
    let k = coarse.k as f64;
    let tip_area = area_of_width(w, recipe.pin_shape);
    let reach = (1.5 * w / k).ceil() as usize;
    found
        .blobs
        .iter()
        .map(|b: &CoarseBlob| CoarseBlob {
            blob: detect::at_half_peak(
                &found.tophat,
                found.threshold,
                b,
                (coarse.w, coarse.h),
                reach,
            ),
            peak: b.peak,
        })
        .filter_map(|b: CoarseBlob| {
            let a = b.blob.area as f64 * k * k;
            let r = a / tip_area;
            let dim = b.blob.width().max(b.blob.height()) as f64 * k;
            ((0.3..3.0).contains(&r) && dim < 2.5 * w + 2.0 * k && !touches_frame(&b.blob, coarse))
                .then(|| {
                    let (x, y) = coarse.to_full(b.blob.cx, b.blob.cy);
                    let bb = &b.blob;
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
