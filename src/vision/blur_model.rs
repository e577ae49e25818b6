//! The blurred tip-in-hole model that [`super::blur_tip`] fits: its two
//! shape columns, the residuals once the linear levels are solved exactly
//! (variable projection), and the Jacobian of those residuals in closed form.
//!
//! Why a closed-form Jacobian: the fit used to difference the projected
//! residuals forward, one extra model evaluation per parameter per
//! iteration, and the model (a dozen erf per sample) was 70 % of the time
//! of a blurred image's inspection. The derivatives of an erf come with the
//! same exp as its value, so value and Jacobian together cost little more
//! than the value alone. The Jacobian is Kaufman's: `J = −P⊥ (∂A/∂p) c`,
//! with `P⊥` the projection off the linear columns. It drops a term of the
//! full Golub–Pereyra Jacobian that lies in the columns' span, which the
//! residual is orthogonal to, so `Jᵀr` — the gradient — is exact and the
//! fit settles where it did with differences.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_2_SQRT_PI};

/// Number of non-linear parameters.
pub(super) const NP: usize = 5;

/// Non-linear parameters: tip centre (part axes, relative to the hole
/// centre), tip half-width, hole half-width, σ.
pub(super) type Params = [f64; NP];

/// The fit's pixels.
#[derive(Debug, Default)]
pub(super) struct Samples {
    /// Pixel positions relative to the hole centre, in the part's axes.
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    /// Positions relative to the hole centre, image axes (background plane).
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub val: Vec<f64>,
}

/// erf, Abramowitz & Stegun 7.1.26 (|error| < 1.5e-7): the model needs
/// a few million evaluations per image, and this precision is far below
/// the noise of any pixel.
#[inline]
pub(super) fn erf(x: f64) -> f64 {
    erf_d(x).0
}

/// erf and its derivative 2/√π·e^(−x²), from one exp.
#[inline]
fn erf_d(x: f64) -> (f64, f64) {
    let e = (-x * x).exp();
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * a);
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t
            + 0.254_829_592)
            * t
            * e;
    (x.signum() * y, FRAC_2_SQRT_PI * e)
}

/// A blurred centred interval [−h, h] at u, ½ [erf(a·k) + erf(b·k)] with
/// a = h − u and b = h + u, keeping each end's erf and slope: the overlap
/// of tip and hole is made of the same ends.
#[derive(Debug, Clone, Copy, Default)]
struct Band {
    a: f64,
    b: f64,
    ea: f64,
    ga: f64,
    eb: f64,
    gb: f64,
}

impl Band {
    #[inline]
    fn at(u: f64, h: f64, k: f64) -> Band {
        let (a, b) = (h - u, h + u);
        let (ea, ga) = erf_d(a * k);
        let (eb, gb) = erf_d(b * k);
        Band {
            a,
            b,
            ea,
            ga,
            eb,
            gb,
        }
    }
    #[inline]
    fn f(&self) -> f64 {
        0.5 * (self.ea + self.eb)
    }
    /// ∂/∂u.
    #[inline]
    fn du(&self, k: f64) -> f64 {
        0.5 * k * (self.gb - self.ga)
    }
    /// ∂/∂h.
    #[inline]
    fn dh(&self, k: f64) -> f64 {
        0.5 * k * (self.ga + self.gb)
    }
    /// ∂/∂k.
    #[inline]
    fn dk(&self) -> f64 {
        0.5 * (self.a * self.ga + self.b * self.gb)
    }
}

/// The overlap of the tip's and the hole's extents along one axis: the
/// interval [max(c − w, −h), min(c + w, h)] blurred at the sample, from the
/// ends of the tip's band `t` (centre c, half-width w) and the hole's band
/// `hb` (half-width h) there, with its derivatives in c, w, h and k.
#[derive(Debug, Clone, Copy, Default)]
struct Overlap {
    f: f64,
    dc: f64,
    dw: f64,
    dh: f64,
    dk: f64,
}

