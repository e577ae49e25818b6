//! The image scale when the recipe has no `mm_per_px`: found from the
//! lattice the pins form, not from the image's size.
//!
//! Candidate tip widths are tried over a geometric ladder (ratio 1.2) from
//! what the frame can hold down to 3.5 px (stopping once every position has
//! its neighbour at the pitch). For each, the coarse search
//! ([`super::detect::search_coarse`]) runs with that tip width, the blobs of
//! about a tip's area (0.3–3 tips) and not touching the frame's edge are
//! kept, and the candidate scores the blobs whose nearest neighbour along a
//! row or a column (within ±12°) is
//! at the recipe's pitch *for that tip width* (pitch / pin_mm × width,
//! ±15 %), minus those whose nearest is at half that pitch (a lattice of every
//! other pin is not the lattice). Only candidates whose matched blobs reach
//! 0.35 of the strongest candidate's top-hat peak count (the tips are the
//! scene's strongest blobs; fixture texture forms lattices too), and only a
//! tip-strong one stops the ladder early. Equal scores go to the
//! candidate whose matched blobs stand stronger (a tip peaks in the top-hat
//! at its own width). The best candidate's matched spacings give the pitch
//! in pixels (median), hence the scale; its blobs' median
//! size must agree with the tip width the pitch implies (a factor of 2 at
//! most; blur and threshold widen a blob), which is the cross-check that
//! the lattice found is made of tips.
//!
//! The chosen candidate is then checked at full resolution: its blobs,
//! measured as the inspection measures them at the tip width its spacings
//! imply, must be whole tips of 0.5–2 × that area (a lattice of every
//! other tip, left when pins are missing or damaged, measures a quarter;
//! fragments of large tips run out of their window); one that fails gives
//! way to the next. When no lattice at one pitch holds, spacings of two
//! or three pitches are tried and the tips' own measured width picks the
//! multiple (a 1 × 3 part without its middle pin), and on a grid of two
//! rows and columns or more, diagonal neighbours (a 2 × 2 part with two
//! opposite pins missing).

use super::detect::{self, Smoothing};
use super::error::VisionError;
use super::gray::{Coarse, Plane, Px};
use super::measure::{self, Localiser, Roi};
use super::recipe::Recipe;

/// What the estimate found.
#[derive(Debug, Clone, PartialEq)]
pub struct ScaleEstimate {
    /// Tip width, px.
    pub pin_px: f64,
    /// Pitch along a row (x) in px.
    pub pitch_px: f64,
    /// Blobs with a neighbour at the pitch (the evidence).
    pub support: usize,
    /// Median blob width / tip width from the pitch (1 when the pitch
    /// came from the periodicity).
    pub size_ratio: f64,
    /// The pitch is the pins' periodicity's ([`super::scale_period`]):
    /// the tips stand out as a lattice, not one by one.
    pub from_period: bool,
}

/// Where an inspection of a recipe without `mm_per_px` takes its first
/// scale from ([`super::top::inspect_top_with`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ScaleStart {
    /// The lattice search ([`super::scale::estimate`]).
    Search,
    /// The lattice search, and a single tip found on a part of a few
    /// positions may give the scale by its area.
    SearchOrOneTip,
    /// One tip's measured width, px
    /// ([`super::scale_one_tip::tip_width`]): a prior the pitch of the
    /// tips then found overrules, as it does the search's.
    TipWidth(f64),
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
    /// Centres of the matched blobs, px.
    pts: Vec<(f64, f64)>,
    /// Bounding boxes of the matched blobs, full px [x0, y0, x1, y1].
    boxes: Vec<[f64; 4]>,
}

/// A candidate's matched blobs must reach this share of the strongest
/// candidate's (median top-hat peak) to count.
const PEAK_SHARE: f64 = 0.35;
/// Matched blobs this strong (fraction of full scale) end the search early;
/// the envelope's faintest tips (contrast 0.3, gain 0.6, vignetted to half)
/// stand about 5 % of full scale.
const DONE_PEAK: f64 = 0.03;

pub(super) use super::scale_blobs::{TipBlob, W_MIN, area_of_width, tip_blobs, width_of_area};

