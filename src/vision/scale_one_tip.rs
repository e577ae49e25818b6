//! The scale from one tip's own width, the last resort when the recipe has
//! no `mm_per_px` and the pins' lattice gives no scale the inspection can
//! use (fewer than two intact tips are present: a 1 × 3 part with two pins
//! missing, a 1 × 4 with one good tip and one damaged).
//!
//! The lattice search ([`super::scale`]) needs two tips a pitch apart.
//! With one tip there is no pitch, but the recipe gives the tip's size in
//! mm (`pin_mm`), which the spec promises and both renderers draw: a whole
//! tip measured at full resolution gives the scale directly. The
//! housing's size is not used: the Rust generator and the Python renderer
//! size it differently (the spec only says the grid is centred on it).
//!
//! Which blob is the tip: over the same ladder of tip widths as the lattice
//! search, the tip-sized blobs of the coarse search; a tip stands highest
//! in the top-hat at about its own width (a larger box spreads it, a
//! smaller opening keeps only its rim), and the tips are the scene's
//! strongest blobs, so the strongest blob over the ladder is taken, then
//! measured at full resolution as the inspection measures a tip. It must be
//! whole in its window, not elongated, and of 0.5–2 × the area the width
//! it was found at implies; its measured area then gives the width.

use super::detect::{self, Smoothing};
use super::gray::{CoarseCache, Plane, Px};
use super::measure::{self, Localiser, Roi};
use super::recipe::Recipe;
use super::scale::{ScaleStart, TipBlob, W_MIN, area_of_width, tip_blobs, width_of_area};

/// How many of the strongest blobs over the ladder are measured before
/// giving up (a glint or a speck of debris may stand above the tip).
const MAX_TRIED: usize = 4;

/// The tip width in px from the one strongest whole tip, or `None` when no
/// blob measures as a whole tip.
pub(super) fn tip_width<P: Px>(plane: &Plane<P>, sign: f32, recipe: &Recipe) -> Option<f64> {
    let (wd, ht) = (plane.w as f64, plane.h as f64);
    let w_max = (wd.min(ht) / 3.0).max(W_MIN);
    let mut cache = CoarseCache::new(plane, sign);
    // (width tried, blob), the strongest blob at each width.
    let mut best: Vec<(f64, TipBlob)> = Vec::new();
    let mut w = w_max;
    while w >= W_MIN {
        let coarse = cache.get(detect::coarse_factor(w));
        if let Some(b) = tip_blobs(recipe, coarse, w, Smoothing::Normal)
            .into_iter()
            .max_by(|a, b| a.3.total_cmp(&b.3))
        {
            best.push((w, b));
        }
        w /= 1.2;
    }
    best.sort_by(|a, b| b.1.3.total_cmp(&a.1.3));
    let mut seen: Vec<(f64, f64)> = Vec::new();
    for (w, (x, y, _, _, bx)) in best {
        // The same blob found at the next width is not a second try.
        if seen.iter().any(|p| (p.0 - x).hypot(p.1 - y) < 0.5 * w) {
            continue;
        }
        if seen.len() == MAX_TRIED {
            break;
        }
        seen.push((x, y));
        let (margin, dilate) = measure::tip_window(w);
        let roi = Roi::around(bx[0], bx[1], bx[2], bx[3], margin, plane.w, plane.h);
        let Some(m) =
            measure::measure_blob(plane, sign, roi, (x, y), Localiser::default(), dilate, None)
        else {
            continue;
        };
        let r = m.area_px / area_of_width(w, recipe.pin_shape);
        if !m.touches_border && m.elongation < 3.0 && (0.5..=2.0).contains(&r) {
            return Some(width_of_area(m.area_px, recipe.pin_shape));
        }
    }
    None
}

/// The fewest tips in the grid's fit for their pitch to overrule one
/// tip's width: two tips a pitch apart read a bent pin's lean as scale
/// (up to a tenth of the pitch), as the width reads blur.
const MIN_PITCH_TIPS: usize = 3;

/// How far (ratio) the tips' pitch may take the scale from one tip's
/// width: blur and the threshold move a measured width by a tenth or so
/// (Rust 1 260 313: 8.2 px where the pitch says 7.6), a lattice of every
/// other tip by twice.
const MAX_PITCH_OVER_WIDTH: f64 = 1.25;

/// The top view's inspection ([`super::top::inspect_top`]), and when it
/// finds no pins at an estimated scale, once more starting from the scale
/// one whole tip gives ([`tip_width`]), and last with a single tip found
/// allowed to give the scale by its area; the result then says the scale
/// was estimated and from what. Any other outcome stands: an image judged
/// before is judged the same.
///
/// From one tip's width, the tips then found set the scale by their pitch
/// when [`MIN_PITCH_TIPS`] or more fit the grid and their scale lies
/// within [`MAX_PITCH_OVER_WIDTH`] of the width's; otherwise the width's
/// scale is held fixed. Held fixed, a scale 8 % off read twelve of a
/// 4 × 4's sixteen good pins bent (Rust 1 260 313, faint 7.6 px tips the
/// lattice search missed and the inspection then found).
pub(super) fn inspect_top<P: Px>(
    recipe: &Recipe,
    plane: &Plane<P>,
    info: super::gray::ImageInfo,
    full_scale: f32,
    opts: &super::InspectOptions,
) -> Result<super::result::Inspection, super::error::VisionError> {
    use super::top::inspect_top_with;
    let first = super::top::inspect_top(recipe, plane, info.clone(), full_scale, opts);
    if recipe.mm_per_px.is_some() || !matches!(first, Err(super::error::VisionError::NoPins { .. }))
    {
        return first;
    }
    if let Some(w) = tip_width(plane, recipe.polarity.sign(), recipe) {
        let mm_per_px = recipe.pin_mm / w;
        let note = format!(
            "no lattice of tips gives the scale: mm_per_px estimated from one tip's width ({w:.1} px): {mm_per_px:.5}"
        );
        let start = ScaleStart::TipWidth(w);
        if let Ok(mut ins) = inspect_top_with(recipe, plane, info.clone(), full_scale, opts, start)
            && ins.grid.fit_inliers >= MIN_PITCH_TIPS
            && (ins.grid.mm_per_px / mm_per_px).ln().abs() <= MAX_PITCH_OVER_WIDTH.ln()
        {
            ins.warnings.push(format!(
                "{note}, then from the pitch of the {} tips found",
                ins.grid.fit_inliers
            ));
            return Ok(ins);
        }
        let mut one = recipe.clone();
        one.mm_per_px = Some(mm_per_px);
        if let Ok(mut ins) = super::top::inspect_top(&one, plane, info.clone(), full_scale, opts) {
            ins.grid.mm_per_px_estimated = true;
            ins.warnings.push(note);
            return Ok(ins);
        }
    }
    // Last: the inspection at its own estimate, a single tip found on a
    // part of a few positions giving the scale by its area (Rust 955 323,
    // a 1 × 3 with both end pins missing, whose strongest blob over the
    // ladder was no whole tip).
    inspect_top_with(
        recipe,
        plane,
        info,
        full_scale,
        opts,
        ScaleStart::SearchOrOneTip,
    )
    .or(first)
}
