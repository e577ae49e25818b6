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

/// What every tip fit on one image shares: the image, its polarity, the
/// recipe, the tips' edge spread and the part's smallest pitch (px).
pub(crate) struct TipModel<'a, P: Px> {
    pub plane: &'a Plane<'a, P>,
    pub sign: f32,
    pub recipe: &'a Recipe,
    pub blur_sigma: f64,
    pub min_pitch_px: f64,
}

impl<P: Px> TipModel<'_, P> {
    fn prior(&self, sim: &Similarity, hole: (f64, f64)) -> TipPrior {
        prior_at(self.recipe, sim, hole, self.blur_sigma, self.min_pitch_px)
    }

    /// Refines the centres of the intact tips `intact` ((position,
    /// candidate) pairs) in place; returns the pairs whose fit settled, and
    /// the part's shape when enough tips gave it ([`common_shape`]).
    /// `nominal` holds the positions' fitted nominal centres (the holes'
    /// centres), px.
    pub(crate) fn refine_centres(
        &self,
        sim: &Similarity,
        nominal: &[(f64, f64)],
        intact: &[(usize, usize)],
        cands: &mut [Candidate],
    ) -> (Vec<(usize, usize)>, Option<PartShape>) {
        let first: Vec<Option<TipFit>> = intact
            .iter()
            .map(|&(pi, ci)| {
                let start = (cands[ci].m.x, cands[ci].m.y);
                fit_tip(self.plane, self.sign, start, &self.prior(sim, nominal[pi]))
            })
            .collect();
        match common_shape(&first) {
            Some(shape) => {
                let done = self.refine_in_part(sim, nominal, intact, cands, shape);
                (done, Some(shape))
            }
            None => {
                let fits = intact.iter().zip(first).map(|(&(pi, ci), f)| (pi, ci, f));
                (
                    settle(self.recipe, sim, nominal, fits.collect(), cands),
                    None,
                )
            }
        }
    }

    /// Refines, with the part's `shape` as prior, the centres of the tips on
    /// `which` ((position, candidate) pairs): the intact tips the shape was
    /// learnt from, and tips a later look found. Returns the pairs whose fit
    /// settled.
    pub(crate) fn refine_in_part(
        &self,
        sim: &Similarity,
        nominal: &[(f64, f64)],
        which: &[(usize, usize)],
        cands: &mut [Candidate],
        shape: PartShape,
    ) -> Vec<(usize, usize)> {
        let fits: Vec<_> = which
            .iter()
            .map(|&(pi, ci)| {
                (
                    pi,
                    ci,
                    self.fit_in_part(sim, nominal[pi], &cands[ci], shape),
                )
            })
            .collect();
        settle(self.recipe, sim, nominal, fits, cands)
    }

    /// The fit of the tip `c` in the hole at `hole` within the part's
    /// shape (σ held, the sizes drawn to the part's).
    fn fit_in_part(
        &self,
        sim: &Similarity,
        hole: (f64, f64),
        c: &Candidate,
        shape: PartShape,
    ) -> Option<TipFit> {
        let mut prior = self.prior(sim, hole);
        prior.part = Some(shape);
        fit_tip(self.plane, self.sign, (c.m.x, c.m.y), &prior)
    }
}