#[cfg(test)]
fn score_candidate(recipe: &Recipe, coarse: &Coarse, w: f64, mult: f64) -> Candidate {
    score_blobs(
        recipe,
        &tip_blobs(recipe, coarse, w, Smoothing::Normal),
        w,
        mult,
    )
}

/// Scores the blobs found at tip width `w` as a lattice whose matched
/// neighbours lie `mult` pitches apart.
fn score_blobs(recipe: &Recipe, pts: &[TipBlob], w: f64, mult: f64) -> Candidate {
    let px = mult * w * recipe.pitch_mm[0] / recipe.pin_mm;
    let py = mult * w * recipe.pitch_mm[1] / recipe.pin_mm;
    let tilt = super::grid::MAX_TILT_DEG.to_radians().tan();
    let (mut score, mut support) = (0i64, 0usize);
    let mut spacings = Vec::new();
    let mut widths = Vec::new();
    let mut peaks = Vec::new();
    let mut matched_pts = Vec::new();
    let mut boxes = Vec::new();
    // Blobs sorted by x for a windowed neighbour search.
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0));
    let reach = 1.3 * px.max(py);
    for (oi, &i) in order.iter().enumerate() {
        let (xi, yi, wi, pi, bi) = pts[i];
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
        // (At several pitches apart the pitch itself between is no
        // sub-lattice: those candidates are only tried when no lattice at
        // one pitch holds.)
        let half = mult == 1.0
            && ((recipe.cols > 1 && near(nx, 0.5 * px)) || (recipe.rows > 1 && near(ny, 0.5 * py)));
        if half {
            score -= 1;
            continue;
        }
        let mut matched = false;
        if recipe.cols as f64 > mult && near(nx, px) {
            spacings.push(nx / mult);
            matched = true;
        }
        if recipe.rows as f64 > mult && near(ny, py) {
            spacings.push(ny * px / py / mult);
            matched = true;
        }
        if matched {
            score += 1;
            support += 1;
            widths.push(wi);
            peaks.push(pi);
            matched_pts.push((xi, yi));
            boxes.push(bi);
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
        pts: matched_pts,
        boxes,
    }
}

/// Scores the blobs found at tip width `w` as tips one pitch apart along
/// both axes at once: a grid's diagonal neighbours (a 2 × 2 part with two
/// opposite pins missing has no pair along a row or a column). Spacings
/// are converted to the x pitch.
fn score_diagonal(recipe: &Recipe, pts: &[TipBlob], w: f64) -> Candidate {
    let px = w * recipe.pitch_mm[0] / recipe.pin_mm;
    let py = w * recipe.pitch_mm[1] / recipe.pin_mm;
    let (diag, alpha) = (px.hypot(py), py.atan2(px));
    let tilt = super::grid::MAX_TILT_DEG.to_radians();
    let mut c = score_blobs(recipe, &[], w, 1.0);
    let mut peaks = Vec::new();
    for (i, &(xi, yi, wi, pi, bi)) in pts.iter().enumerate() {
        // Nearest blob further on (+x) whose direction lies within the
        // tilt of either diagonal.
        let d = pts
            .iter()
            .enumerate()
            .filter(|&(j, p)| j != i && p.0 > xi)
            .filter(|(_, p)| {
                let a = (p.1 - yi).atan2(p.0 - xi);
                (a.abs() - alpha).abs() <= tilt
            })
            .map(|(_, p)| (p.0 - xi).hypot(p.1 - yi))
            .fold(f64::INFINITY, f64::min);
        if (d / diag - 1.0).abs() < 0.15 {
            c.score += 1;
            c.support += 1;
            c.spacings.push(d * px / diag);
            c.widths.push(wi);
            peaks.push(pi);
            c.pts.push((xi, yi));
            c.boxes.push(bi);
        }
    }
    c.peak = super::grid::median(&mut peaks).unwrap_or(0.0);
    c
}

/// The most blobs a perfect image of the part can match: positions with a
/// neighbouring position one pitch further along the row or the column
/// (skips left out). A 3 × 2 part matches at most 5 of its 6 tips, a
/// 1 × N part N − 1.
fn most_matched(recipe: &Recipe) -> usize {
    recipe
        .positions()
        .iter()
        .filter(|&&(r, c)| {
            (c + 1 < recipe.cols && !recipe.is_skipped(r, c + 1))
                || (r + 1 < recipe.rows && !recipe.is_skipped(r + 1, c))
        })
        .count()
}