#[inline]
fn overlap(c: f64, w: f64, h: f64, t: &Band, hb: &Band, k: f64) -> Overlap {
    // Each end is the tip's or the hole's, whichever is inside. The upper
    // end's distance from the sample is a band's `a`; the lower end's is
    // minus its `b` (erf odd, its slope even).
    let lo_is_tip = c - w > -h;
    let hi_is_tip = c + w < h;
    let lo = if lo_is_tip { c - w } else { -h };
    let hi = if hi_is_tip { c + w } else { h };
    if hi <= lo {
        return Overlap::default();
    }
    let (d_hi, e_hi, g_hi) = if hi_is_tip {
        (t.a, t.ea, t.ga)
    } else {
        (hb.a, hb.ea, hb.ga)
    };
    let (d_lo, e_lo, g_lo) = if lo_is_tip {
        (-t.b, -t.eb, t.gb)
    } else {
        (-hb.b, -hb.eb, hb.gb)
    };
    let s_hi = 0.5 * k * g_hi;
    let s_lo = -0.5 * k * g_lo;
    let (mut dc, mut dw, mut dh) = (0.0, 0.0, 0.0);
    if lo_is_tip {
        dc += s_lo;
        dw -= s_lo;
    } else {
        dh -= s_lo;
    }
    if hi_is_tip {
        dc += s_hi;
        dw += s_hi;
    } else {
        dh += s_hi;
    }
    Overlap {
        f: 0.5 * (e_hi - e_lo),
        dc,
        dw,
        dh,
        dk: 0.5 * (d_hi * g_hi - d_lo * g_lo),
    }
}

/// The two shape columns at one sample, with their derivatives in the
/// parameters (σ through k): `(hole, tip, ∂hole, ∂tip)`.
///
/// The tip occludes the hole and, where it stands past the hole's rim,
/// the housing: the scene is housing + (hole − housing)·[H ∪ T] +
/// (tip − hole)·[T], and [H ∪ T] = [H] + [T] − [H ∩ T]. Square: H ∩ T is a
/// rectangle (both in the part's axes), blurred exactly; round: the blurred
/// lens is taken as the smaller of the two blurred discs (exact where
/// either edge is sharp or far), and a disc is blurred radially.
#[inline]
fn columns(round: bool, u: f64, v: f64, p: &Params, k: f64) -> (f64, f64, Params, Params) {
    let (w, h) = (p[2], p[3]);
    let (du, dv) = (u - p[0], v - p[1]);
    // Derivatives per parameter; index 4 holds ∂/∂k until the caller
    // applies dk/dσ.
    let (hole, d_hole, tip, d_tip, both, d_both);
    if round {
        let hb = Band::at(u.hypot(v), h, k);
        let rt = du.hypot(dv);
        let tb = Band::at(rt, w, k);
        // ∂rt/∂p0 = −du/rt; a band is even in r, so its slope at 0 is 0.
        let (gx, gy) = if rt > 1e-12 {
            (-du / rt, -dv / rt)
        } else {
            (0.0, 0.0)
        };
        hole = hb.f();
        d_hole = [0.0, 0.0, 0.0, hb.dh(k), hb.dk()];
        tip = tb.f();
        let slope = tb.du(k);
        d_tip = [slope * gx, slope * gy, tb.dh(k), 0.0, tb.dk()];
        (both, d_both) = if hole <= tip {
            (hole, d_hole)
        } else {
            (tip, d_tip)
        };
    } else {
        let (hu, hv) = (Band::at(u, h, k), Band::at(v, h, k));
        let (fhu, fhv) = (hu.f(), hv.f());
        hole = fhu * fhv;
        d_hole = [
            0.0,
            0.0,
            0.0,
            hu.dh(k) * fhv + fhu * hv.dh(k),
            hu.dk() * fhv + fhu * hv.dk(),
        ];
        let (tu, tv) = (Band::at(du, w, k), Band::at(dv, w, k));
        let (ftu, ftv) = (tu.f(), tv.f());
        tip = ftu * ftv;
        d_tip = [
            -tu.du(k) * ftv,
            -ftu * tv.du(k),
            tu.dh(k) * ftv + ftu * tv.dh(k),
            0.0,
            tu.dk() * ftv + ftu * tv.dk(),
        ];
        let ou = overlap(p[0], w, h, &tu, &hu, k);
        let ov = overlap(p[1], w, h, &tv, &hv, k);
        both = ou.f * ov.f;
        d_both = [
            ou.dc * ov.f,
            ou.f * ov.dc,
            ou.dw * ov.f + ou.f * ov.dw,
            ou.dh * ov.f + ou.f * ov.dh,
            ou.dk * ov.f + ou.f * ov.dk,
        ];
    }
    let mut d_union = [0.0; NP];
    for j in 0..NP {
        d_union[j] = d_hole[j] + d_tip[j] - d_both[j];
    }
    (hole + tip - both, tip, d_union, d_tip)
}

