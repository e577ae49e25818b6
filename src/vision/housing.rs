//! The housing's outline in a top view: its four edges found by edge
//! profiles along the lattice axes, starting just outside the outermost
//! pins. The outline anchors the grid when the pins alone cannot, and
//! bounds where an extra counts ([`rect_distance`]).

use super::fit::{self, Similarity};
use super::gray::{Coarse, Plane, Px};
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
        let n = (PROFILE_PITCHES / step) as usize + 3;
        let lines = across_lines(across, k / pitch_across);
        let profiles: Vec<Vec<f32>> = lines
            .iter()
            .map(|&f| {
                (0..n)
                    .map(|i| {
                        let t = start + dir * i as f64 * step;
                        if along_a { sample(t, f) } else { sample(f, t) }
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

/// The housing's pose in the part frame of a grid fit: its rotation and
/// centre relative to the fit's, measured at full resolution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HousingPose {
    /// Rotation of the housing's sides against the fit's axes, radians.
    pub dtheta: f64,
    /// Centre of the outline in the fit's part frame, mm.
    pub centre_mm: (f64, f64),
}

impl HousingPose {
    /// The grid placed on the housing: its centre on the outline's centre,
    /// its axes along the outline's sides, the scale kept.
    pub fn frame(&self, sim: &Similarity) -> Similarity {
        let (tx, ty) = sim.apply(self.centre_mm.0, self.centre_mm.1);
        Similarity {
            s: sim.s,
            theta: sim.theta + self.dtheta,
            tx,
            ty,
        }
    }
}

/// The housing's four sides measured at full resolution in the frame of
/// `sim` (part-frame mm), starting from the coarse outline `rect`
/// ([u0, u1, v0, v1], mm) of a part whose pins span ±`field` mm. Each side
/// is profiled across at up to 41 places along its middle (±60 % of its
/// half length: rounded corners are symmetric and leave the slope and
/// the centre alone), neighbouring profiles are averaged into 4–10
/// segments, in each the outermost strong step (a box difference over
/// ±3 px) is placed to a sub-pixel by a parabola, and a robust line
/// through them gives the side's direction and place. Outermost, not
/// steepest: a housing's edge may have two steps of similar height
/// (fixture → chamfer band → housing), and taking the steeper one let
/// the choice alternate along a side (Rust 840 510). `None` unless all
/// four sides are found with most segments on one straight edge, no
/// side has a nearly strong step beyond the chosen one in many segments
/// (opposite sides could then take different steps and shift the
/// centre by half the chamfer band), and all four agree on the
/// rotation, or three do and the fourth is placed by its points at their
/// slope. This is a ruler independent of the pins: with two or three
/// pins the similarity fit bends its rotation, centre and scale to any
/// one pin's bend, the housing does not.
pub(crate) fn measure_pose<P: Px>(
    plane: &Plane<P>,
    sim: &Similarity,
    rect: [f64; 4],
    field: (f64, f64),
) -> Option<HousingPose> {
    let s = sim.s;
    if !(s > 0.0) || !(rect[1] > rect[0]) || !(rect[3] > rect[2]) {
        return None;
    }
    let at = |u: f64, v: f64| {
        let (x, y) = sim.apply(u, v);
        if x < 0.0 || y < 0.0 || x > (plane.w - 1) as f64 || y > (plane.h - 1) as f64 {
            f32::NAN
        } else {
            plane.bilinear(x, y)
        }
    };
    let step = 0.5 / s;
    // side: (normal along u?, direction, edge, along-range lo, hi, field half)
    let sides = [
        (true, 1.0, rect[1], rect[2], rect[3], field.0),
        (true, -1.0, rect[0], rect[2], rect[3], field.0),
        (false, 1.0, rect[3], rect[0], rect[1], field.1),
        (false, -1.0, rect[2], rect[0], rect[1], field.1),
    ];
    let mut lines = Vec::with_capacity(4);
    for &(normal_u, dir, e0, lo, hi, half) in &sides {
        let margin = dir * e0 - half;
        if !(margin * s > 3.0) {
            return None;
        }
        let (c_o, l_half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let w_in = 0.45 * margin;
        let w_out = (0.45 * margin).max(4.0 / s);
        let n_prof = ((1.2 * l_half * s / 2.0) as usize).clamp(5, 41);
        let n_s = ((w_in + w_out) / step) as usize + 1;
        if n_s < 5 {
            return None;
        }
        let mut profs = Vec::with_capacity(n_prof);
        for j in 0..n_prof {
            let t = c_o + 0.6 * l_half * (2.0 * j as f64 / (n_prof - 1) as f64 - 1.0);
            let prof: Vec<f64> = (0..n_s)
                .map(|i| {
                    let q = e0 - dir * w_in + dir * i as f64 * step;
                    let mut acc = 0.0;
                    for dt in ACROSS_PX {
                        let tt = t + dt / s;
                        acc += if normal_u { at(q, tt) } else { at(tt, q) } as f64;
                    }
                    acc / ACROSS_PX.len() as f64
                })
                .collect();
            if prof.iter().any(|v| !v.is_finite()) {
                return None;
            }
            profs.push((t, prof));
        }
        // Neighbouring profiles averaged into segments, and each segment's
        // step strength by a box difference: one pixel's step of a faint,
        // blurred edge was no larger than the noise.
        let n_seg = (n_prof / PROFILES_PER_SEGMENT).clamp(4, 10);
        let box_w = ((BOX_PX * 2.0) as usize).max(1);
        let signed: Vec<(f64, Vec<f64>)> = (0..n_seg)
            .map(|k| {
                let (a, b) = (k * n_prof / n_seg, (k + 1) * n_prof / n_seg);
                let m = (b - a) as f64;
                let t = profs[a..b].iter().map(|p| p.0).sum::<f64>() / m;
                let prof: Vec<f64> = (0..n_s)
                    .map(|i| profs[a..b].iter().map(|p| p.1[i]).sum::<f64>() / m)
                    .collect();
                (t, box_steps(&prof, box_w))
            })
            .collect();
        let sig_g = step_noise(&signed, box_w);
        let profs: Vec<(f64, Vec<f64>)> = signed
            .into_iter()
            .map(|(t, g)| (t, g.into_iter().map(f64::abs).collect()))
            .collect();
        let n_prof = profs.len();
        let mut gmax: Vec<f64> = profs
            .iter()
            .map(|(_, g)| g.iter().cloned().fold(0.0, f64::max))
            .collect();
        let gref = grid::median(&mut gmax).unwrap_or(0.0);
        // The side's clutter: the typical strength over all its samples,
        // texture, shading and the edge's flanks included (the median of
        // |N(0, σ)| would be 0.674 σ were they noise alone). A step counts
        // as the edge from 0.4 of the side's strongest and 3 × the
        // clutter, but never above 0.6 of the strongest where the noise
        // itself is lower: on a short side (a housing's end beside one
        // row) the edge's flanks fill most of the profile and the clutter
        // read over the edge itself (Rust 1 150 210), while on a long one
        // 3 × the clutter keeps out a lesser step further out (a
        // fixture's edge half as strong, Python 590 271).
        let mut all: Vec<f64> = profs
            .iter()
            .flat_map(|p| p.1.iter().copied())
            .filter(|v| *v > 0.0)
            .collect();
        let clutter = grid::median(&mut all).unwrap_or(0.0) / 0.674;
        let strong = (STRONG_STEP * gref)
            .max(STRONG_SIGMAS * sig_g)
            .max((STRONG_SIGMAS * clutter).min(STRONG_CAP * gref));
        let amb = (AMBIGUOUS_STEP * gref).max(AMBIGUOUS_SIGMAS * clutter);
        let mut n_amb = 0;
        let mut pts = Vec::with_capacity(n_prof);
        for (t, g) in &profs {
            // The outermost strong step: the housing's outline, whether the
            // fixture → chamfer or the chamfer → housing step is steeper.
            let Some(k) = outermost_peak(g, strong) else {
                continue;
            };
            // Another step further out, past the chosen one's flank, that
            // is nearly strong: which step is outermost is then a matter of
            // noise and may differ between opposite sides.
            let beyond = (k + 1..g.len()).find(|&i| g[i] < amb);
            if beyond.is_some_and(|b| outermost_peak(&g[b..], amb).is_some()) {
                n_amb += 1;
            }
            let mut off = 0.0;
            if k > 0 && k + 1 < g.len() {
                let (a, b, c) = (g[k - 1], g[k], g[k + 1]);
                let den = a - 2.0 * b + c;
                if den < 0.0 {
                    off = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
                }
            }
            let q = e0 - dir * w_in + dir * (k as f64 + 1.0 + off) * step;
            pts.push((*t, q));
        }
        if 10 * n_amb > 3 * n_prof {
            return None;
        }
        let fit = fit::robust_line(&pts, 0.75 / s)?;
        let k_in = fit.inlier.iter().filter(|b| **b).count();
        if 10 * k_in < 7 * n_prof || fit.rms * s > 0.5 {
            return None;
        }
        let dtheta = if normal_u { -fit.line.b } else { fit.line.b };
        lines.push((normal_u, fit.line, dtheta, l_half, pts));
    }
    // One side's slope may differ from the others by its noise: a pixel
    // over its measured length.
    let agree = |d: f64, l: f64, mean: f64| (d - mean).abs() <= 0.01_f64.max(1.0 / (1.2 * l * s));
    let mean_of = |skip: Option<usize>| {
        let (mut sw, mut sd) = (0.0, 0.0);
        for (i, &(_, _, d, l, _)) in lines.iter().enumerate() {
            if Some(i) != skip {
                sw += l * l;
                sd += l * l * d;
            }
        }
        sd / sw
    };
    let mut dtheta = mean_of(None);
    if !lines.iter().all(|l| agree(l.2, l.3, dtheta)) {
        // A single side turned against three that agree (an end of the
        // housing beside the orientation mark, whose step pulls part of
        // the side's profiles: Rust 945 509, 0.03 rad off) is placed by
        // its points at the others' slope; more than one, no pose.
        let j = (0..4).find(|&j| {
            let m = mean_of(Some(j));
            (0..4).all(|i| i == j || agree(lines[i].2, lines[i].3, m))
        })?;
        dtheta = mean_of(Some(j));
        let (normal_u, _, _, _, ref pts) = lines[j];
        let b = if normal_u { -dtheta } else { dtheta };
        let mut a: Vec<f64> = pts.iter().map(|&(t, q)| q - b * t).collect();
        lines[j].1 = fit::Line {
            a: grid::median(&mut a)?,
            b,
        };
    }
    // Centre: the mid-line between each pair of opposite sides, taken at
    // the other pair's centre (two passes settle the coupling).
    let (mut cu, mut cv) = (0.5 * (rect[0] + rect[1]), 0.5 * (rect[2] + rect[3]));
    for _ in 0..2 {
        cu = 0.5 * (lines[0].1.y_at(cv) + lines[1].1.y_at(cv));
        cv = 0.5 * (lines[2].1.y_at(cu) + lines[3].1.y_at(cu));
    }
    Some(HousingPose {
        dtheta,
        centre_mm: (cu, cv),
    })
}

/// Signed step strength at each sample c = k + 1 of `prof` (k = 0..len −
/// 2): the difference of the means over `w` samples on either side, c
/// itself left out (0 where a window leaves the profile).
fn box_steps(prof: &[f64], w: usize) -> Vec<f64> {
    let n = prof.len();
    (1..n.saturating_sub(1))
        .map(|c| {
            if c < w || c + w >= n {
                return 0.0;
            }
            let lo: f64 = prof[c - w..c].iter().sum();
            let hi: f64 = prof[c + 1..=c + w].iter().sum();
            (hi - lo) / w as f64
        })
        .collect()
}

/// σ of a segment's step strength, from the differences between
/// neighbouring segments' signed strengths (`box_steps` with half-width
/// `w`): along a straight side they see the same edge and independent
/// noise, so the edge cancels and the median of |difference| is 0.674 √2 σ.
/// Taken from the strengths themselves, the edge's own flanks filled most
/// of a short profile and the noise read 3–5 × high, above the edge
/// (a housing's end beside two or three pins: Rust 1 150 210).
fn step_noise(segments: &[(f64, Vec<f64>)], w: usize) -> f64 {
    let mut d: Vec<f64> = segments
        .windows(2)
        .flat_map(|p| {
            let (a, b) = (&p[0].1, &p[1].1);
            let valid = w.saturating_sub(1)..a.len().saturating_sub(w);
            valid.map(move |i| (a[i] - b[i]).abs())
        })
        .collect();
    grid::median(&mut d).unwrap_or(0.0) / (0.674 * std::f64::consts::SQRT_2)
}

/// Offsets across a side (px) whose samples are averaged into one profile
/// point: a housing edge is straight over a few pixels, the noise is not.
const ACROSS_PX: [f64; 5] = [-2.0, -1.0, 0.0, 1.0, 2.0];

/// Profiles averaged into one segment (4–10 segments a side).
const PROFILES_PER_SEGMENT: usize = 4;

/// Half-width of the box difference giving a step's strength, px.
const BOX_PX: f64 = 3.0;

/// A step counts as the housing's edge from this share of the side's
/// median strongest step, and from this many σ of the step strength's
/// noise and this many times the side's clutter level.
const STRONG_STEP: f64 = 0.4;
const STRONG_SIGMAS: f64 = 3.0;

/// The most of the side's median strongest step the clutter may ask of
/// the edge's step.
const STRONG_CAP: f64 = 0.6;

/// A step further out than the chosen one makes the choice ambiguous from
/// this share of the median strongest step and this many times the side's
/// clutter level.
const AMBIGUOUS_STEP: f64 = 0.25;
const AMBIGUOUS_SIGMAS: f64 = 2.5;

/// Index of the maximum of the outermost run of `g` at least `strong`.
fn outermost_peak(g: &[f64], strong: f64) -> Option<usize> {
    let mut i = (0..g.len()).rev().find(|&i| g[i] >= strong)?;
    let mut best = i;
    while i > 0 && g[i - 1] >= strong {
        i -= 1;
        if g[i] > g[best] {
            best = i;
        }
    }
    Some(best)
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