/// Share of `small`'s matched blobs lying inside the tips of `large` (within
/// 0.6 of its tip width of one of its matched blobs).
fn share_inside(small: &Candidate, large: &Candidate) -> f64 {
    if small.pts.is_empty() {
        return 0.0;
    }
    let r2 = (0.6 * large.w).powi(2);
    let inside = small
        .pts
        .iter()
        .filter(|&&(x, y)| {
            large
                .pts
                .iter()
                .any(|&(lx, ly)| (x - lx).powi(2) + (y - ly).powi(2) <= r2)
        })
        .count();
    inside as f64 / small.pts.len() as f64
}

/// The highest score; ties to the stronger matched blobs, then to the
/// larger width (the ladder runs from the largest down).
fn best_candidate(cands: &[Candidate]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, c) in cands.iter().enumerate() {
        if best.is_none_or(|b| {
            c.score > cands[b].score || (c.score == cands[b].score && c.peak > cands[b].peak)
        }) {
            best = Some(i);
        }
    }
    best
}

/// The candidate to try first: the best one ([`best_candidate`]), unless
/// its blobs lie inside the tips of a lattice at twice its width or more:
/// then they are structure of those tips (glints, rim slivers a narrow
/// top-hat leaves of a large tip, fragments of a bevel), not the part. The
/// tips at their own width stand at least as strong in the top-hat as
/// their fragments do, so the larger lattice takes over when its blobs are
/// as strong and hold most of the smaller one's.
fn choose(cands: &[Candidate]) -> Option<usize> {
    let bi = best_candidate(cands)?;
    let b = &cands[bi];
    let mut bigger: Option<usize> = None;
    for (i, c) in cands.iter().enumerate() {
        let holds =
            c.w >= 2.0 * b.w && c.score >= 2 && c.peak >= 0.8 * b.peak && share_inside(b, c) >= 0.5;
        if holds && bigger.is_none_or(|g| c.score > cands[g].score) {
            bigger = Some(i);
        }
    }
    Some(bigger.unwrap_or(bi))
}

/// At most this many of a candidate's blobs are measured at full
/// resolution.
const MAX_CHECKED: usize = 12;

/// A measured tip of this share of the area the candidate implies, or up
/// to its inverse, is a tip of that width (blur and the threshold move a
/// tip's measured area by far less; a lattice of every other tip measures
/// a quarter).
const TIP_AREA_SHARE: f64 = 0.5;

/// Whether the candidate's blobs are tips of the width its spacings imply,
/// measured at full resolution as the inspection measures them (window,
/// dilation and localiser of `top.rs`): at least half the blobs checked
/// (and one) of a tip's area within [`TIP_AREA_SHARE`], whole in their
/// window, not elongated. Returns the median measured area / implied area
/// of those.
fn tips_hold<P: Px>(plane: &Plane<P>, sign: f32, recipe: &Recipe, c: &Candidate) -> Option<f64> {
    let mut sp = c.spacings.clone();
    let pitch_px = super::grid::median(&mut sp)?;
    let s = pitch_px / recipe.pitch_mm[0];
    let pin_px = s * recipe.pin_mm;
    let tip_area = recipe.tip_area_mm2() * s * s;
    let (margin, dilate) = measure::tip_window(pin_px);
    let mut ratios = Vec::new();
    let mut checked = 0usize;
    for (&(x, y), b) in c.pts.iter().zip(&c.boxes).take(MAX_CHECKED) {
        checked += 1;
        let roi = Roi::around(b[0], b[1], b[2], b[3], margin, plane.w, plane.h);
        let Some(m) =
            measure::measure_blob(plane, sign, roi, (x, y), Localiser::default(), dilate, None)
        else {
            continue;
        };
        let r = m.area_px / tip_area;
        if !m.touches_border
            && m.elongation < 3.0
            && (TIP_AREA_SHARE..=1.0 / TIP_AREA_SHARE).contains(&r)
        {
            ratios.push(r);
        }
    }
    if ratios.is_empty() || 2 * ratios.len() < checked {
        return None;
    }
    super::grid::median(&mut ratios)
}

