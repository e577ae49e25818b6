//! Robust least-squares fits that imageproc lacks: a 2-D similarity
//! (rotation, translation, optionally scale) between the nominal grid and the
//! detected pin centres, and a straight line (the side view's housing edge).
//!
//! Robustness: a similarity fit starts from a median-based estimate and is
//! refined by iteratively reweighted least squares with Tukey's biweight and
//! a MAD scale (floored so that sub-pixel agreement does not reject good
//! pins), then refitted by plain least squares on the inliers. One bent or
//! missing pin therefore has no pull on the grid. The line fit is a
//! deterministic RANSAC over point pairs followed by the same refinement.

use serde::Serialize;

/// x = t + s R(θ) m: maps part-frame millimetres to image pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Similarity {
    /// Pixels per millimetre.
    pub s: f64,
    /// Rotation, radians (image axes: x right, y down; positive turns +x towards +y).
    pub theta: f64,
    pub tx: f64,
    pub ty: f64,
}

impl Similarity {
    pub fn apply(&self, u: f64, v: f64) -> (f64, f64) {
        let (sn, cs) = self.theta.sin_cos();
        (
            self.tx + self.s * (cs * u - sn * v),
            self.ty + self.s * (sn * u + cs * v),
        )
    }

    /// Part-frame (mm) coordinates of an image point.
    pub fn inverse(&self, x: f64, y: f64) -> (f64, f64) {
        self.inverse_map()(x, y)
    }

    /// [`Similarity::inverse`] with its sine and cosine taken once, for
    /// loops over every pixel (the same arithmetic, so the same results).
    pub fn inverse_map(&self) -> impl Fn(f64, f64) -> (f64, f64) + use<> {
        let (sn, cs) = self.theta.sin_cos();
        let (tx, ty, s) = (self.tx, self.ty, self.s);
        move |x, y| {
            let (dx, dy) = (x - tx, y - ty);
            ((cs * dx + sn * dy) / s, (-sn * dx + cs * dy) / s)
        }
    }

    /// Rotates an image-axis vector into the part frame (no scaling).
    pub fn to_part_axes(&self, dx: f64, dy: f64) -> (f64, f64) {
        let (sn, cs) = self.theta.sin_cos();
        (cs * dx + sn * dy, -sn * dx + cs * dy)
    }
}

/// Weighted least-squares similarity (Umeyama in 2-D). `fixed_scale` keeps
/// s fixed (rigid fit). Returns `None` when the weights vanish or the
/// model points coincide (scale undetermined).
pub fn fit_similarity(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    weights: &[f64],
    fixed_scale: Option<f64>,
    fallback_theta: f64,
) -> Option<Similarity> {
    let sw: f64 = weights.iter().sum();
    if !(sw > 0.0) || model.len() != image.len() || model.len() != weights.len() {
        return None;
    }
    let mut mu = (0.0, 0.0);
    let mut pi = (0.0, 0.0);
    for ((m, p), w) in model.iter().zip(image).zip(weights) {
        mu.0 += w * m.0;
        mu.1 += w * m.1;
        pi.0 += w * p.0;
        pi.1 += w * p.1;
    }
    mu = (mu.0 / sw, mu.1 / sw);
    pi = (pi.0 / sw, pi.1 / sw);
    let (mut a, mut b, mut mm) = (0.0, 0.0, 0.0);
    for ((m, p), w) in model.iter().zip(image).zip(weights) {
        let (mu_, mv_) = (m.0 - mu.0, m.1 - mu.1);
        let (pu, pv) = (p.0 - pi.0, p.1 - pi.1);
        a += w * (mu_ * pu + mv_ * pv);
        b += w * (mu_ * pv - mv_ * pu);
        mm += w * (mu_ * mu_ + mv_ * mv_);
    }
    let spread = (a * a + b * b).sqrt();
    let theta = if spread > 1e-12 * (1.0 + mm) {
        b.atan2(a)
    } else {
        fallback_theta
    };
    let s = match fixed_scale {
        Some(s) => s,
        None => {
            if mm <= 1e-12 {
                return None;
            }
            spread / mm
        }
    };
    if !(s.is_finite() && s > 0.0) {
        return None;
    }
    let (sn, cs) = theta.sin_cos();
    let tx = pi.0 - s * (cs * mu.0 - sn * mu.1);
    let ty = pi.1 - s * (sn * mu.0 + cs * mu.1);
    Some(Similarity { s, theta, tx, ty })
}

