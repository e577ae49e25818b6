//! The top view's candidates: every coarse blob measured at full
//! resolution (two coarse blobs that resolve to one are kept once), and
//! which of a second, fainter pass's tip-like blobs join the first pass's,
//! and the last passes when no pass finds a tip.
//! Kept apart from `top.rs`, which places the lattice and judges.

use super::InspectOptions;
use super::detect::{self, CoarseSearch};
use super::gray::{Plane, Px};
use super::measure::{self, BlobMeasure, Roi};
use super::recipe::Recipe;
use super::tip_levels::{Candidate, MIN_SNR, snr_of};

/// Full-resolution measurement of every coarse blob.
pub(super) fn measure_candidates<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    cs: &CoarseSearch,
    pin_px: f64,
    opts: &InspectOptions,
) -> Vec<(BlobMeasure, Roi, (f64, f64))> {
    measure_blobs(plane, sign, cs, &cs.blobs, pin_px, opts)
}

/// How close (in tip widths) a smaller blob's centre may lie to a larger
/// tip-sized one's before it is taken for a piece of it (0.3 tip widths
/// for any larger blob: the same blob resolved twice).
const SAME_BLOB_TIPS: f64 = 0.5;

/// A blob is tip-sized up to this area in squared tip widths (a square
/// tip is 1, the recipe's damaged limit 1.5). A larger structure (Rust
/// seed 925 198: a dark housing patch of 20 tips' area, 11.6 px from an
/// end tip of 25 px) must not take a whole tip for a piece of itself.
const TIP_SIZED: f64 = 1.5;

/// Full-resolution measurement of `blobs` (of `cs`'s coarse image).
pub(super) fn measure_blobs<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    cs: &CoarseSearch,
    blobs: &[detect::CoarseBlob],
    pin_px: f64,
    opts: &InspectOptions,
) -> Vec<(BlobMeasure, Roi, (f64, f64))> {
    let k = cs.coarse.k as f64;
    let (margin, dilate) = super::measure::tip_window(pin_px);
    let mut out: Vec<(BlobMeasure, Roi, (f64, f64))> = Vec::with_capacity(blobs.len());
    for cb in blobs {
        let b = &cb.blob;
        let roi = Roi::around_coarse(b, k, margin, plane.w, plane.h);
        let seed = cs.coarse.to_full(b.cx, b.cy);
        if let Some(m) = measure::measure_blob(plane, sign, roi, seed, opts.localiser, dilate, None)
        {
            out.push((m, roi, seed));
        }
    }
    // Two coarse blobs can resolve to one blob at full resolution, or the
    // smaller to a piece of the larger: a centre within half a tip of a
    // larger tip-sized blob's lies on that blob. Rust seed 925 116 (a
    // dark tip off centre in its bright hole): the whole tip and a third
    // of it, 3.2 px apart, were both kept; the piece stood nearer the
    // grid's position and was read a damaged pin, the tip itself an
    // extra.
    out.sort_by(|a, b| b.0.area_px.total_cmp(&a.0.area_px));
    let mut kept: Vec<(BlobMeasure, Roi, (f64, f64))> = Vec::with_capacity(out.len());
    for m in out {
        let same = |q: &(BlobMeasure, Roi, (f64, f64))| {
            let d = (q.0.x - m.0.x).hypot(q.0.y - m.0.y);
            let tip_sized = q.0.area_px <= TIP_SIZED * pin_px * pin_px;
            d <= 0.3 * pin_px || (tip_sized && d <= SAME_BLOB_TIPS * pin_px)
        };
        if !kept.iter().any(same) {
            kept.push(m);
        }
    }
    kept
}

/// Debris fainter than the coarse threshold, where it stands clear of its
/// neighbourhood (`top_faint`): added to `cands` (unused, not pin-like) as
/// candidates for the extras only, once every pin is placed, where no
/// candidate lies within half a tip.
pub(super) fn add_faint_debris<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    cs: &CoarseSearch,
    pin_px: f64,
    opts: &InspectOptions,
    cands: &mut Vec<Candidate>,
    used: &mut Vec<bool>,
) {
    let mut faint = super::top_faint::faint_blobs(cs, pin_px);
    faint.extend(super::top_faint::noisy_debris_blobs(cs, pin_px));
    for (m, roi, seed) in measure_blobs(plane, sign, cs, &faint, pin_px, opts) {
        if cands
            .iter()
            .all(|c| (c.m.x - m.x).hypot(c.m.y - m.y) > 0.5 * pin_px)
        {
            cands.push(Candidate {
                m,
                pinlike: false,
                roi,
                seed,
            });
            used.push(false);
        }
    }
}