/// Estimates the tip width (px) and the pitch (px) from the image alone.
///
/// When the search finds no lattice of tips, it runs once more with the
/// coarse search's wider smoothing box ([`Smoothing::Faint`]): small faint
/// tips under heavy noise (contrast 0.3, σ 15 DN, 6–7 px tips) peak in
/// the top-hat below the noise floor's 6 σ with a box of half a tip, and
/// clear it with one of four fifths. When that fails too, a third pass
/// searches two steps of the ladder narrower than each width it scores
/// ([`NARROW_SEARCH`]): large tips (40–45 px) on fixture texture blotchy
/// at their own scale stand below the top-hat's noise floor at their own
/// width and clear it at a narrower one. Images whose tips the first pass
/// finds are unchanged.
///
/// When the pass that answers found no lattice whose tips hold at one
/// pitch ([`Held`]), or none at all, the pins' periodicity decides
/// ([`super::scale_period`]): summed over every tip at once, it finds the
/// rows of tips too faint to clear any floor one by one, where the blob
/// passes had fallen back on one unchecked pair of blobs (Rust seed
/// 965 105: a lattice of every other tip, the scale half the truth). A
/// lattice held at two or three pitches gives way only to a finer period
/// by a whole multiple ([`divides`]; a 1 × 3 part without its middle pin
/// has a period of two pitches, and its tips' measured width says so).
/// When the periodicity shows nothing, the pass's answer (or the first
/// pass's error) stands.
pub fn estimate<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
    full_scale: f32,
) -> Result<ScaleEstimate, VisionError> {
    let pass_with = |smoothing, ratio, strongest| {
        estimate_smoothed(plane, sign, recipe, full_scale, smoothing, ratio, strongest)
    };
    let pass = |smoothing, ratio| pass_with(smoothing, ratio, None);
    let period = || super::scale_period::estimate(plane, sign, recipe);
    let (e, held) = match pass(Smoothing::Normal, 1.0) {
        Err(e @ VisionError::NoPins { .. }) => {
            match pass(Smoothing::Faint, 1.0).or_else(|_| pass(Smoothing::Normal, NARROW_SEARCH)) {
                Ok(r) => r,
                Err(_) => return period().ok_or(e),
            }
        }
        r => r?,
    };
    // A lattice matched by more blobs than twice the part's positions is
    // not the part: where texture blobs outnumber the tips, the coarse
    // search's tips' contrast (the median of every blob) is the texture's
    // and a texture lattice wins (Rust 910 811: 2055 blobs beside 10 tips
    // in a 1759 × 2463 frame under σ 2 DN; 151 matched at 3.7 px). The
    // ladder then runs again with the tips' contrast from the strongest
    // blobs, as many as the part has positions. (Not always: where one
    // tip is left among a few positions, the strongest blobs beside it are
    // other structure, whose lattice then wins; Rust 955 323.)
    let n_pos = recipe.positions().len();
    let (e, held) = if e.support > 2 * n_pos {
        pass_with(Smoothing::Normal, 1.0, Some(n_pos)).unwrap_or((e, held))
    } else {
        (e, held)
    };
    Ok(match held {
        Held::Pitch => e,
        // A lattice of two or three pitches held by a fifth of the pairs
        // the part can show is no evidence against the period's: Rust
        // 1 030 443 (2 × 14, 27 pairs; noise 13 DN on a 0.33 contrast)
        // held 35.8 px on one pair where the period read 31.40 px (truth
        // 31.40), and 1 221 068 (1 × 16 with a skip, 13 pairs; contrast
        // 0.44 at gain 0.63, σ 11 DN, blur 2.3 px) 21.8 px on one pair
        // of noise blobs where the period read 32.46 px (truth 32.50):
        // every pin was judged on the wrong grid, or none found. A 1 × 3
        // or 2 × 3 part with pins missing may show one pair only, and
        // there the pair holds (Rust 980 696, 901 293).
        Held::Multiple => period()
            .filter(|p| {
                divides(p.pitch_px, e.pitch_px) || HELD_SHARE * e.support < most_matched(recipe)
            })
            .unwrap_or(e),
        Held::No => period().unwrap_or(e),
    })
}

