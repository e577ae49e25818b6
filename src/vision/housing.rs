//! The housing's outline in a top view: its four edges found by edge
//! profiles along the lattice axes, starting just outside the outermost
//! pins. The outline anchors the grid when the pins alone cannot, and
//! bounds where an extra counts ([`rect_distance`]).

use super::gray::Coarse;
use super::grid::{self, Lattice};

/// How far either side of a point the housing edge's step height is read
/// (full-resolution px). Read as the central difference of neighbouring
/// samples, a step blurred over a few pixels held only a slice of its
/// height: Rust seed 925 492 (blur 2.45 px, tips at 147 DN over the
/// housing, the housing 54 DN under the fixture) measured 18 DN against
/// the 22 asked, no edge was found, and with the end pin missing the grid
/// stood a pitch off. Three pixels span a blur σ of 2.5 px's edge.
const STEP_REACH_PX: f64 = 3.0;

/// The same reach in pitches, when longer: a housing's chamfered rim (up
/// to a fifth of a pitch wide) ramps the step over many samples. Rust
/// seed 925 385 (23 px tips, no blur, two pins missing) read 6.5–8 DN of
/// a 22 DN step against the 7.2 asked.
const STEP_REACH_PITCH: f64 = 0.15;

/// Housing edges in lattice units [a0, a1, b0, b1], from edge profiles
/// along the lattice axes starting just outside the outermost pins: per
/// side, the profiles of lines across the pins' field (about one coarse
/// pixel apart) averaged, and the outermost strong step of the mean
/// ([`outermost_step`]); where the mean shows none, the median of the
/// lines' own steps ([`lines_median_step`]).
pub(crate) fn find_housing(
    coarse: &Coarse,
    lat: &Lattice,
    a_span: (i64, i64),
    b_span: (i64, i64),
    pin_px: f64,
    min_step: f32,
) -> Option<[f64; 4]> {
    let k = coarse.k as f64;
    let sample = |a: f64, b: f64| {
        let (x, y) = lat.to_image(a, b);
        let (cx, cy) = coarse.from_full(x, y);
        coarse.bilinear(cx, cy)
    };
    let half_pin_a = (0.5 * pin_px + 2.0) / lat.px;
    let half_pin_b = (0.5 * pin_px + 2.0) / lat.py;
    let off_a = 0.9 * pin_px / lat.px;
    let off_b = 0.9 * pin_px / lat.py;
    // One side's edge: the mean of the profiles along `lines` (fixed
    // coordinates across the axis), then its outermost strong step.
    let side = |along_a: bool, across: (f64, f64), start: f64, dir: f64| -> Option<f64> {
        let (pitch, pitch_across) = if along_a {
            (lat.px, lat.py)
        } else {
            (lat.py, lat.px)
        };
        let step = 0.5 * k / pitch;
        let lines = across_lines(across, k / pitch_across);
        // The profiles end where any line leaves the image: beyond the
        // frame the samples only repeat its border, and a vignetted
        // corner's ramp cut flat there can read as a step, outermost of
        // all (Rust 950 646: a dark 1 × 11 under vignetting 0.46, its
        // far end's profile running 50 px past the frame; the window
        // stood a pitch off, and stands right with the profile ended).
        let at = |i: usize, f: f64| {
            let t = start + dir * i as f64 * step;
            if along_a { (t, f) } else { (f, t) }
        };
        let inside = |(a, b): (f64, f64)| {
            let (x, y) = lat.to_image(a, b);
            let (cx, cy) = coarse.from_full(x, y);
            cx >= 0.0 && cy >= 0.0 && cx <= (coarse.w - 1) as f64 && cy <= (coarse.h - 1) as f64
        };
        let n = (0..(PROFILE_PITCHES / step) as usize + 3)
            .take_while(|&i| lines.iter().all(|&f| inside(at(i, f))))
            .count();
        if n < 3 {
            return None;
        }
        let profiles: Vec<Vec<f32>> = lines
            .iter()
            .map(|&f| {
                (0..n)
                    .map(|i| {
                        let (a, b) = at(i, f);
                        sample(a, b)
                    })
                    .collect()
            })
            .collect();
        let inv = 1.0 / lines.len() as f32;
        let mean: Vec<f32> = (0..n)
            .map(|i| profiles.iter().map(|p| p[i]).sum::<f32>() * inv)
            .collect();
        let i = outermost_step(&mean, min_step, k, pitch)
            .or_else(|| lines_median_step(&profiles, min_step, k, pitch))?;
        Some(start + dir * i * step)
    };
    let b_across = (b_span.0 as f64 - off_b, b_span.1 as f64 + off_b);
    let a_across = (a_span.0 as f64 - off_a, a_span.1 as f64 + off_a);
    let a1 = side(true, b_across, a_span.1 as f64 + half_pin_a, 1.0)?;
    let a0 = side(true, b_across, a_span.0 as f64 - half_pin_a, -1.0)?;
    let b1 = side(false, a_across, b_span.1 as f64 + half_pin_b, 1.0)?;
    let b0 = side(false, a_across, b_span.0 as f64 - half_pin_b, -1.0)?;
    Some([a0, a1, b0, b1])
}