/// Moves each candidate to its fitted centre where the fit settled on the
/// same tip ([`settled_on_the_same_tip`]); returns those pairs.
fn settle(
    recipe: &Recipe,
    sim: &Similarity,
    nominal: &[(f64, f64)],
    fits: Vec<(usize, usize, Option<TipFit>)>,
    cands: &mut [Candidate],
) -> Vec<(usize, usize)> {
    let half_w = 0.5 * recipe.pin_mm * sim.s;
    let mut done = Vec::with_capacity(fits.len());
    for (pi, ci, f) in fits {
        let Some(f) = f else {
            continue;
        };
        let c = (cands[ci].m.x, cands[ci].m.y);
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

/// Fewest free fits whose medians are the part's blur and shape.
const MIN_FITS_FOR_COMMON_SIGMA: usize = 3;

/// What one part's tips share: one lens blurs them all (σ), one design
/// cuts every tip and every clearance hole to one size (half-widths, px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartShape {
    pub sigma: f64,
    pub half_w: f64,
    pub hole_half: f64,
    /// The fits' median RMS residual: the noise the sizes' priors are
    /// weighed against (sample units).
    pub noise: f64,
}

/// The width (px, one standard deviation) of the prior that pulls a tip's
/// half-width and its hole's towards the part's medians
/// ([`PartShape::half_w`], [`PartShape::hole_half`]): a MAP fit, in which
/// a size is worth its data's evidence against one of this width. Held
/// outright, a size cannot follow what the model leaves out around one tip
/// (a low-noise good tip near the limit moved 0.5 px outward with the hole
/// held, Rust 940 988; the independent renderer's tips, whose areas vary
/// ±8 %, read 5–8 % worse with the tip's size held); left free, both trade
/// against the levels and the centre under heavy noise (Rust 910 518). Over
/// the ten Rust top sets this width read +1 −2 verdicts against the tip
/// held and a 0.2 px hole prior, with the ok-pin centres' 99th percentile
/// 0.48 px against 0.52.
const SIZE_PRIOR_PX: f64 = 0.2;

/// The part's blur σ and its tips' and holes' half-widths: the medians of
/// the tips' own free fits, from at least [`MIN_FITS_FOR_COMMON_SIGMA`]
/// fits (else `None`, and each tip keeps its own).
///
/// Why the tips are then fitted again with σ held and the sizes drawn to
/// these ([`SIZE_PRIOR_PX`]): a single tip's free
/// σ also absorbs what the model does not describe (the specular dome, the
/// edge ramp, the housing's texture), and on a tip off-centre in its hole σ
/// trades against the centre along the offset. Bent tips of 1 × 3 – 1 × 7
/// parts fitted σ 1.3–2.2 × the part's and moved 0.5–1.4 px back towards
/// the hole, so bent pins read ok (Rust 820 148, 820 699, 830 710,
/// 890 466); with σ held at the part's median their centres came within
/// 0.03–0.3 px of the truth. Under heavy noise the sizes trade too: a
/// small bright tip against a large dim one, a narrow hole against a wide
/// one, each pair fitting the noise about equally well, and the free sizes
/// of one 2 × 17 (Rust 910 518, σ 14.8 DN on 6.5 px tips) ran to their
/// clamps on most tips while the centres wandered 1–2 px; drawn to the
/// part's medians, the centre is what is left to fit.
fn common_shape(fits: &[Option<TipFit>]) -> Option<PartShape> {
    let settled: Vec<&TipFit> = fits.iter().flatten().collect();
    if settled.len() < MIN_FITS_FOR_COMMON_SIGMA {
        return None;
    }
    let median_of = |f: &dyn Fn(&TipFit) -> f64| {
        let mut v: Vec<f64> = settled.iter().map(|t| f(t)).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    Some(PartShape {
        sigma: median_of(&|t| t.sigma),
        half_w: median_of(&|t| t.half_w),
        hole_half: median_of(&|t| t.hole_half),
        noise: median_of(&|t| t.rms),
    })
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
        part: None,
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
    /// The part's shape ([`common_shape`]): σ held there, the half-widths
    /// drawn to it ([`SIZE_PRIOR_PX`]).
    pub part: Option<PartShape>,
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
    p[4] = match prior.part {
        Some(h) => h.sigma,
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
    // The sizes' priors as more residuals, w · (size − part's size).
    let priors: [(usize, f64, f64); 2] = match prior.part {
        Some(h) => [
            (2, h.noise / SIZE_PRIOR_PX, h.half_w),
            (3, h.noise / SIZE_PRIOR_PX, h.hole_half),
        ],
        None => [(2, 0.0, 0.0), (3, 0.0, 0.0)],
    };
    let penalty = |p: &Params| {
        priors
            .iter()
            .map(|&(i, w, v0)| (w * (p[i] - v0)).powi(2))
            .sum::<f64>()
    };
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
        for &(i, w, v0) in &priors {
            jtj[i][i] += w * w;
            jtr[i] -= w * w * (p[i] - v0);
        }
        // The part's σ takes no step: its row and column are the
        // identity's.
        if prior.part.is_some() {
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
            if evaluate(&s, prior.round, &q, &mut trial).is_some()
                && trial.ss + penalty(&q) < cur.ss + penalty(&p)
            {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::blur_model::erf;
    use crate::vision::synth::Rng;

    /// A square's indicator blurred by a Gaussian of `sigma`, one axis.
    fn edge_pair(x: f64, half: f64, sigma: f64) -> f64 {
        let k = std::f64::consts::FRAC_1_SQRT_2 / sigma;
        0.5 * (erf((x + half) * k) - erf((x - half) * k))
    }

    /// A 41 × 41 image: housing at 20 000, a square hole (half-width
    /// `hole_half`) 6 000 darker centred at (20, 20), a square tip
    /// (half-width `half_w`) 15 000 above the hole at `tip`, blurred by
    /// `sigma`, with Gaussian noise of `noise`.
    fn image(
        tip: (f64, f64),
        half_w: f64,
        hole_half: f64,
        sigma: f64,
        noise: f64,
        rng: &mut Rng,
    ) -> Vec<u16> {
        let mut v = Vec::with_capacity(41 * 41);
        for y in 0..41 {
            for x in 0..41 {
                let (x, y) = (x as f64, y as f64);
                let hole =
                    edge_pair(x - 20.0, hole_half, sigma) * edge_pair(y - 20.0, hole_half, sigma);
                let t = edge_pair(x - tip.0, half_w, sigma) * edge_pair(y - tip.1, half_w, sigma);
                let val = 20_000.0 - 6_000.0 * hole + 15_000.0 * t + noise * rng.normal();
                v.push(val.round().clamp(0.0, 65_535.0) as u16);
            }
        }
        v
    }

    fn prior(half_w: f64, sigma: f64, part: Option<PartShape>) -> TipPrior {
        TipPrior {
            round: false,
            theta: 0.0,
            half_w,
            sigma,
            hole: (20.0, 20.0),
            window: 1.5 * half_w + 3.0 * sigma + 2.0,
            part,
        }
    }

    /// Under heavy noise (σ 6 000 against a tip 15 000 above its hole, a
    /// 6.6 px tip blurred by σ 2 px) the free sizes trade against the
    /// levels and the centre wanders; with the part's shape as prior the
    /// centre scatters less, over the same forty noise draws.
    #[test]
    fn the_parts_shape_steadies_a_noisy_tips_centre() {
        let (hw, hole, sg, noise) = (3.3, 4.7, 2.0, 6_000.0);
        let truth = (21.0, 19.3);
        let shape = PartShape {
            sigma: sg,
            half_w: hw,
            hole_half: hole,
            noise,
        };
        let mut rng = Rng::new(11);
        let (mut free_ss, mut held_ss, mut n) = (0.0, 0.0, 0);
        for _ in 0..40 {
            let data = image(truth, hw, hole, sg, noise, &mut rng);
            let plane = Plane {
                w: 41,
                h: 41,
                data: &data,
            };
            let start = (truth.0 + 0.3, truth.1 - 0.3);
            let free = fit_tip(&plane, 1.0, start, &prior(hw, sg, None));
            let held = fit_tip(&plane, 1.0, start, &prior(hw, sg, Some(shape)));
            let (Some(f), Some(h)) = (free, held) else {
                continue;
            };
            free_ss += (f.x - truth.0).powi(2) + (f.y - truth.1).powi(2);
            held_ss += (h.x - truth.0).powi(2) + (h.y - truth.1).powi(2);
            n += 1;
        }
        assert!(n >= 35, "only {n} of 40 fits settled");
        let (free_rms, held_rms) = ((free_ss / n as f64).sqrt(), (held_ss / n as f64).sqrt());
        assert!(
            held_rms < 0.8 * free_rms,
            "held {held_rms:.3} px against free {free_rms:.3} px"
        );
    }

    /// With little noise the data outweighs a prior that is off (the tip
    /// 0.2 px and the hole 0.5 px larger than the part's medians say): the
    /// centre of a tip 1.4 px off its hole's centre is still read exactly.
    #[test]
    fn a_clean_tip_is_read_where_it_is_whatever_the_parts_shape_says() {
        let (hw, hole, sg) = (3.5, 5.2, 1.6);
        let truth = (21.2, 19.4);
        let shape = PartShape {
            sigma: sg,
            half_w: hw - 0.2,
            hole_half: hole - 0.5,
            noise: 30.0,
        };
        let mut rng = Rng::new(5);
        let data = image(truth, hw, hole, sg, 30.0, &mut rng);
        let plane = Plane {
            w: 41,
            h: 41,
            data: &data,
        };
        let f = fit_tip(&plane, 1.0, (21.0, 19.8), &prior(hw, sg, Some(shape))).expect("fit");
        let err = (f.x - truth.0).hypot(f.y - truth.1);
        assert!(err < 0.02, "centre {err:.3} px off");
    }
}