/// One evaluation of the model at `p`.
#[derive(Debug, Default)]
pub(super) struct Eval {
    /// Residuals, data − model, with the linear levels solved exactly.
    pub res: Vec<f64>,
    /// Sum of squared residuals.
    pub ss: f64,
    /// The tip's level above its hole's (sign space).
    pub a_tip: f64,
    /// ∂res/∂p, a column per parameter.
    pub jac: [Vec<f64>; NP],
    /// Per sample: the shape columns and their derivatives (scratch).
    cols: Vec<(f64, f64, Params, Params)>,
}

/// Evaluates the model at `p` into `e`, residuals and Jacobian: the
/// columns' erf are the cost, and the Jacobian reuses them. `None` when the
/// linear levels are undetermined.
pub(super) fn evaluate(s: &Samples, round: bool, p: &Params, e: &mut Eval) -> Option<()> {
    let sigma = p[4].max(1e-3);
    let k = FRAC_1_SQRT_2 / sigma;
    let dk_dsigma = if p[4] > 1e-3 { -k / sigma } else { 0.0 };
    let n = s.val.len();
    // Columns: 1, x, y, hole ∪ tip, tip.
    const M: usize = 5;
    let mut ata = [[0f64; M]; M];
    let mut aty = [0f64; M];
    e.cols.clear();
    for i in 0..n {
        let c = columns(round, s.u[i], s.v[i], p, k);
        let a = [1.0, s.x[i], s.y[i], c.0, c.1];
        for r in 0..M {
            aty[r] += a[r] * s.val[i];
            for q in r..M {
                ata[r][q] += a[r] * a[q];
            }
        }
        e.cols.push(c);
    }
    for r in 0..M {
        for q in 0..r {
            ata[r][q] = ata[q][r];
        }
    }
    let coef = solve_sym(ata, aty)?;
    let row = |i: usize| [1.0, s.x[i], s.y[i], e.cols[i].0, e.cols[i].1];
    e.res.clear();
    e.ss = 0.0;
    for i in 0..n {
        let a = row(i);
        let m: f64 = a.iter().zip(&coef).map(|(x, c)| x * c).sum();
        let r = s.val[i] - m;
        e.ss += r * r;
        e.res.push(r);
    }
    e.a_tip = coef[4];
    // d_j = (∂A/∂p_j) c per sample, then J_j = −P⊥ d_j = −(d_j − A g_j)
    // with g_j = (AᵀA)⁻¹ Aᵀ d_j.
    let d_of = |i: usize, j: usize| {
        let (_, _, dh, dt) = &e.cols[i];
        let d = coef[3] * dh[j] + coef[4] * dt[j];
        if j == 4 { d * dk_dsigma } else { d }
    };
    let mut atd = [[0f64; M]; NP];
    for i in 0..n {
        let a = row(i);
        for (j, atd_j) in atd.iter_mut().enumerate() {
            let d = d_of(i, j);
            for r in 0..M {
                atd_j[r] += a[r] * d;
            }
        }
    }
    let mut g = [[0f64; M]; NP];
    for j in 0..NP {
        g[j] = solve_sym(ata, atd[j])?;
    }
    for (j, col) in e.jac.iter_mut().enumerate() {
        col.clear();
        col.extend((0..n).map(|i| {
            let a = row(i);
            let proj: f64 = a.iter().zip(&g[j]).map(|(x, c)| x * c).sum();
            proj - d_of(i, j)
        }));
    }
    Some(())
}