/// How far out from the outermost pins an edge is looked for, in pitches:
/// an end pin missing (one pitch) and a margin of about 1.5 pitches.
const PROFILE_PITCHES: f64 = 2.6;

/// The most profiles averaged for one side.
const MAX_LINES: usize = 48;

/// Lines evenly across `span` (lattice units) about `spacing` apart (one
/// coarse pixel), at most [`MAX_LINES`] and at least two.
fn across_lines(span: (f64, f64), spacing: f64) -> Vec<f64> {
    let len = (span.1 - span.0).max(0.0);
    let n = ((len / spacing.max(1e-9)) as usize + 1).clamp(2, MAX_LINES);
    (0..n)
        .map(|i| span.0 + len * i as f64 / (n - 1) as f64)
        .collect()
}

/// The step reach ([`STEP_REACH_PX`] or [`STEP_REACH_PITCH`] of `pitch`
/// px, the longer) in profile samples, half a coarse pixel (`k` full px)
/// apart.
fn reach_samples(k: f64, pitch: f64) -> usize {
    let reach = STEP_REACH_PX.max(STEP_REACH_PITCH * pitch);
    ((reach / (0.5 * k)).round() as usize).max(1)
}

/// The largest difference between samples of `prof` `gap` apart.
fn max_step(prof: &[f32], gap: usize) -> f32 {
    (0..prof.len().saturating_sub(gap))
        .map(|i| (prof[i + gap] - prof[i]).abs())
        .fold(0f32, f32::max)
}