/// Result of [`robust_similarity`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobustFit {
    pub sim: Similarity,
    /// Per point: used in the final least-squares fit.
    pub inlier: Vec<bool>,
    /// RMS residual of the inliers, pixels.
    pub rms_px: f64,
    /// Robust residual scale (MAD, floored), pixels.
    pub sigma_px: f64,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Robust similarity: Tukey-biweight IRLS from `init` (or the plain fit),
/// MAD scale floored at `min_sigma_px`, then least squares on the inliers.
pub fn robust_similarity(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    fixed_scale: Option<f64>,
    init: Option<Similarity>,
    min_sigma_px: f64,
) -> Option<RobustFit> {
    let n = model.len();
    if n == 0 || image.len() != n {
        return None;
    }
    let fallback = init.map(|s| s.theta).unwrap_or(0.0);
    let mut sim = match init {
        Some(s) => s,
        None => fit_similarity(model, image, &vec![1.0; n], fixed_scale, fallback)?,
    };
    let resid = |sim: &Similarity| residuals(model, image, sim);
    let mut sigma = min_sigma_px;
    let mut w = vec![1.0; n];
    for _ in 0..10 {
        let r = resid(&sim);
        let mut rr = r.clone();
        sigma = (1.4826 * median(&mut rr)).max(min_sigma_px);
        let c = 4.685 * sigma;
        for (wi, ri) in w.iter_mut().zip(&r) {
            let t = ri / c;
            *wi = if t < 1.0 { (1.0 - t * t).powi(2) } else { 0.0 };
        }
        let Some(next) = fit_similarity(model, image, &w, fixed_scale, sim.theta) else {
            break;
        };
        let moved = (next.tx - sim.tx).abs()
            + (next.ty - sim.ty).abs()
            + (next.theta - sim.theta).abs() * 1e3;
        sim = next;
        if moved < 1e-6 {
            break;
        }
    }
    let r = resid(&sim);
    let c = 4.685 * sigma;
    let inlier: Vec<bool> = r.iter().map(|&ri| ri < c).collect();
    let wi: Vec<f64> = inlier.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
    if let Some(final_fit) = fit_similarity(model, image, &wi, fixed_scale, sim.theta) {
        sim = final_fit;
    }
    let r = resid(&sim);
    Some(RobustFit {
        sim,
        rms_px: inlier_rms(&r, &inlier),
        inlier,
        sigma_px: sigma,
    })
}

/// Fits with the fewest points mask a bent pin: with three or four pins
/// the least-squares start spreads one pin's bend over all of them, the
/// median residual is then a share of the bend, and the biweight's cut-off
/// (4.685 × 1.48 × that median) keeps the bent pin in. Above this many
/// points the median is set by the good pins and the masking is gone.
pub const CONSENSUS_MAX_POINTS: usize = 16;

/// Truncated squared residuals (MSAC's cost): a point within `tau_px`
/// costs its squared residual, any point further costs `tau_px²`.
fn truncated_cost(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    sim: &Similarity,
    tau_px: f64,
) -> f64 {
    let t2 = tau_px * tau_px;
    model
        .iter()
        .zip(image)
        .map(|(m, p)| {
            let q = sim.apply(m.0, m.1);
            ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).min(t2)
        })
        .sum()
}

