//! Centre of a blurred tip from a model of the tip in its clearance hole.
//!
//! Under defocus a tip's edge spreads over several pixels, and so do the
//! edges around it: the dark clearance gap and the housing beyond. A tip
//! that stands off-centre in its hole (an ok pin near the position limit)
//! has the housing close on one side and the gap wide on the other, so the
//! blurred housing light lifts the foot of the near edge only. Any centroid
//! of the tip's own pixels (coverage, thresholded, intensity) moves towards
//! the housing, i.e. outward — the offset is over-stated exactly where it
//! decides bent against ok (0.3–0.4 px at blur σ 2–2.5 px).
//!
//! The fix is to model what is there instead of hoping it cancels: the
//! blurred image around a tip is
//!
//! ```text
//! I(x) = a0 + gx·x + gy·y + a_hole · B_σ[hole](x − n) + a_tip · B_σ[tip](x − c)
//! ```
//!
//! with `B_σ[shape]` the shape's indicator convolved with a Gaussian of σ
//! (closed form with erf: a square is a product of two erf differences in
//! the part's axes, a disc is approximated radially), `n` the hole's centre
//! (the fitted nominal position: the hole is machined there, the pin
//! deviates from it), `c` the tip's centre. The levels and the background
//! plane are linear and solved exactly for each trial of the non-linear
//! parameters (c, tip half-width, hole half-width, σ), which a damped
//! Gauss–Newton (Levenberg–Marquardt) iteration fits. Both shapes are
//! symmetric about their own centres, so what the model does not describe
//! (a dome on the tip, rounded corners, a slightly different hole shape)
//! is symmetric too and does not move `c` to first order; what moved the
//! centroid — the housing's light — is now part of the model.

use super::blur_model::{Eval, NP, Params, Samples, evaluate, solve_sym};
use super::fit::Similarity;
use super::gray::{Plane, Px};
use super::recipe::{PinShape, Recipe};
use super::tip_levels::Candidate;

/// Edge spread (px, the tips' median) above which the model replaces the
/// coverage centroid; below it the coverage centroid is exact already.
pub(crate) const MIN_SIGMA_PX: f64 = 0.8;

/// Refines the centres of the intact tips `intact` ((position, candidate)
/// pairs) in place; returns the pairs whose fit settled. `nominal` holds the
/// positions' fitted nominal centres (the holes' centres), px.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine_centres<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
    sim: &Similarity,
    nominal: &[(f64, f64)],
    intact: &[(usize, usize)],
    cands: &mut [Candidate],
    blur_sigma: f64,
    min_pitch_px: f64,
) -> Vec<(usize, usize)> {
    let half_w = 0.5 * recipe.pin_mm * sim.s;
    let fit_at = |pi: usize, start: (f64, f64), sigma: Option<f64>| {
        let mut prior = prior_at(recipe, sim, nominal[pi], blur_sigma, min_pitch_px);
        prior.fixed_sigma = sigma;
        fit_tip(plane, sign, start, &prior)
    };
    let centroid = |ci: usize| (cands[ci].m.x, cands[ci].m.y);
    let first: Vec<Option<TipFit>> = intact
        .iter()
        .map(|&(pi, ci)| fit_at(pi, centroid(ci), None))
        .collect();
    let part_sigma = common_sigma(&first);
    let mut done = Vec::with_capacity(intact.len());
    for (&(pi, ci), f) in intact.iter().zip(first) {
        let c = (cands[ci].m.x, cands[ci].m.y);
        let f = match part_sigma {
            Some(sg) => fit_at(pi, c, Some(sg)),
            None => f,
        };
        let Some(f) = f else {
            continue;
        };
        // A fit that moved off the tip has locked onto something else (a
        // neighbour, the housing): keep the centroid.
        if !settled_on_the_same_tip(c, (f.x, f.y), nominal[pi], half_w) {
            continue;
        }
        let m = &mut cands[ci].m;
        m.x = f.x;
        m.y = f.y;
        done.push((pi, ci));
    }
    done
}

/// Fewest free fits whose median σ is the part's blur.
const MIN_FITS_FOR_COMMON_SIGMA: usize = 3;