/// Whether the tips' measured areas (`areas`, each over the tip area the
/// estimated scale expects) allow that scale changed by the factor `f`:
/// area goes as the scale squared, so the median area's log must lie no
/// further from ln f² than from 0 by more than [`AREA_SLACK`].
///
/// Points alone cannot tell a lattice from another when a few of them
/// hold a bent pin: Rust seed 925 232, tips 43.4 and 28.1 px apart (the
/// second pair's tip bent 0.22 pitch), fit a lattice of 23.9 px at 0, 1.82
/// and 3 pitches as well as the estimate's 28 px fits the bent pair; its
/// tips measure 1.48 × the estimate's area, where 23.9 px would make them
/// 0.73 ×, so the estimate stands (the truth, 35.7 px, would be 1.63 ×).
/// A change of 10 % is within what blur and the threshold do to an area:
/// Python seed 730 124's tips (blur 2.2 px) measure 1.12 × where its true
/// lattice, 12 % above the estimate, makes them 1.26 ×.
pub fn areas_allow(areas: &[f64], f: f64) -> bool {
    let mut a: Vec<f64> = areas.iter().copied().filter(|a| *a > 0.0).collect();
    match super::grid::median(&mut a) {
        Some(m) => (m.ln() - 2.0 * f.ln()).abs() < m.ln().abs() + AREA_SLACK,
        None => false,
    }
}

/// How much further (in log area) the tips' median area may sit from a
/// proposed scale than from the estimate ([`areas_allow`]): ±20 %.
const AREA_SLACK: f64 = 0.2;

/// Whether `fine` is a half or a third of `coarse` (±10 %): the only way a
/// lattice of tips held at two or three pitches apart can be wrong is in
/// the multiple (its tips are tips), so a period counts against it only
/// there. (The top-hat's rim of a 35 px tip shows a "period" of a few px:
/// Rust seed 970 565, a 1 × 3 with a damaged pin.)
fn divides(fine: f64, coarse: f64) -> bool {
    [2.0, 3.0]
        .iter()
        .any(|m| (coarse / fine / m - 1.0).abs() < 0.1)
}

/// A lattice held at two or three pitches by fewer than one in this many
/// of the pairs the part can show gives way to the pins' periodicity
/// ([`estimate`]).
const HELD_SHARE: usize = 5;

/// How the lattice a pass chose was checked ([`tips_hold`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Held {
    /// Its tips hold at one pitch apart.
    Pitch,
    /// Its tips hold at two or three pitches apart, or diagonally.
    Multiple,
    /// Its tips do not hold: the best guess.
    No,
}

/// The last pass's search width, as a share of the tip width scored: two
/// steps of the ladder narrower ([`super::scale_blobs::tip_blobs_searched_at`]).
const NARROW_SEARCH: f64 = 1.0 / 1.44;