/// The similarity two points determine exactly (with `fixed_scale`, the
/// rotation of their joining vector and the translation of their midpoint).
fn through_pair(
    m: [(f64, f64); 2],
    p: [(f64, f64); 2],
    fixed_scale: Option<f64>,
) -> Option<Similarity> {
    let dm = (m[1].0 - m[0].0, m[1].1 - m[0].1);
    let dp = (p[1].0 - p[0].0, p[1].1 - p[0].1);
    let lm = dm.0.hypot(dm.1);
    if !(lm > 1e-12) {
        return None;
    }
    let theta = dp.1.atan2(dp.0) - dm.1.atan2(dm.0);
    let s = fixed_scale.unwrap_or(dp.0.hypot(dp.1) / lm);
    if !(s.is_finite() && s > 0.0) {
        return None;
    }
    let mid_m = (0.5 * (m[0].0 + m[1].0), 0.5 * (m[0].1 + m[1].1));
    let mid_p = (0.5 * (p[0].0 + p[1].0), 0.5 * (p[0].1 + p[1].1));
    let (sn, cs) = theta.sin_cos();
    Some(Similarity {
        s,
        theta,
        tx: mid_p.0 - s * (cs * mid_m.0 - sn * mid_m.1),
        ty: mid_p.1 - s * (sn * mid_m.0 + cs * mid_m.1),
    })
}

/// Least squares on the points within `tau_px` of `sim`, repeated until
/// that set no longer changes (at most ten times; MSAC's local
/// optimisation). A pair's exact fit carries its own two pins' errors; the
/// fit on every pin it agrees with does not.
fn refit_on_consensus(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    fixed_scale: Option<f64>,
    mut sim: Similarity,
    tau_px: f64,
) -> Similarity {
    let mut last: Vec<bool> = Vec::new();
    for _ in 0..10 {
        let inside: Vec<bool> = residuals(model, image, &sim)
            .iter()
            .map(|&r| r < tau_px)
            .collect();
        if inside == last || inside.iter().filter(|b| **b).count() < 2 {
            break;
        }
        let w: Vec<f64> = inside.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
        let Some(next) = fit_similarity(model, image, &w, fixed_scale, sim.theta) else {
            break;
        };
        sim = next;
        last = inside;
    }
    sim
}

/// Each point's distance from where `sim` puts its model point (px).
pub(crate) fn residuals(model: &[(f64, f64)], image: &[(f64, f64)], sim: &Similarity) -> Vec<f64> {
    model
        .iter()
        .zip(image)
        .map(|(m, p)| {
            let q = sim.apply(m.0, m.1);
            ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).sqrt()
        })
        .collect()
}

/// RMS of the inliers' residuals.
fn inlier_rms(r: &[f64], inlier: &[bool]) -> f64 {
    let (mut ss, mut k) = (0.0, 0usize);
    for (ri, &b) in r.iter().zip(inlier) {
        if b {
            ss += ri * ri;
            k += 1;
        }
    }
    rms_of(ss, k)
}

/// A pin left out of a consensus fit must stand at least this many
/// position tolerances off it (a bent pin is drawn ≥ 1.15 off, less the
/// share of the good pins' own offsets the grid takes)…
const LEFT_OUT_MIN_TOL: f64 = 1.1;
/// …and every pin kept in it within this many: a good part's pins stand up
/// to 0.85 tolerances off their places, each in its own direction, and a
/// fit that keeps some of them 0.6–1 off and leaves another just over one
/// explains an all-good part by a bent pin (rows of 4–9 with every pin 0.8
/// off: 0 of 200 such parts flagged with this bound, 60 % without).
const KEPT_MAX_TOL: f64 = 0.6;