/// The part's blur σ: the median of the tips' own fitted σ, from at least
/// [`MIN_FITS_FOR_COMMON_SIGMA`] fits (else `None`, and each tip keeps its
/// own).
///
/// Why the tips are then fitted again with σ held there: one lens blurs the
/// whole part, but a single tip's free σ also absorbs what the model does not
/// describe (the specular dome, the edge ramp, the housing's texture), and on
/// a tip off-centre in its hole σ trades against the centre along the offset.
/// Bent tips of 1 × 3 – 1 × 7 parts fitted σ 1.3–2.2 × the part's and moved
/// 0.5–1.4 px back towards the hole, so bent pins read ok (Rust 820 148,
/// 820 699, 830 710, 890 466); with σ held at the part's median their centres
/// came within 0.03–0.3 px of the truth.
fn common_sigma(fits: &[Option<TipFit>]) -> Option<f64> {
    let mut sigmas: Vec<f64> = fits.iter().flatten().map(|f| f.sigma).collect();
    if sigmas.len() < MIN_FITS_FOR_COMMON_SIGMA {
        return None;
    }
    sigmas.sort_by(|a, b| a.total_cmp(b));
    Some(sigmas[sigmas.len() / 2])
}

/// The model's prior for the tip in the hole centred at `hole` (px): the
/// recipe's tip at the fitted scale and rotation, the tips' edge spread,
/// and a window holding the tip, its hole and the blur, within half a pitch.
pub(crate) fn prior_at(
    recipe: &Recipe,
    sim: &Similarity,
    hole: (f64, f64),
    blur_sigma: f64,
    min_pitch_px: f64,
) -> TipPrior {
    let half_w = 0.5 * recipe.pin_mm * sim.s;
    TipPrior {
        round: recipe.pin_shape == PinShape::Round,
        theta: sim.theta,
        half_w,
        sigma: blur_sigma,
        hole,
        window: (1.5 * half_w + 3.0 * blur_sigma + 2.0).min(0.5 * min_pitch_px),
        fixed_sigma: None,
    }
}

/// Whether the model's centre `fit` is still the tip whose coverage
/// centroid is `centroid`, in the hole centred at `hole` (px).
///
/// A small move is always the same tip. A larger one is the same tip only
/// when it goes where the bias the model removes points: the blurred
/// housing's light pulls the centroid away from the hole's centre, so the
/// fit moves back towards it — mostly along the line to the hole, ending
/// nearer the hole, by at most the tip's half-width. On small tips under
/// strong blur (6–7 px tips, σ ≈ 1.1 px) that bias reaches 1–1.5 px, past
/// the fixed bound, and good pins near the limit read bent (Rust 860 040).
/// A fit that locked onto a neighbour or the housing moves
/// elsewhere or further and is refused.
fn settled_on_the_same_tip(
    centroid: (f64, f64),
    fit: (f64, f64),
    hole: (f64, f64),
    half_w: f64,
) -> bool {
    let (sx, sy) = (fit.0 - centroid.0, fit.1 - centroid.1);
    let shift = sx.hypot(sy);
    if shift <= 0.2 * half_w + 0.5 {
        return true;
    }
    let (hx, hy) = (hole.0 - centroid.0, hole.1 - centroid.1);
    let to_hole = hx.hypot(hy);
    let towards = (sx * hx + sy * hy) / to_hole.max(1e-9);
    let fit_to_hole = (fit.0 - hole.0).hypot(fit.1 - hole.1);
    shift <= half_w && towards >= 0.8 * shift && fit_to_hole < to_hole
}

/// What the fit knows before it starts.
#[derive(Debug, Clone, Copy)]
pub struct TipPrior {
    /// Round tip and hole (disc) or square ones.
    pub round: bool,
    /// The part's rotation (radians), image axes.
    pub theta: f64,
    /// The nominal tip's half-width, px.
    pub half_w: f64,
    /// The edge spread measured on the tips, px (start value of σ).
    pub sigma: f64,
    /// The hole's centre (the fitted nominal position), px.
    pub hole: (f64, f64),
    /// Half-size of the square window around `hole`, px.
    pub window: f64,
    /// σ held here instead of fitted (the part's blur, [`common_sigma`]).
    pub fixed_sigma: Option<f64>,
}

/// The fitted tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipFit {
    pub x: f64,
    pub y: f64,
    pub half_w: f64,
    pub hole_half: f64,
    pub sigma: f64,
    /// Tip level above the hole's (sign space).
    pub a_tip: f64,
    /// RMS residual of the fit (sample units).
    pub rms: f64,
}

fn clamp_params(p: &mut Params, prior: &TipPrior) {
    let w0 = prior.half_w;
    p[2] = p[2].clamp(0.6 * w0, 1.5 * w0);
    p[3] = p[3].clamp(p[2] + 0.05, 3.0 * w0 + 1.0);
    p[4] = match prior.fixed_sigma {
        Some(sg) => sg,
        None => p[4].clamp(0.2, 3.0 * prior.sigma.max(0.5) + 1.0),
    };
}