/// Where (a fractional index into `prof`, samples half a coarse pixel
/// apart, `k` full px per coarse px) the outermost strong step of `prof`
/// lies: the outermost local maximum of the step filter at half its
/// largest value or more, placed by a narrower difference near it. The
/// step filter is the difference of the means over the step reach
/// ([`reach_samples`]) on either side: it reads a blurred or chamfered
/// edge's whole height where a central difference holds a slice of it,
/// and it averages the noise down. With the central difference, the outermost sample at
/// 0.4 of the largest was the noise of the fixture beyond the edge in one
/// profile in three under σ 13–15 DN (Rust 941 473, 961 450: the edge
/// read at the search's end, the housing centre half a pitch off and the
/// grid a pitch off with an end pin missing). `None` when the step falls
/// short of `min_step`.
fn outermost_step(prof: &[f32], min_step: f32, k: f64, pitch: f64) -> Option<f64> {
    let n = prof.len();
    // Each box spans the reach on its side (twice the reach in samples),
    // cut short at the profile's ends down to a quarter of that: an edge
    // close outside the end pin has little housing inside it.
    let w = 2 * reach_samples(k, pitch);
    let least = (w / 4).max(2);
    if n < 2 * least {
        return None;
    }
    let mut sum = vec![0f32; n + 1];
    for (i, v) in prof.iter().enumerate() {
        sum[i + 1] = sum[i] + v;
    }
    let mean = |a: usize, b: usize| (sum[b] - sum[a]) / (b - a) as f32;
    // filter[j]: the step between samples m − 1 and m, m = j + least.
    let filter: Vec<f32> = (least..=n - least)
        .map(|m| (mean(m, (m + w).min(n)) - mean(m.saturating_sub(w), m)).abs())
        .collect();
    let fmax = filter.iter().cloned().fold(0f32, f32::max);
    // Whether there is an edge at all: the filter's step, or the height
    // between single samples up to twice the boxes apart (the boxes lose
    // part of a ramp as long as themselves: Rust 970 155's chamfered edge
    // close outside the end pin read 23 of its 30 DN against 25 asked).
    let height = |gap: usize| max_step(prof, gap);
    if fmax.max(height(2)).max(height(w)).max(height(2 * w)) < min_step {
        return None;
    }
    let mut j = filter.iter().rposition(|&v| v >= 0.5 * fmax)?;
    while j > 0 && filter[j - 1] > filter[j] {
        j -= 1;
    }
    // The filter finds the edge; a narrow difference (of means over a
    // quarter of a box either side, so that the noise the boxes averaged
    // away does not come back) places it, within a box's width either
    // side: the outermost sample at 0.4 of the steepest there. The boxes
    // blur a housing's two steps (fixture → chamfer band → housing) into
    // one between them, 16 px inside the outer one on Rust 945 509 (50 px
    // tips), whose outline then no longer held the pose that judges its
    // bent end pin.
    let h = (w / 4).max(1);
    let m = j + least;
    let (lo, hi) = (m.saturating_sub(w).max(h), (m + w).min(n - h));
    let g = |i: usize| (mean(i + 1, i + 1 + h) - mean(i - h, i)).abs();
    let gmax = (lo..hi).map(g).fold(0f32, f32::max);
    (lo..hi)
        .rev()
        .find(|&i| g(i) >= 0.4 * gmax)
        .map(|i| i as f64)
}

/// Where no step shows in the mean profile (a faint edge on a blotchy
/// fixture, Python 590 171: the lines' edges at different places average
/// away): the median of the lines' own outermost steps at 0.4 of their
/// steepest central difference, the sharp ones where there are any, as
/// each side was read before the profiles were averaged.
fn lines_median_step(profiles: &[Vec<f32>], min_step: f32, k: f64, pitch: f64) -> Option<f64> {
    let d = reach_samples(k, pitch);
    let found: Vec<(f64, bool)> = profiles
        .iter()
        .filter_map(|prof| {
            let n = prof.len();
            let g: Vec<f32> = (1..n - 1)
                .map(|i| (prof[i + 1] - prof[i - 1]).abs())
                .collect();
            let gmax = g.iter().cloned().fold(0f32, f32::max);
            let sharp = gmax >= min_step;
            if !sharp && max_step(prof, 2 * d) < min_step {
                return None;
            }
            let i = g.iter().rposition(|&v| v >= 0.4 * gmax)?;
            Some(((i + 1) as f64, sharp))
        })
        .collect();
    let sharp = found.iter().any(|e| e.1);
    let mut v: Vec<f64> = found
        .iter()
        .filter(|e| e.1 || !sharp)
        .map(|e| e.0)
        .collect();
    grid::median(&mut v)
}

/// Distance of (u, v) from the rectangle [u0, u1] × [v0, v1] (0 inside).
pub(crate) fn rect_distance(u: f64, v: f64, r: [f64; 4]) -> f64 {
    let du = (r[0] - u).max(u - r[1]).max(0.0);
    let dv = (r[2] - v).max(v - r[3]).max(0.0);
    du.hypot(dv)
}

#[cfg(test)]
#[path = "housing_tests.rs"]
mod tests;