/// [`robust_similarity`] that a bent pin among a few cannot mask: besides
/// the fit from `init`, every pair of points proposes the similarity it
/// determines, refitted on the points it places within `tau_px`
/// ([`refit_on_consensus`]), and the fit with the least truncated cost over
/// all points (residuals over `tau_px` count as `tau_px`, MSAC) is
/// returned. `tau_px` is the distance beyond which a pin is off its place
/// (the position tolerance): a pin bent beyond it then costs the same
/// wherever it is, so the grid follows the pins that agree, and the bent
/// pin shows its whole bend instead of the share least squares (or a
/// biweight started from the pair, whose cut-off a few pins set wide) leaves
/// it. A consensus fit that leaves pins out is taken only when it is clear:
/// at most a third of the points (at least one) off, each
/// [`LEFT_OUT_MIN_TOL`] or more, every kept one within [`KEPT_MAX_TOL`]
/// (with a free scale, two of four pins always fit a pair exactly). From
/// four points on; with more than [`CONSENSUS_MAX_POINTS`] points this is
/// [`robust_similarity`].
pub fn consensus_similarity(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    fixed_scale: Option<f64>,
    init: Option<Similarity>,
    min_sigma_px: f64,
    tau_px: f64,
) -> Option<RobustFit> {
    let from_init = robust_similarity(model, image, fixed_scale, init, min_sigma_px);
    // With three points a pair leaves one point as the only check, and the
    // least cost does not tell a bent pin from pins that all stand off:
    // with a free scale, three collinear pins with an end one bent by d
    // (the outer pair leaves the middle one off by d/2); rigid, three pins
    // each 0.8 tolerances off in random directions, which a pair explains
    // with one pin bent (unit test in `synth_envelope`, blurred tips off
    // centre). From four points on, a pair leaves two checks.
    let n = model.len();
    if !(4..=CONSENSUS_MAX_POINTS).contains(&n) || image.len() != n || !(tau_px > 0.0) {
        return from_init;
    }
    let max_off = ((n - 1) / 3).max(1);
    let mut best_cost = from_init
        .as_ref()
        .map(|f| truncated_cost(model, image, &f.sim, tau_px))
        .unwrap_or(f64::INFINITY);
    let mut best: Option<Similarity> = None;
    for i in 0..n {
        for j in i + 1..n {
            let Some(sim) = through_pair([model[i], model[j]], [image[i], image[j]], fixed_scale)
            else {
                continue;
            };
            let sim = refit_on_consensus(model, image, fixed_scale, sim, tau_px);
            let r = residuals(model, image, &sim);
            let off = r.iter().filter(|&&ri| ri >= tau_px).count();
            // A proposal that keeps every pin is no better than the robust
            // fit from `init`: least squares over pins legitimately off
            // within tolerance would move the good pins' reported offsets.
            if off == 0 || off > max_off {
                continue;
            }
            let clear = r.iter().all(|&ri| {
                if ri >= tau_px {
                    ri >= LEFT_OUT_MIN_TOL * tau_px
                } else {
                    ri <= KEPT_MAX_TOL * tau_px
                }
            });
            if !clear {
                continue;
            }
            let cost = truncated_cost(model, image, &sim, tau_px);
            if cost < best_cost {
                best_cost = cost;
                best = Some(sim);
            }
        }
    }
    let Some(sim) = best else {
        return from_init;
    };
    let r = residuals(model, image, &sim);
    let inlier: Vec<bool> = r.iter().map(|&ri| ri < tau_px).collect();
    let mut rr = r.clone();
    let sigma_px = (1.4826 * median(&mut rr)).max(min_sigma_px);
    Some(RobustFit {
        sim,
        rms_px: inlier_rms(&r, &inlier),
        inlier,
        sigma_px,
    })
}

/// The points within `tau_px` of `seed`, a pose from another ruler (the
/// housing's outline), and the similarity least squares fits to them
/// ([`refit_on_consensus`]): still a fit to the pins, but one whose
/// consensus the other ruler chose. With four to eight pins and one or two
/// bent, the pins alone may explain the bend by a turned or shifted grid
/// as well as by a bent pin (`consensus_similarity` keeps the pins' own
/// fit unless its choice is clear); the housing does not turn with them.
/// `None` unless at least two points, and at least half of them, stay
/// within `tau_px` of the refitted pose (the seed is a second ruler, so
/// two bent pins of four need not outvote the two good ones).
pub fn consensus_from_seed(
    model: &[(f64, f64)],
    image: &[(f64, f64)],
    fixed_scale: Option<f64>,
    seed: Similarity,
    tau_px: f64,
) -> Option<RobustFit> {
    let n = model.len();
    if n < 2 || image.len() != n || !(tau_px > 0.0) {
        return None;
    }
    let sim = refit_on_consensus(model, image, fixed_scale, seed, tau_px);
    let r = residuals(model, image, &sim);
    let inlier: Vec<bool> = r.iter().map(|&ri| ri < tau_px).collect();
    let kept = inlier.iter().filter(|b| **b).count();
    if kept < 2 || 2 * kept < n {
        return None;
    }
    let mut rr = r.clone();
    Some(RobustFit {
        sim,
        rms_px: inlier_rms(&r, &inlier),
        inlier,
        sigma_px: 1.4826 * median(&mut rr),
    })
}

