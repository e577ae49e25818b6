//! The image scale when the recipe has no `mm_per_px`: found from the
//! lattice the pins form, not from the image's size.
//!
//! Candidate tip widths are tried over a geometric ladder (ratio 1.2) from
//! what the frame can hold down to 3.5 px (stopping once every position has
//! its neighbour at the pitch). For each, the coarse search
//! ([`super::detect::search_coarse`]) runs with that tip width, the blobs of
//! about a tip's area (0.3–3 tips) are kept, and the candidate scores the
//! blobs whose nearest neighbour along a row or a column (within ±12°) is
//! at the recipe's pitch *for that tip width* (pitch / pin_mm × width,
//! ±15 %), minus those whose nearest is at half that pitch (a lattice of every
//! other pin is not the lattice). Only candidates whose matched blobs reach
//! 0.35 of the strongest candidate's top-hat peak count (the tips are the
//! scene's strongest blobs; fixture texture forms lattices too), and only a
//! tip-strong one stops the ladder early. The best candidate's matched spacings
//! give the pitch in pixels (median), hence the scale; its blobs' median
//! size must agree with the tip width the pitch implies (a factor of 2 at
//! most; blur and threshold widen a blob), which is the cross-check that
//! the lattice found is made of tips.

use super::detect::{self, CoarseBlob};
use super::error::VisionError;
use super::gray::{Coarse, Plane, Px};
use super::recipe::{PinShape, Recipe};

/// What the estimate found.
#[derive(Debug, Clone, PartialEq)]
pub struct ScaleEstimate {
    /// Tip width, px.
    pub pin_px: f64,
    /// Pitch along a row (x) in px.
    pub pitch_px: f64,
    /// Blobs with a neighbour at the pitch (the evidence).
    pub support: usize,
    /// Median blob width / tip width from the pitch.
    pub size_ratio: f64,
}

struct Candidate {
    score: i64,
    support: usize,
    /// Matched neighbour spacings, converted to the x pitch, px.
    spacings: Vec<f64>,
    widths: Vec<f64>,
    w: f64,
    /// Median top-hat peak of the matched blobs.
    peak: f64,
}

/// A candidate's matched blobs must reach this share of the strongest
/// candidate's (median top-hat peak) to count.
const PEAK_SHARE: f64 = 0.35;
/// Matched blobs this strong (fraction of full scale) end the search early;
/// the envelope's faintest tips (contrast 0.3, gain 0.6, vignetted to half)
/// stand about 5 % of full scale.
const DONE_PEAK: f64 = 0.03;

/// Smallest tip width tried, px.
const W_MIN: f64 = 3.5;

fn width_of_area(a: f64, shape: PinShape) -> f64 {
    match shape {
        PinShape::Square => a.sqrt(),
        PinShape::Round => (4.0 * a / std::f64::consts::PI).sqrt(),
    }
}

fn score_candidate(recipe: &Recipe, coarse: &Coarse, w: f64) -> Candidate {
    let found = detect::search_coarse(coarse, w, None);
    let k = coarse.k as f64;
    let tip_area = match recipe.pin_shape {
        PinShape::Square => w * w,
        PinShape::Round => std::f64::consts::PI / 4.0 * w * w,
    };
    let pts: Vec<(f64, f64, f64, f64)> = found
        .blobs
        .iter()
        .filter_map(|b: &CoarseBlob| {
            let a = b.blob.area as f64 * k * k;
            let r = a / tip_area;
            let dim = b.blob.width().max(b.blob.height()) as f64 * k;
            ((0.3..3.0).contains(&r) && dim < 2.5 * w + 2.0 * k).then(|| {
                let (x, y) = coarse.to_full(b.blob.cx, b.blob.cy);
                (x, y, width_of_area(a, recipe.pin_shape), b.peak as f64)
            })
        })
        .collect();
    let px = w * recipe.pitch_mm[0] / recipe.pin_mm;
    let py = w * recipe.pitch_mm[1] / recipe.pin_mm;
    let tilt = super::grid::MAX_TILT_DEG.to_radians().tan();
    let (mut score, mut support) = (0i64, 0usize);
    let mut spacings = Vec::new();
    let mut widths = Vec::new();
    let mut peaks = Vec::new();
    // Blobs sorted by x for a windowed neighbour search.
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0));
    let reach = 1.3 * px.max(py);
    for (oi, &i) in order.iter().enumerate() {
        let (xi, yi, wi, pi) = pts[i];
        // Nearest blob in the +x cone and in the ±y cone (within ±12°).
        let (mut nx, mut ny) = (f64::INFINITY, f64::INFINITY);
        let lo = order[..oi]
            .iter()
            .rposition(|&j| xi - pts[j].0 > reach)
            .map_or(0, |p| p + 1);
        for &j in order[lo..].iter() {
            if j == i {
                continue;
            }
            let (dx, dy) = (pts[j].0 - xi, pts[j].1 - yi);
            if dx > reach {
                break;
            }
            let d = dx.hypot(dy);
            if dx > 0.0 && dy.abs() <= tilt * dx {
                nx = nx.min(d);
            }
            if dy > 0.0 && dx.abs() <= tilt * dy {
                ny = ny.min(d);
            }
        }
        let near = |d: f64, p: f64| (d / p - 1.0).abs() < 0.15;
        let half =
            (recipe.cols > 1 && near(nx, 0.5 * px)) || (recipe.rows > 1 && near(ny, 0.5 * py));
        if half {
            score -= 1;
            continue;
        }
        let mut matched = false;
        if recipe.cols > 1 && near(nx, px) {
            spacings.push(nx);
            matched = true;
        }
        if recipe.rows > 1 && near(ny, py) {
            spacings.push(ny * px / py);
            matched = true;
        }
        if matched {
            score += 1;
            support += 1;
            widths.push(wi);
            peaks.push(pi);
        }
    }
    let peak = super::grid::median(&mut peaks).unwrap_or(0.0);
    Candidate {
        score,
        support,
        spacings,
        widths,
        w,
        peak,
    }
}

