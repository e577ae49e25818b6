//! The housing's pose at full resolution: its sides measured in the
//! frame of a grid fit, giving a rotation and centre the pins do not
//! move. With two or three pins the similarity fit bends its rotation,
//! centre and scale to any one pin's bend; the housing does not. Kept
//! apart from `housing.rs` (the coarse outline it starts from).

use super::fit::{self, Similarity};
use super::gray::{Plane, Px};
use super::grid;

/// The housing's pose in the part frame of a grid fit: its rotation and
/// centre relative to the fit's, measured at full resolution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HousingPose {
    /// Rotation of the housing's sides against the fit's axes, radians.
    pub dtheta: f64,
    /// Centre of the outline in the fit's part frame, mm. Along an axis
    /// whose two ends were not both measured, the fit's own centre (0):
    /// the pins' ([`measure_pose`]).
    pub centre_mm: (f64, f64),
    /// Whether only the two long sides were measured (the centre along
    /// them is then the pins').
    pub long_sides_only: bool,
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

/// One side of the coarse outline to measure, in the frame of a fit.
#[derive(Debug, Clone, Copy)]
struct Side {
    /// Whether the side's normal runs along u (an end of a row along u).
    normal_u: bool,
    /// +1 for the side at the larger coordinate, −1 for the smaller.
    dir: f64,
    /// The coarse edge's place across the side, mm.
    edge: f64,
    /// The side's extent along itself, mm.
    lo: f64,
    hi: f64,
    /// Half the pins' field across the side, mm.
    half: f64,
}

/// Why a side was not measured (kept for tests and diagnosis).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SideFail {
    /// Less than 3 px between the outermost pins and the coarse edge.
    NoMargin,
    /// A profile leaves the image (a tight crop).
    LeavesImage,
    /// No step at all across the side (its profiles are flat).
    NoStep,
    /// Several segments have a nearly strong step beyond the chosen one.
    Ambiguous,
    /// No line through the segments' steps, or too few of them on it.
    NotStraight,
}

/// A side measured: the line through its edge points (across as a
/// function of along, mm), its turn against the fit's axes, its half
/// length and the points.
#[derive(Debug, Clone)]
struct SideLine {
    normal_u: bool,
    line: fit::Line,
    dtheta: f64,
    l_half: f64,
    pts: Vec<(f64, f64)>,
}

/// The housing's sides measured at full resolution in the frame of
/// `sim` (part-frame mm), starting from the coarse outline `rect`
/// ([u0, u1, v0, v1], mm) of a part whose pins span ±`field` mm
/// ([`measure_side`]). With all four sides found, they must agree on the
/// rotation, or three do and the fourth is placed by its points at their
/// slope; the centre is the outline's. Where a side is not found but
/// both of the outline's longer sides are and agree on the rotation, the
/// pose is theirs: the rotation and the centre across them, while along
/// them the centre stays the fit's (the pins'). A housing's end is short
/// beside one row of a few pins, and it is the side most often lost:
/// its profiles leave a tight crop (Rust 1 161 135), or a few segments
/// see the fixture's or the mark's step (1 140 704, 1 151 343, 1 130 205).
/// The long sides alone then hold the rotation a bent pin pulls the
/// pins' fit to (2.7°–4.1° on those parts), and the along-row centre of
/// the pins is half a bend along the row at worst. `None` otherwise.
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
    let at = sampler(plane, sim);
    let side = |normal_u, dir, edge, lo, hi, half| Side {
        normal_u,
        dir,
        edge,
        lo,
        hi,
        half,
    };
    let sides = [
        side(true, 1.0, rect[1], rect[2], rect[3], field.0),
        side(true, -1.0, rect[0], rect[2], rect[3], field.0),
        side(false, 1.0, rect[3], rect[0], rect[1], field.1),
        side(false, -1.0, rect[2], rect[0], rect[1], field.1),
    ];
    let found: Vec<Option<SideLine>> = sides
        .iter()
        .map(|&d| measure_side(&at, s, d).ok())
        .collect();
    if found.iter().all(Option::is_some) {
        let lines: Vec<SideLine> = found.into_iter().flatten().collect();
        return four_sides(lines, rect, s);
    }
    // The pair must be the outline's longer sides: a short end's slope
    // is a pixel over its length, and the ends of a 1 × 3 at 28 px/mm
    // agreed within that on a rotation 0.017 rad off, which put a good
    // end pin a third of its tolerance out (Rust 920 643).
    let long_u = rect[1] - rect[0] >= rect[3] - rect[2];
    let a = if long_u { 2 } else { 0 };
    let (Some(p), Some(q)) = (found[a].clone(), found[a + 1].clone()) else {
        return None;
    };
    // With no third side to outvote either, the two must agree with each
    // other, not merely each with their mean: two long sides 0.032 rad
    // apart passed the looser test and turned a 1 × 4's grid (Rust
    // 920 909).
    if !agree(p.dtheta, p.l_half, s, q.dtheta) {
        return None;
    }
    let dtheta = weighted_turn(&[&p, &q]);
    let across = 0.5 * (p.line.y_at(0.0) + q.line.y_at(0.0));
    let centre_mm = if p.normal_u {
        (across, 0.0)
    } else {
        (0.0, across)
    };
    Some(HousingPose {
        dtheta,
        centre_mm,
        long_sides_only: true,
    })
}

/// The plane sampled at part-frame (u, v) mm through `sim`: bilinear, NaN
/// off the image (a profile that leaves a tight crop is refused, not
/// clamped to the border's samples).
fn sampler<'a, P: Px>(plane: &'a Plane<P>, sim: &'a Similarity) -> impl Fn(f64, f64) -> f32 + 'a {
    move |u, v| {
        let (x, y) = sim.apply(u, v);
        if x < 0.0 || y < 0.0 || x > (plane.w - 1) as f64 || y > (plane.h - 1) as f64 {
            f32::NAN
        } else {
            plane.bilinear(x, y)
        }
    }
}