/// Too few tips: small faint tips under heavy noise peak below the coarse
/// search's noise floor with its usual smoothing box, all of them or only
/// those in a dim part of the frame; a second pass with the wider one
/// (`Smoothing::Faint`) finds them. With no tip at all the second pass
/// replaces the first, and its search is returned to measure from; otherwise
/// the first pass's blobs stay (debris small against a tip is flattened by
/// the wider box) and the second adds its tip-like blobs that stand a
/// pitch from a tip ([`faint_tips_to_add`]). Images whose tips the first
/// pass finds all of are unchanged.
pub(super) fn faint_pass<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
    pin_px: f64,
    candidates: &dyn Fn(&CoarseSearch) -> Vec<Candidate>,
    cands: &mut Vec<Candidate>,
) -> Option<CoarseSearch> {
    let n_pos = recipe.positions().len();
    let n_pinlike = |c: &[Candidate]| c.iter().filter(|c| c.pinlike).count();
    if n_pinlike(cands) >= n_pos {
        return None;
    }
    let cs2 = detect::coarse_search_smoothed(
        plane,
        sign,
        pin_px,
        None,
        Some(n_pos),
        detect::Smoothing::Faint,
    );
    let cands2 = candidates(&cs2);
    if n_pinlike(cands) == 0 {
        if n_pinlike(&cands2) == 0 {
            return None;
        }
        *cands = cands2;
        return Some(cs2);
    }
    let s0 = pin_px / recipe.pin_mm;
    let (px, py) = (recipe.pitch_mm[0] * s0, recipe.pitch_mm[1] * s0);
    let pitch = match (recipe.rows > 1, recipe.cols > 1) {
        (true, true) => (px, py),
        (false, _) => (px, px),
        (true, false) => (py, py),
    };
    let add = faint_tips_to_add(cands, cands2, pin_px, pitch);
    cands.extend(add);
    None
}

/// The second pass's tip-like blobs worth adding to the first pass's
/// candidates: not within half a tip of a blob the first pass has, a
/// contrast of at least [`MIN_SNR`] σ over the noise, and a pitch (±15 %,
/// either axis) from another tip-like blob of either pass: tips stand on
/// the lattice, the fixture's texture and noise rarely do.
pub(super) fn faint_tips_to_add(
    first: &[Candidate],
    second: Vec<Candidate>,
    pin_px: f64,
    pitch_px: (f64, f64),
) -> Vec<Candidate> {
    let new: Vec<Candidate> = second
        .into_iter()
        .filter(|c| {
            c.pinlike
                && snr_of(&c.m) >= MIN_SNR
                && first
                    .iter()
                    .all(|f| (f.m.x - c.m.x).hypot(f.m.y - c.m.y) > 0.5 * pin_px)
        })
        .collect();
    let tips: Vec<(f64, f64)> = first
        .iter()
        .filter(|c| c.pinlike)
        .chain(new.iter())
        .map(|c| (c.m.x, c.m.y))
        .collect();
    new.into_iter()
        .filter(|c| {
            tips.iter()
                .any(|t| at_pitch((t.0 - c.m.x).hypot(t.1 - c.m.y), pitch_px))
        })
        .collect()
}

/// Whether a distance `d` (px) is one of the two pitches (px), ±15 %.
fn at_pitch(d: f64, pitch_px: (f64, f64)) -> bool {
    [pitch_px.0, pitch_px.1]
        .iter()
        .any(|&p| p > 0.0 && (d - p).abs() < 0.15 * p)
}

