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
        let (sn, cs) = self.theta.sin_cos();
        let (dx, dy) = (x - self.tx, y - self.ty);
        ((cs * dx + sn * dy) / self.s, (-sn * dx + cs * dy) / self.s)
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
    let resid = |sim: &Similarity| -> Vec<f64> {
        model
            .iter()
            .zip(image)
            .map(|(m, p)| {
                let q = sim.apply(m.0, m.1);
                ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).sqrt()
            })
            .collect()
    };
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
    let (mut ss, mut k) = (0.0, 0usize);
    for (ri, &b) in r.iter().zip(&inlier) {
        if b {
            ss += ri * ri;
            k += 1;
        }
    }
    Some(RobustFit {
        sim,
        inlier,
        rms_px: rms_of(ss, k),
        sigma_px: sigma,
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
mod tests {
    use super::*;

    fn grid() -> Vec<(f64, f64)> {
        let mut m = Vec::new();
        for r in 0..2 {
            for c in 0..10 {
                m.push(((c as f64 - 4.5) * 2.54, (r as f64 - 0.5) * 2.54));
            }
        }
        m
    }

    #[test]
    fn exact_similarity_is_recovered() {
        let truth = Similarity {
            s: 33.3,
            theta: 0.07,
            tx: 512.3,
            ty: 380.9,
        };
        let m = grid();
        let p: Vec<_> = m.iter().map(|q| truth.apply(q.0, q.1)).collect();
        let f = fit_similarity(&m, &p, &vec![1.0; m.len()], None, 0.0).unwrap();
        assert!((f.s - truth.s).abs() < 1e-9 && (f.theta - truth.theta).abs() < 1e-12);
        assert!((f.tx - truth.tx).abs() < 1e-9 && (f.ty - truth.ty).abs() < 1e-9);
        let (u, v) = f.inverse(p[3].0, p[3].1);
        assert!((u - m[3].0).abs() < 1e-9 && (v - m[3].1).abs() < 1e-9);
    }

    #[test]
    fn one_bent_pin_does_not_drag_the_fit() {
        let truth = Similarity {
            s: 1.0 / 0.03,
            theta: -0.03,
            tx: 500.0,
            ty: 400.0,
        };
        let m = grid();
        let mut p: Vec<_> = m.iter().map(|q| truth.apply(q.0, q.1)).collect();
        // 0.3 mm bent pin = 10 px; plain least squares would move by 0.5 px.
        p[7].0 += 10.0;
        p[12].1 -= 6.0;
        let plain = fit_similarity(&m, &p, &vec![1.0; m.len()], Some(truth.s), 0.0).unwrap();
        assert!((plain.tx - truth.tx).abs() > 0.3);
        let f = robust_similarity(&m, &p, Some(truth.s), None, 0.05).unwrap();
        assert!((f.sim.tx - truth.tx).abs() < 1e-6 && (f.sim.ty - truth.ty).abs() < 1e-6);
        assert!((f.sim.theta - truth.theta).abs() < 1e-9);
        assert!(!f.inlier[7] && !f.inlier[12]);
        assert_eq!(f.inlier.iter().filter(|b| **b).count(), 18);
        // Free scale too.
        let f = robust_similarity(&m, &p, None, None, 0.05).unwrap();
        assert!((f.sim.s - truth.s).abs() < 1e-6);
    }

    #[test]
    fn line_through_a_comb_ignores_the_teeth() {
        // Housing edge y = 300 + 0.02 x sampled every column; 30 % of the
        // columns are pins reaching 100 px higher.
        let pts: Vec<(f64, f64)> = (0..200)
            .map(|i| {
                let x = i as f64 * 5.0;
                let y = 300.0 + 0.02 * x;
                if i % 10 < 3 { (x, y - 100.0) } else { (x, y) }
            })
            .collect();
        let f = robust_line(&pts, 2.0).unwrap();
        assert!((f.line.b - 0.02).abs() < 1e-9 && (f.line.a - 300.0).abs() < 1e-6);
        assert_eq!(f.inlier.iter().filter(|b| **b).count(), 140);
        assert!((f.line.height_above(0.0, 200.0) - 100.0 / (1.0f64 + 0.0004).sqrt()).abs() < 1e-9);
    }
}