/// Estimates the tip width (px) and the pitch (px) from the image alone.
pub fn estimate<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
    full_scale: f32,
) -> Result<ScaleEstimate, VisionError> {
    let no_pins = |msg: String| VisionError::NoPins {
        part: recipe.part_number.clone(),
        msg,
    };
    let (wd, ht) = (plane.w as f64, plane.h as f64);
    // Largest tip the frame can hold: the grid fits in the image.
    let n_x = recipe.cols.max(1) as f64;
    let n_y = recipe.rows.max(1) as f64;
    let fit_x = wd.max(ht) / (n_x * recipe.pitch_mm[0] / recipe.pin_mm);
    let fit_y = wd.max(ht) / (n_y * recipe.pitch_mm[1] / recipe.pin_mm);
    let w_max = (1.15 * fit_x.min(fit_y)).min(wd.min(ht) / 3.0).max(W_MIN);
    let mut coarse_cache: Vec<Option<Coarse>> = vec![None; 9];
    let mut cands: Vec<Candidate> = Vec::new();
    // From the largest candidate down: large ones are cheap (coarse images).
    let n_pos = recipe.positions().len() as f64;
    let mut w = w_max;
    let mut contrast_checked = false;
    while w >= W_MIN {
        let k = detect::coarse_factor(w);
        if coarse_cache[k].is_none() {
            coarse_cache[k] = Some(Coarse::build(plane, k, sign));
        }
        let Some(coarse) = coarse_cache[k].as_ref() else {
            break;
        };
        if !contrast_checked {
            detect::check_contrast(coarse, full_scale)?;
            contrast_checked = true;
        }
        let c = score_candidate(recipe, coarse, w);
        // Every position of the recipe in a row already, and in blobs of a
        // tip's contrast: no smaller candidate can do better (and smaller
        // ones cost the most). A lattice of faint blobs (fixture texture,
        // vignetting bumps at a large width) does not end the search.
        let done = c.score as f64 >= 0.9 * n_pos && c.peak >= DONE_PEAK * full_scale as f64;
        if c.score > 0 {
            cands.push(c);
        }
        if done {
            break;
        }
        w /= 1.2;
    }
    // The tips are the scene's strongest blobs: a candidate counts only if
    // its matched blobs stand at least `PEAK_SHARE` of the strongest
    // candidate's (a lattice of texture blobs at 5 × the tip width scores
    // as many neighbours as the few pins but at a hundredth of their
    // contrast). Among those, the highest score; ties to the larger width.
    let top_peak = cands.iter().map(|c| c.peak).fold(0.0, f64::max);
    let mut best: Option<Candidate> = None;
    for c in cands {
        if c.peak >= PEAK_SHARE * top_peak && best.as_ref().is_none_or(|b| c.score > b.score) {
            best = Some(c);
        }
    }
    let Some(b) = best else {
        return Err(no_pins(format!(
            "no tip-sized blobs in a row at the recipe's pitch-to-tip ratio ({:.2}) for any tip width from {W_MIN} to {w_max:.0} px (mm_per_px absent, so the scale had to be found)",
            recipe.pitch_mm[0] / recipe.pin_mm
        )));
    };
    let mut sp = b.spacings.clone();
    let pitch_px = super::grid::median(&mut sp).unwrap_or(b.w * recipe.pitch_mm[0] / recipe.pin_mm);
    let pin_px = pitch_px * recipe.pin_mm / recipe.pitch_mm[0];
    let mut ws = b.widths.clone();
    let size_ratio = super::grid::median(&mut ws).unwrap_or(pin_px) / pin_px;
    if !(0.5..=2.0).contains(&size_ratio) {
        return Err(no_pins(format!(
            "the blobs in a row at the recipe's pitch ({pitch_px:.1} px) are {size_ratio:.2} times the tip width that pitch implies: no consistent scale (mm_per_px absent)"
        )));
    }
    Ok(ScaleEstimate {
        pin_px,
        pitch_px,
        support: b.support,
        size_ratio,
    })
}