/// The last passes when neither the usual nor the wider smoothing box
/// finds a tip-like candidate: the search and its candidates of the first
/// pass that finds one, or `None`. `candidates` measures a search's blobs
/// and says which are tip-like.
///
/// 1. The background's closing bounded to a clearance hole's reach
///    ([`detect::Smoothing::HoleReach`]): a one-row housing narrower than
///    the closing's window, on a fixture beyond the tips' level, is filled
///    to the fixture's level by the unbounded closing and its tips vanish
///    from the top-hat.
/// 2. Fixture texture blotchy at the tips' own scale (the Python
///    renderer's, under 40–45 px tips at contrast 0.3) lifts the
///    top-hat's noise floor to the tips' peak: their cores clear it and
///    their windows cut them, or nothing clears it. The search at the tip
///    width and at one and two steps of the scale ladder narrower (the
///    tip still passes whole through the top-hat, the texture's larger
///    blotches less), with its blobs grown to half their peak
///    ([`detect::at_half_peak`]), finds them whole. Grown cores of noise
///    are tip-sized too (pure noise of 256 DN gave "tips" on 65 % of the
///    positions), so this pass counts only when two of its tip-like
///    candidates stand a pitch apart (±15 %, `pitch` in px along x and y):
///    the lattice the scale search already asked of tips.
/// 3. Small faint tips under heavy noise in a dim corner (6.8 px tips at
///    contrast 0.36 and gain 0.6, vignetted by 0.48, σ 13 DN and JPEG:
///    Rust seed 900 064) peak at 4–5 σ of the top-hat's noise with either
///    box, below the 6 σ floor. The wider box with the floor at 4 σ
///    ([`detect::Smoothing::FaintLowFloor`]) finds them, and noise blobs
///    with them; so this pass counts only when a third of the recipe's
///    positions (and two) have a tip-like candidate with another a pitch
///    away, which noise alone at 4 σ does not give.
fn last_resort_search<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    pin_px: f64,
    pitch: (f64, f64),
    n_pos: Option<usize>,
    candidates: &dyn Fn(&CoarseSearch) -> Vec<Candidate>,
) -> Option<(CoarseSearch, Vec<Candidate>)> {
    let tip_like = |c: &[Candidate]| c.iter().any(|c| c.pinlike);
    let hole_reach = detect::coarse_search_smoothed(
        plane,
        sign,
        pin_px,
        None,
        n_pos,
        detect::Smoothing::HoleReach,
    );
    let cands = candidates(&hole_reach);
    if tip_like(&cands) {
        return Some((hole_reach, cands));
    }
    for f in [1.0, 1.0 / 1.2, 1.0 / 1.44] {
        let mut cs = detect::coarse_search(plane, sign, f * pin_px, None, n_pos);
        let reach = (1.5 * pin_px / cs.coarse.k as f64).ceil() as usize;
        let size = (cs.coarse.w, cs.coarse.h);
        cs.blobs = detect::grown_to_half_peak(&cs.tophat, cs.threshold, &cs.blobs, size, reach);
        let cands = candidates(&cs);
        if pitch_pair(&cands, pitch) {
            return Some((cs, cands));
        }
    }
    paired_search(
        plane,
        sign,
        (pin_px, pitch, n_pos),
        candidates,
        detect::Smoothing::FaintLowFloor,
    )
}

/// The search with `smoothing` and its candidates, where a third of the
/// recipe's positions (and two) have a tip-like candidate with another a
/// pitch away; the part is (tip width px, pitch px, positions).
fn paired_search<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    (pin_px, pitch, n_pos): (f64, (f64, f64), Option<usize>),
    candidates: &dyn Fn(&CoarseSearch) -> Vec<Candidate>,
    smoothing: detect::Smoothing,
) -> Option<(CoarseSearch, Vec<Candidate>)> {
    let cs = detect::coarse_search_smoothed(plane, sign, pin_px, None, n_pos, smoothing);
    let cands = candidates(&cs);
    let enough = n_pos.unwrap_or(2).div_ceil(3).max(2);
    (paired_tips(&cands, pitch) >= enough).then_some((cs, cands))
}