/// [`estimate`] with one smoothing box for the coarse search, run at
/// `search_ratio` × each tip width tried.
fn estimate_smoothed<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
    full_scale: f32,
    smoothing: Smoothing,
    search_ratio: f64,
    strongest: Option<usize>,
) -> Result<(ScaleEstimate, Held), VisionError> {
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
    // The tip-sized blobs found at each width tried: (width, blobs).
    let mut tried: Vec<(f64, Vec<TipBlob>)> = Vec::new();
    let mut cands: Vec<Candidate> = Vec::new();
    // From the largest candidate down: large ones are cheap (coarse images).
    // Ending the ladder needs nearly every position matched: counted against
    // what the part can match (a small grid's corner tip has no neighbour
    // further on), not against its positions, or a 3 × 2 part never ends
    // it and the ladder runs on into sub-tip structure.
    let n_match = most_matched(recipe).max(1) as f64;
    let mut w = w_max;
    let mut contrast_checked = false;
    let mut blobs_at = |w: f64| -> Result<Vec<TipBlob>, VisionError> {
        let k = detect::coarse_factor(search_ratio * w);
        if coarse_cache[k].is_none() {
            coarse_cache[k] = Some(Coarse::build(plane, k, sign));
        }
        let Some(coarse) = coarse_cache[k].as_ref() else {
            return Ok(Vec::new());
        };
        if !contrast_checked {
            detect::check_contrast(coarse, full_scale)?;
            contrast_checked = true;
        }
        Ok(super::scale_blobs::tip_blobs_searched_at(
            recipe,
            coarse,
            search_ratio * w,
            w,
            smoothing,
            strongest,
        ))
    };
    while w >= W_MIN {
        let pts = blobs_at(w)?;
        let c = score_blobs(recipe, &pts, w, 1.0);
        tried.push((w, pts));
        // Every position of the recipe in a row already, and in blobs of a
        // tip's contrast: no smaller candidate can do better (and smaller
        // ones cost the most). A lattice of faint blobs (fixture texture,
        // vignetting bumps at a large width) does not end the search.
        let done = c.score as f64 >= 0.9 * n_match && c.peak >= DONE_PEAK * full_scale as f64;
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
    // contrast). Among those, the highest score; ties to the stronger
    // blobs. A tip stands highest in the top-hat at its own width: at a
    // larger width the smoothing box spreads it (a lattice of every other
    // tip, when defects leave one spacing at each width, peaked at 0.35
    // of full scale at twice the width and 0.80 at its own), at a smaller
    // one the opening leaves only its rim and glints.
    let top_peak = cands.iter().map(|c| c.peak).fold(0.0, f64::max);
    cands.retain(|c| c.peak >= PEAK_SHARE * top_peak);
    // The choice is then checked at full resolution: its blobs, measured
    // as the inspection measures them at the tip width its spacings imply,
    // must be tips of that width ([`tips_hold`]). A lattice of every other
    // tip (a missing or damaged pin leaves only spacings of two pitches)
    // implies twice the tip width, and the tips measure a quarter of the
    // area it implies; fragments of large tips run out of their window.
    // Such a choice gives way to the next one.
    let mut first: Option<Candidate> = None;
    let mut chosen: Option<Candidate> = None;
    while let Some(bi) = choose(&cands) {
        let c = cands.swap_remove(bi);
        if tips_hold(plane, sign, recipe, &c).is_some() {
            chosen = Some(c);
            break;
        }
        first.get_or_insert(c);
    }
    // No lattice at one pitch holds: pins left only two or three pitches
    // apart (a 1 × 3 part without its middle pin, a 1 × 5 missing one and
    // with one damaged). The spacings are then read as two or three
    // pitches, and the tips' own measured width (the second ruler) decides
    // which: the candidate whose tips measure closest to the width its
    // pitch implies.
    let mut held = if chosen.is_some() {
        Held::Pitch
    } else {
        Held::No
    };
    if chosen.is_none() {
        let n_max = recipe.cols.max(recipe.rows);
        let mut multi: Vec<(Candidate, f64)> = Vec::new();
        let mut w = w_max;
        let mut i = 0;
        while w >= W_MIN {
            if i == tried.len() {
                let pts = blobs_at(w)?;
                tried.push((w, pts));
            }
            let (wt, pts) = &tried[i];
            // 0.0: diagonal neighbours (below).
            for mult in [2.0, 3.0, 0.0] {
                let c = if mult == 0.0 {
                    if recipe.rows < 2 || recipe.cols < 2 {
                        continue;
                    }
                    score_diagonal(recipe, pts, *wt)
                } else if (n_max as f64) <= mult {
                    continue;
                } else {
                    score_blobs(recipe, pts, *wt, mult)
                };
                if c.score > 0
                    && let Some(r) = tips_hold(plane, sign, recipe, &c)
                {
                    multi.push((c, r));
                }
            }
            i += 1;
            w /= 1.2;
        }
        let top = multi.iter().map(|m| m.0.peak).fold(0.0, f64::max);
        multi.retain(|m| m.0.peak >= PEAK_SHARE * top);
        chosen = multi
            .into_iter()
            .max_by(|a, b| {
                a.0.score
                    .cmp(&b.0.score)
                    .then(b.1.ln().abs().total_cmp(&a.1.ln().abs()))
            })
            .map(|m| m.0);
        if chosen.is_some() {
            held = Held::Multiple;
        }
    }
    let Some(b) = chosen.or(first) else {
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
    Ok((
        ScaleEstimate {
            pin_px,
            pitch_px,
            support: b.support,
            size_ratio,
            from_period: false,
        },
        held,
    ))
}

#[cfg(test)]
#[path = "scale_tests.rs"]
pub(super) mod tests;
