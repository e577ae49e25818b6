//! The Cramér–Rao lower bound on a tip's centre: how well ANY unbiased
//! measurement could locate it in this very image, given its blur, contrast,
//! light and noise.
//!
//! Why: issue 12 asks for an ok-pin centre RMS of 0.10 px over the whole
//! envelope. Whether that is a matter of the pipeline or of physics depends
//! on the information the pixels carry. For a feature shifted by (dx, dy)
//! the Fisher information is Σ ∂I/∂d ∂I/∂dᵀ / var over its pixels
//! (independent Gaussian noise), and the bound on the radial error is
//! √trace(F⁻¹). The derivatives are taken by rendering the part shifted by
//! ±δ (so the pixels' area sampling and the blur are exact), over a disc
//! around the tip. The disc may reach the edge of the tip's clearance hole,
//! which moves with the part: that only adds information, so the bound
//! stays a lower bound. Clipped pixels carry none. JPEG loss is not
//! modelled (it adds noise, again only raising the true bound).

use super::*;

/// Radial Cramér–Rao bound (px) on the centre of a feature at `centre`,
/// from the pixels within `radius` px: `gx`, `gy` are the derivatives of
/// each pixel's exposed value with respect to the feature's shift in x and
/// y, `value` the exposed (noiseless) values, `variance(v)` the noise
/// variance of a pixel of value `v`; pixels at or beyond `clip` carry no
/// information. `None` when the window holds none (flat or clipped).
#[allow(clippy::too_many_arguments)]
pub fn fisher_bound_px(
    gx: &[f32],
    gy: &[f32],
    value: &[f32],
    w: usize,
    h: usize,
    centre: (f64, f64),
    radius: f64,
    clip: (f32, f32),
    variance: impl Fn(f32) -> f32,
) -> Option<f64> {
    let (cx, cy) = centre;
    let x0 = (cx - radius).floor().max(0.0) as usize;
    let y0 = (cy - radius).floor().max(0.0) as usize;
    let x1 = ((cx + radius).ceil().max(0.0) as usize).min(w.saturating_sub(1));
    let y1 = ((cy + radius).ceil().max(0.0) as usize).min(h.saturating_sub(1));
    let (mut fxx, mut fxy, mut fyy) = (0.0f64, 0.0f64, 0.0f64);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let i = y * w + x;
            let v = value[i];
            if (x as f64 - cx).hypot(y as f64 - cy) > radius || v <= clip.0 || v >= clip.1 {
                continue;
            }
            let var = variance(v).max(1e-12) as f64;
            let (a, b) = (gx[i] as f64, gy[i] as f64);
            fxx += a * a / var;
            fxy += a * b / var;
            fyy += b * b / var;
        }
    }
    let det = fxx * fyy - fxy * fxy;
    (det > 1e-12 * (fxx + fyy).powi(2) && det > 0.0).then(|| ((fxx + fyy) / det).sqrt())
}