/// The last passes ([`last_resort_search`]) where the searches before
/// them found no tip-like candidate, or found some (`current`) of which
/// no two stand a pitch apart on a part of two positions or more: then
/// what they found may be the fixture's texture, the tips lost from the
/// top-hat, and the last passes' candidates replace them only where more
/// of theirs stand a pitch from another than `current` holds tip-like
/// candidates at all. Python seed 720 190: a dark 1 × 18 on a bright
/// housing 2.4 tips tall, on a dark fixture; in the inverted polarity the
/// fixture stands at the tips' level, the unbounded closing filled the
/// housing to it and the tips vanished from the top-hat, while 6 texture
/// blobs of the fixture passed as tips (no two a pitch apart) and made an
/// error ("3 pins lie on the grid but outside the recipe's positions").
/// The hole-reach pass finds the 17 tips, paired. A part whose few tips
/// stand apart (a 1 × 3 without its middle pin) keeps them: the last
/// passes would have to pair more candidates than it has tips.
pub(super) fn last_passes<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    pin_px: f64,
    pitch: (f64, f64),
    n_pos: Option<usize>,
    candidates: &dyn Fn(&CoarseSearch) -> Vec<Candidate>,
    current: &[Candidate],
) -> Option<(CoarseSearch, Vec<Candidate>)> {
    let tips = current.iter().filter(|c| c.pinlike).count();
    if tips > 0 && (n_pos.unwrap_or(0) < 2 || pitch_pair(current, pitch)) {
        return None;
    }
    // The very last: the floor from the image's noise alone
    // ([`detect::Smoothing::NoiseOnlyFloor`]), counted on the terms of
    // the low-floor pass. An image of almost no noise whose top-hat is
    // mostly structure has a spread of that structure, above its tips
    // (Rust 1 280 221: a dark 2 × 2 of 30 px tips in light rims, σ 2 DN, a
    // dark band round the housing, vignetting 0.39: one tip of four
    // cleared the floor and three good pins read bent on a grid at the
    // image's axes). Texture blotchy at the tips' scale clears that floor
    // too, paired a pitch apart by chance (Python seed 650 388): the pass
    // counts only where it holds no more tip-like candidates than the
    // recipe has positions.
    let better =
        |(_, c): &(CoarseSearch, Vec<Candidate>)| tips == 0 || paired_tips(c, pitch) > tips;
    let noise_only = detect::Smoothing::NoiseOnlyFloor;
    let few = |(_, c): &(CoarseSearch, Vec<Candidate>)| {
        c.iter().filter(|c| c.pinlike).count() <= n_pos.unwrap_or(0)
    };
    last_resort_search(plane, sign, pin_px, pitch, n_pos, candidates)
        .filter(better)
        .or_else(|| {
            paired_search(plane, sign, (pin_px, pitch, n_pos), candidates, noise_only).filter(few)
        })
        .filter(better)
}

/// Whether two tip-like candidates stand a pitch apart (within ±15 % of
/// either pitch, px).
fn pitch_pair(cands: &[Candidate], pitch: (f64, f64)) -> bool {
    paired_tips(cands, pitch) >= 2
}

/// How many tip-like candidates have another a pitch away (±15 % of
/// either pitch, px).
fn paired_tips(cands: &[Candidate], pitch: (f64, f64)) -> usize {
    let tips: Vec<(f64, f64)> = cands
        .iter()
        .filter(|c| c.pinlike)
        .map(|c| (c.m.x, c.m.y))
        .collect();
    tips.iter()
        .enumerate()
        .filter(|&(i, a)| {
            tips.iter()
                .enumerate()
                .any(|(j, b)| j != i && at_pitch((a.0 - b.0).hypot(a.1 - b.1), pitch))
        })
        .count()
}

/// Each grid position's candidate: (position → candidate, candidate
/// taken), nearest pairs first within `r_assign` (px) of the position's
/// `nominal` place, a blob under 0.15 of a tip's area (`tip_px`) taken
/// only where no larger one is in reach.
pub(super) fn assign_to_positions(
    nominal: &[(f64, f64)],
    cands: &[Candidate],
    tip_px: f64,
    r_assign: f64,
) -> (Vec<Option<usize>>, Vec<bool>) {
    let mut pairs = Vec::new();
    for (pi, n) in nominal.iter().enumerate() {
        for (ci, c) in cands.iter().enumerate() {
            let d = (c.m.x - n.0).hypot(c.m.y - n.1);
            if d < r_assign {
                let penalty = if c.m.area_px / tip_px < 0.15 {
                    1e6
                } else {
                    0.0
                };
                pairs.push((d + penalty, pi, ci));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pos_cand: Vec<Option<usize>> = vec![None; nominal.len()];
    let mut used = vec![false; cands.len()];
    for (_, pi, ci) in pairs {
        if pos_cand[pi].is_none() && !used[ci] {
            pos_cand[pi] = Some(ci);
            used[ci] = true;
        }
    }
    (pos_cand, used)
}

/// Marks used every candidate within `r` px of `at`: where the empty
/// positions' second look finds a tip, a blob left unassigned at that very
/// place is the same tip measured in another window, not debris beside it.
pub(super) fn use_blobs_at(cands: &[Candidate], used: &mut [bool], at: (f64, f64), r: f64) {
    for (ci, c) in cands.iter().enumerate() {
        if (c.m.x - at.0).hypot(c.m.y - at.1) < r {
            used[ci] = true;
        }
    }
}