/// A line y = a + b x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Line {
    pub a: f64,
    pub b: f64,
}

impl Line {
    pub fn y_at(&self, x: f64) -> f64 {
        self.a + self.b * x
    }
    /// Signed perpendicular distance of (x, y) above the line (positive
    /// towards smaller y, i.e. up in the image).
    pub fn height_above(&self, x: f64, y: f64) -> f64 {
        (self.y_at(x) - y) / (1.0 + self.b * self.b).sqrt()
    }
}

/// Result of [`robust_line`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineFit {
    pub line: Line,
    pub inlier: Vec<bool>,
    pub rms: f64,
}

fn ls_line(pts: &[(f64, f64)], w: &[f64]) -> Option<Line> {
    let sw: f64 = w.iter().sum();
    if !(sw > 0.0) {
        return None;
    }
    let mx = pts.iter().zip(w).map(|(p, w)| w * p.0).sum::<f64>() / sw;
    let my = pts.iter().zip(w).map(|(p, w)| w * p.1).sum::<f64>() / sw;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (p, w) in pts.iter().zip(w) {
        sxx += w * (p.0 - mx) * (p.0 - mx);
        sxy += w * (p.0 - mx) * (p.1 - my);
    }
    if sxx <= 1e-12 {
        return None;
    }
    let b = sxy / sxx;
    Some(Line { a: my - b * mx, b })
}

/// Robust line through points where up to about half may be outliers:
/// deterministic RANSAC (pairs spread over the data) with inlier band
/// `tol`, then Tukey IRLS and least squares on the inliers.
pub fn robust_line(pts: &[(f64, f64)], tol: f64) -> Option<LineFit> {
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let count = |l: &Line| {
        pts.iter()
            .filter(|p| (l.y_at(p.0) - p.1).abs() <= tol)
            .count()
    };
    let mut best: Option<(usize, Line)> = None;
    // Deterministic pair sampling: strides over the index space.
    let trials = 400.min(n * (n - 1) / 2);
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    for _ in 0..trials {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let i = ((state >> 33) as usize) % n;
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let j = ((state >> 33) as usize) % n;
        if i == j || (pts[i].0 - pts[j].0).abs() < 1e-9 {
            continue;
        }
        let b = (pts[j].1 - pts[i].1) / (pts[j].0 - pts[i].0);
        let l = Line {
            a: pts[i].1 - b * pts[i].0,
            b,
        };
        let c = count(&l);
        if best.as_ref().is_none_or(|(bc, _)| c > *bc) {
            best = Some((c, l));
        }
    }
    let (_, mut line) = best?;
    let mut w = vec![0.0; n];
    for _ in 0..5 {
        for (wi, p) in w.iter_mut().zip(pts) {
            let t = (line.y_at(p.0) - p.1).abs() / (2.0 * tol);
            *wi = if t < 1.0 { (1.0 - t * t).powi(2) } else { 0.0 };
        }
        match ls_line(pts, &w) {
            Some(l) => line = l,
            None => break,
        }
    }
    let inlier: Vec<bool> = pts
        .iter()
        .map(|p| (line.y_at(p.0) - p.1).abs() <= tol)
        .collect();
    let wi: Vec<f64> = inlier.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
    if let Some(l) = ls_line(pts, &wi) {
        line = l;
    }
    let (mut ss, mut k) = (0.0, 0usize);
    for (p, &b) in pts.iter().zip(&inlier) {
        if b {
            ss += (line.y_at(p.0) - p.1).powi(2);
            k += 1;
        }
    }
    Some(LineFit {
        line,
        inlier,
        rms: rms_of(ss, k),
    })
}

/// The root mean square of `k` squared residuals summing to `ss` (NaN for
/// none).
fn rms_of(ss: f64, k: usize) -> f64 {
    if k > 0 {
        (ss / k as f64).sqrt()
    } else {
        f64::NAN
    }
}

#[cfg(test)]
#[path = "fit_tests.rs"]
mod tests;