/// Whether a side's turn `d` (half length `l` mm, at `s` px/mm) is the
/// rotation `mean` within its noise: a pixel over its measured length,
/// and no finer than 0.01 rad.
fn agree(d: f64, l: f64, s: f64, mean: f64) -> bool {
    (d - mean).abs() <= 0.01_f64.max(1.0 / (1.2 * l * s))
}

/// The sides' turns averaged with weights the square of their lengths
/// (a slope's error falls as the length).
fn weighted_turn(lines: &[&SideLine]) -> f64 {
    let (mut sw, mut sd) = (0.0, 0.0);
    for l in lines {
        sw += l.l_half * l.l_half;
        sd += l.l_half * l.l_half * l.dtheta;
    }
    sd / sw
}

/// The pose from four measured sides (in the order of `measure_pose`):
/// all agree on the rotation, or three do and the fourth is placed by
/// its points at their slope; more than one turned, `None`.
fn four_sides(mut lines: Vec<SideLine>, rect: [f64; 4], s: f64) -> Option<HousingPose> {
    let mean_of = |lines: &[SideLine], skip: Option<usize>| {
        let kept: Vec<&SideLine> = (0..4)
            .filter(|&i| Some(i) != skip)
            .map(|i| &lines[i])
            .collect();
        weighted_turn(&kept)
    };
    let mut dtheta = mean_of(&lines, None);
    if !lines.iter().all(|l| agree(l.dtheta, l.l_half, s, dtheta)) {
        // A single side turned against three that agree (an end of the
        // housing beside the orientation mark, whose step pulls part of
        // the side's profiles: Rust 945 509, 0.03 rad off) is placed by
        // its points at the others' slope; more than one, no pose.
        let j = (0..4).find(|&j| {
            let m = mean_of(&lines, Some(j));
            (0..4).all(|i| i == j || agree(lines[i].dtheta, lines[i].l_half, s, m))
        })?;
        dtheta = mean_of(&lines, Some(j));
        let b = if lines[j].normal_u { -dtheta } else { dtheta };
        let mut a: Vec<f64> = lines[j].pts.iter().map(|&(t, q)| q - b * t).collect();
        lines[j].line = fit::Line {
            a: grid::median(&mut a)?,
            b,
        };
    }
    // Centre: the mid-line between each pair of opposite sides, taken at
    // the other pair's centre (two passes settle the coupling).
    let (mut cu, mut cv) = (0.5 * (rect[0] + rect[1]), 0.5 * (rect[2] + rect[3]));
    for _ in 0..2 {
        cu = 0.5 * (lines[0].line.y_at(cv) + lines[1].line.y_at(cv));
        cv = 0.5 * (lines[2].line.y_at(cu) + lines[3].line.y_at(cu));
    }
    Some(HousingPose {
        dtheta,
        centre_mm: (cu, cv),
        long_sides_only: false,
    })
}

/// One side of the housing at full resolution, sampled through `at`
/// (part-frame mm, NaN off the image) at `s` px/mm. The side is profiled
/// across at up to 41 places along its middle (±60 % of its half length:
/// rounded corners are symmetric and leave the slope and the centre
/// alone), neighbouring profiles are averaged into 4–10 segments, in
/// each the outermost strong step (a box difference over ±3 px) is
/// placed to a sub-pixel by a parabola, and a robust line through them
/// gives the side's direction and place. Outermost, not steepest: a
/// housing's edge may have two steps of similar height (fixture →
/// chamfer band → housing), and taking the steeper one let the choice
/// alternate along a side (Rust 840 510). Refused unless most segments
/// lie on one straight edge and few have a nearly strong step beyond
/// the chosen one (opposite sides could then take different steps and
/// shift the centre by half the chamfer band).
fn measure_side(at: &dyn Fn(f64, f64) -> f32, s: f64, side: Side) -> Result<SideLine, SideFail> {
    let Side {
        normal_u,
        dir,
        edge: e0,
        lo,
        hi,
        half,
    } = side;
    let step = 0.5 / s;
    let margin = dir * e0 - half;
    if !(margin * s > 3.0) {
        return Err(SideFail::NoMargin);
    }
    let (c_o, l_half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    let w_in = 0.45 * margin;
    let w_out = (0.45 * margin).max(4.0 / s);
    let n_prof = ((1.2 * l_half * s / 2.0) as usize).clamp(5, 41);
    let n_s = ((w_in + w_out) / step) as usize + 1;
    if n_s < 5 {
        return Err(SideFail::NoMargin);
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
            return Err(SideFail::LeavesImage);
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
    // A flat side (clipped to full scale, or no step at all) has no edge;
    // every sample then passed a threshold of 0, the last one was taken
    // in each segment and made a perfectly straight side (Rust 920 909).
    if !(gref > 0.0) {
        return Err(SideFail::NoStep);
    }
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
        return Err(SideFail::Ambiguous);
    }
    let fit = fit::robust_line(&pts, 0.75 / s).ok_or(SideFail::NotStraight)?;
    let k_in = fit.inlier.iter().filter(|b| **b).count();
    if 10 * k_in < 7 * n_prof || fit.rms * s > 0.5 {
        return Err(SideFail::NotStraight);
    }
    let dtheta = if normal_u { -fit.line.b } else { fit.line.b };
    Ok(SideLine {
        normal_u,
        line: fit.line,
        dtheta,
        l_half,
        pts,
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

#[cfg(test)]
#[path = "housing_pose_tests.rs"]
mod tests;