/// Solves a small symmetric positive (semi-)definite system by Gaussian
/// elimination with partial pivoting; `None` when singular.
pub(super) fn solve_sym<const M: usize>(mut a: [[f64; M]; M], mut b: [f64; M]) -> Option<[f64; M]> {
    let scale = (0..M)
        .map(|i| a[i][i].abs())
        .fold(0.0, f64::max)
        .max(1e-300);
    for col in 0..M {
        let piv = (col..M).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 * scale {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..M {
            let f = a[r][col] / a[col][col];
            for c in col..M {
                a[r][c] -= f * a[col][c];
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0f64; M];
    for r in (0..M).rev() {
        let mut acc = b[r];
        for c in r + 1..M {
            acc -= a[r][c] * x[c];
        }
        x[r] = acc / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, e) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265),
        ] {
            assert!((erf(x) - e).abs() < 2e-7, "{x}");
            assert!((erf(-x) + e).abs() < 2e-7, "{x}");
        }
    }

    /// A tip off-centre in its hole, with a background plane and noise-free
    /// levels, sampled on a rotated grid.
    fn samples(round: bool, truth: &Params) -> Samples {
        let (sn, cs) = 0.07f64.sin_cos();
        let mut s = Samples::default();
        let k = FRAC_1_SQRT_2 / truth[4];
        for yi in -12..=12 {
            for xi in -12..=12 {
                let (dx, dy) = (xi as f64, yi as f64);
                let (u, v) = (cs * dx + sn * dy, -sn * dx + cs * dy);
                let (hole, tip, _, _) = columns(round, u, v, truth, k);
                s.u.push(u);
                s.v.push(v);
                s.x.push(dx / 12.0);
                s.y.push(dy / 12.0);
                s.val
                    .push(80.0 + 3.0 * dx / 12.0 - 20.0 * hole + 150.0 * tip);
            }
        }
        s
    }

    /// The closed-form Jacobian against central differences of the
    /// projected residuals, for both shapes, at a point away from the truth
    /// (non-zero residuals) and with the tip overlapping the hole's rim.
    #[test]
    fn the_jacobian_matches_central_differences_of_the_residuals() {
        for round in [false, true] {
            let truth: Params = [1.3, -0.8, 4.0, 5.5, 1.4];
            let s = samples(round, &truth);
            let p: Params = [2.1, -1.7, 3.6, 5.1, 1.1];
            let mut e = Eval::default();
            evaluate(&s, round, &p, &mut e).unwrap();
            assert!(e.ss > 1.0, "the point must not be the minimum");
            for j in 0..NP {
                let h = 1e-5;
                let (mut a, mut b) = (Eval::default(), Eval::default());
                let (mut pa, mut pb) = (p, p);
                pa[j] += h;
                pb[j] -= h;
                evaluate(&s, round, &pa, &mut a).unwrap();
                evaluate(&s, round, &pb, &mut b).unwrap();
                // Kaufman's Jacobian omits a term in the columns' span, to
                // which the residual is orthogonal: compare what the fit
                // steps along, the gradient Jᵀr, which is exact.
                let num_grad: f64 = a
                    .res
                    .iter()
                    .zip(&b.res)
                    .zip(&e.res)
                    .map(|((x, y), r)| (x - y) / (2.0 * h) * r)
                    .sum();
                let grad: f64 = e.jac[j].iter().zip(&e.res).map(|(x, r)| x * r).sum();
                let scale = num_grad.abs().max(1e-3 * e.ss);
                assert!(
                    (grad - num_grad).abs() < 1e-4 * scale,
                    "round {round}, parameter {j}: gradient {grad} against {num_grad}"
                );
            }
        }
    }
}