/// Fits the tip model around `prior.hole`, starting from the tip centre
/// `start` (px). `None` when the window is too small or the fit does not
/// settle on a tip brighter than its hole.
pub fn fit_tip<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    start: (f64, f64),
    prior: &TipPrior,
) -> Option<TipFit> {
    let (hx, hy) = prior.hole;
    let r = prior.window;
    let x0 = (hx - r).floor().max(0.0) as usize;
    let y0 = (hy - r).floor().max(0.0) as usize;
    let x1 = ((hx + r).ceil() as usize + 1).min(plane.w);
    let y1 = ((hy + r).ceil() as usize + 1).min(plane.h);
    if x1 <= x0 + 4 || y1 <= y0 + 4 {
        return None;
    }
    // Large windows are sampled on a sparser grid: the fit needs the
    // edges' shape, not every pixel (cost ∝ samples).
    let stride = (((x1 - x0) * (y1 - y0)) as f64 / 1500.0)
        .sqrt()
        .ceil()
        .max(1.0) as usize;
    let (sn, cs) = prior.theta.sin_cos();
    let mut s = Samples::default();
    for y in (y0..y1).step_by(stride) {
        for x in (x0..x1).step_by(stride) {
            let (dx, dy) = (x as f64 - hx, y as f64 - hy);
            s.u.push(cs * dx + sn * dy);
            s.v.push(-sn * dx + cs * dy);
            s.x.push(dx / r);
            s.y.push(dy / r);
            s.val.push((sign * plane.data[y * plane.w + x].f()) as f64);
        }
    }
    let (dx, dy) = (start.0 - hx, start.1 - hy);
    let mut p: Params = [
        cs * dx + sn * dy,
        -sn * dx + cs * dy,
        prior.half_w,
        1.25 * prior.half_w + 0.5,
        prior.sigma.max(0.5),
    ];
    clamp_params(&mut p, prior);
    let fit_sigma = prior.fixed_sigma.is_none();
    let mut cur = Eval::default();
    let mut trial = Eval::default();
    evaluate(&s, prior.round, &p, &mut cur)?;
    let mut lambda = 1e-3;
    for _ in 0..15 {
        let mut jtj = [[0f64; NP]; NP];
        let mut jtr = [0f64; NP];
        for a in 0..NP {
            for b in a..NP {
                jtj[a][b] = cur.jac[a].iter().zip(&cur.jac[b]).map(|(x, y)| x * y).sum();
                jtj[b][a] = jtj[a][b];
            }
            jtr[a] = -cur.jac[a]
                .iter()
                .zip(&cur.res)
                .map(|(x, y)| x * y)
                .sum::<f64>();
        }
        // A held σ takes no step: its row and column are the identity's.
        if !fit_sigma {
            for a in 0..NP {
                jtj[a][4] = 0.0;
                jtj[4][a] = 0.0;
            }
            jtj[4][4] = 1.0;
            jtr[4] = 0.0;
        }
        let mut improved = false;
        let mut step_len = 0.0;
        for _ in 0..8 {
            let mut m = jtj;
            for (i, row) in m.iter_mut().enumerate() {
                row[i] += lambda * jtj[i][i].max(1e-9);
            }
            let Some(step) = solve_sym(m, jtr) else {
                lambda *= 10.0;
                continue;
            };
            let mut q = p;
            for i in 0..NP {
                q[i] += step[i];
            }
            clamp_params(&mut q, prior);
            // The trial carries its Jacobian: most trials are taken.
            if evaluate(&s, prior.round, &q, &mut trial).is_some() && trial.ss < cur.ss {
                step_len = (q[0] - p[0]).hypot(q[1] - p[1]);
                p = q;
                std::mem::swap(&mut cur, &mut trial);
                lambda = (lambda * 0.3).max(1e-7);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved || step_len < 1e-3 {
            break;
        }
    }
    let (ss, a_tip) = (cur.ss, cur.a_tip);
    if !(a_tip > 0.0) {
        return None;
    }
    let (u, v) = (p[0], p[1]);
    Some(TipFit {
        x: hx + cs * u - sn * v,
        y: hy + sn * u + cs * v,
        half_w: p[2],
        hole_half: p[3],
        sigma: p[4],
        a_tip,
        rms: (ss / s.val.len() as f64).sqrt(),
    })
}