impl EnvelopeCase {
    /// The Cramér–Rao bound (px) on the centre of every intact (ok) tip of a
    /// top view, as (row, col, bound); empty for the side view. Five scene
    /// renders: use it for evaluation, not in a hot loop.
    pub fn centre_bounds(&self) -> Vec<(u32, u32, f64)> {
        if self.recipe.view != View::Top {
            return Vec::new();
        }
        let f = &self.factors;
        let (w, h) = (f.width as usize, f.height as usize);
        let gain = f.gain as f32;
        let (mut value, pins, _) = self.scene();
        value.iter_mut().for_each(|v| *v *= gain);
        // Central differences of renders shifted by ±δ px.
        const DELTA: f64 = 0.05;
        let derivative = |ux: f64, uy: f64| -> Vec<f32> {
            let shifted = |sign: f64| {
                let mut c = self.clone();
                c.factors.centre_px.0 += sign * DELTA * ux;
                c.factors.centre_px.1 += sign * DELTA * uy;
                c.scene().0
            };
            let (p, m) = (shifted(1.0), shifted(-1.0));
            p.iter()
                .zip(&m)
                .map(|(a, b)| gain * (a - b) / (2.0 * DELTA) as f32)
                .collect()
        };
        let (gx, gy) = (derivative(1.0, 0.0), derivative(0.0, 1.0));
        // The tip, its blurred edge and a pixel of margin.
        let radius = 0.75 * f.tip_px + 2.0 * f.blur_px + 1.0;
        pins.iter()
            .filter(|p| p.defect == PinStatus::Ok)
            .filter_map(|p| {
                let c = (p.x_px?, p.y_px?);
                let b = fisher_bound_px(&gx, &gy, &value, w, h, c, radius, (0.0, 255.0), |v| {
                    self.noise_variance(v)
                })?;
                Some((p.row, p.col, b))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::fisher_bound_px;

    /// The standard normal distribution function (Abramowitz–Stegun 7.1.26,
    /// |error| < 1.5e-7), so that the test's truth does not share code with
    /// the renderer.
    fn phi(x: f64) -> f64 {
        let z = x.abs() / std::f64::consts::SQRT_2;
        let t = 1.0 / (1.0 + 0.3275911 * z);
        let poly = t
            * (0.254829592
                + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
        let erf = 1.0 - poly * (-z * z).exp();
        0.5 * (1.0 + erf.copysign(x))
    }

    /// A square tip of width `a`, contrast `c`, Gaussian blur `s`, with white
    /// noise σ: separable, I = c A(x) A(y), so F_xx = c²/σ² ∫A'² ∫A², with
    /// ∫A'² = (1 − e^{−a²/4s²}) / (√π s) in closed form and ∫A² by
    /// quadrature; by symmetry the radial bound is √(2 / F_xx). The pixel
    /// derivatives are the analytic ones of the point-sampled square.
    #[test]
    fn the_bound_of_a_blurred_square_matches_its_closed_form() {
        let pdf = |u: f64| (-0.5 * u * u).exp() / (std::f64::consts::TAU).sqrt();
        for &(a, c, s, sigma) in &[
            (12.0, 50.0, 2.0, 5.0),
            (7.0, 30.0, 2.5, 16.0),
            (20.0, 120.0, 1.5, 2.0),
        ] {
            let n = 96usize;
            let (cx, cy) = (47.3, 48.6);
            let edge = |u: f64| phi((u + a / 2.0) / s) - phi((u - a / 2.0) / s);
            // d/d(centre) of edge(x − centre) = −edge'(x − centre).
            let slope = |u: f64| -(pdf((u + a / 2.0) / s) - pdf((u - a / 2.0) / s)) / s;
            let at = |i: usize| ((i % n) as f64 - cx, (i / n) as f64 - cy);
            let value: Vec<f32> = (0..n * n)
                .map(|i| {
                    let (u, v) = at(i);
                    (10.0 + c * edge(u) * edge(v)) as f32
                })
                .collect();
            let gx: Vec<f32> = (0..n * n)
                .map(|i| {
                    let (u, v) = at(i);
                    (c * slope(u) * edge(v)) as f32
                })
                .collect();
            let gy: Vec<f32> = (0..n * n)
                .map(|i| {
                    let (u, v) = at(i);
                    (c * edge(u) * slope(v)) as f32
                })
                .collect();
            let got = fisher_bound_px(&gx, &gy, &value, n, n, (cx, cy), 40.0, (0.0, 1e9), |_| {
                (sigma * sigma) as f32
            })
            .expect("information");
            let d1 = (1.0 - (-a * a / (4.0 * s * s)).exp()) / (std::f64::consts::PI.sqrt() * s);
            let h = 0.01;
            let a2: f64 = (-4000..=4000).map(|k| edge(k as f64 * h).powi(2) * h).sum();
            let fxx = c * c / (sigma * sigma) * d1 * a2;
            let want = (2.0 / fxx).sqrt();
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "a {a} c {c} s {s} σ {sigma}: bound {got:.5} px, closed form {want:.5} px"
            );
        }
    }

    #[test]
    fn clipped_or_flat_patches_carry_no_information() {
        let n = 32usize;
        let flat = vec![0f32; n * n];
        let value = vec![100f32; n * n];
        let b = |gx: &[f32], gy: &[f32], v: &[f32]| {
            fisher_bound_px(gx, gy, v, n, n, (16.0, 16.0), 8.0, (0.0, 255.0), |_| 1.0)
        };
        assert!(b(&flat, &flat, &value).is_none());
        let ramp: Vec<f32> = (0..n * n).map(|i| (i % 7) as f32).collect();
        assert!(
            b(
                &ramp,
                &ramp.iter().map(|g| 2.0 * g).collect::<Vec<_>>(),
                &value
            )
            .is_none()
        );
        assert!(b(&ramp, &flat, &value).is_none(), "no information along y");
        let clipped = vec![255f32; n * n];
        let gy: Vec<f32> = (0..n * n).map(|i| (i % 5) as f32).collect();
        assert!(b(&ramp, &gy, &clipped).is_none());
        assert!(b(&ramp, &gy, &value).is_some());
    }

    /// Less noise, a smaller bound, pin by pin, on a drawn top view.
    #[test]
    fn halving_the_noise_lowers_every_bound() {
        let case = (820_000..)
            .map(super::EnvelopeCase::draw)
            .find(|c| !c.centre_bounds().is_empty() && c.factors.noise_dn > 4.0)
            .expect("a top view with ok tips");
        let b = case.centre_bounds();
        let mut quiet = case.clone();
        quiet.factors.noise_dn *= 0.5;
        let bq = quiet.centre_bounds();
        assert_eq!(b.len(), bq.len());
        for (x, y) in b.iter().zip(&bq) {
            assert!(y.2 < 0.75 * x.2, "{x:?} vs {y:?}");
        }
    }
}
