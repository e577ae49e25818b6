//! Scalar root bracketing and maximisation on dense output (Brent's
//! methods), and golden-section minimisation for the fits.

/// Finds t in [a, b] with g(a) and g(b) of opposite signs (g(a) on the "old"
/// side) such that g(t) lies on the NEW side (the sign of g(b), or zero) and
/// `accept(g(t))` holds, or the bracket has shrunk to `t_tol`. Returns the
/// point on the new side and g there, plus the number of evaluations.
///
/// Keeping the returned point on the new side matters for events: a root
/// reported a hair on the old side would make the next crossing invisible
/// (model.md, Integration).
pub fn bracket_root<G, A>(
    mut g: G,
    a: f64,
    ga: f64,
    b: f64,
    gb: f64,
    t_tol: f64,
    accept: A,
) -> (f64, f64, u32)
where
    G: FnMut(f64) -> f64,
    A: Fn(f64) -> bool,
{
    // Brent's zeroin, watching every evaluated point: the first one on the
    // new side that `accept`s is returned; otherwise, once the bracket is
    // below `t_tol`, its end on the new side. The new side is strictly the
    // sign of g(b): an exact zero counts as the old side, because next to a
    // restart point g can round to 0 (e − c below the resolution of c).
    let new_side = |v: f64| v != 0.0 && v.signum() == gb.signum();
    if accept(gb) {
        return (b, gb, 0);
    }
    let (mut xa, mut fa, mut xb, mut fb) = (a, ga, b, gb);
    let (mut xc, mut fc) = (xa, fa);
    let mut d = xb - xa;
    let mut e = d;
    let mut evals = 0;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) && fb != 0.0 {
            xc = xa;
            fc = fa;
            d = xb - xa;
            e = d;
        }
        if fc.abs() < fb.abs() {
            xa = xb;
            xb = xc;
            xc = xa;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * f64::EPSILON * xb.abs() + 0.5 * t_tol;
        let xm = 0.5 * (xc - xb);
        if xm.abs() <= tol1 {
            break;
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if xa == xc {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (xb - xa) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol1 * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        xa = xb;
        fa = fb;
        xb += if d.abs() > tol1 {
            d
        } else {
            tol1 * xm.signum()
        };
        fb = g(xb);
        evals += 1;
        if fb == 0.0 {
            // An exact zero is not a point on the new side: keep it as the
            // old side's end and close the bracket towards the new side.
            fb = -gb.signum() * f64::MIN_POSITIVE;
        }
        if new_side(fb) && accept(fb) {
            return (xb, fb, evals);
        }
    }
    // The bracket [xb, xc] is tiny: return its end on the new side.
    if new_side(fb) {
        (xb, fb, evals)
    } else {
        (xc, fc, evals)
    }
}

/// Maximises g on [a, b] (Brent's golden-section / parabolic method) to an
/// abscissa tolerance `t_tol`. Returns (t, g(t), evaluations). The end
/// values, when known, are compared too, so a monotone g gives its larger end.
pub fn maximize<G>(mut g: G, a: f64, b: f64, ga: f64, gb: f64, t_tol: f64) -> (f64, f64, u32)
where
    G: FnMut(f64) -> f64,
{
    const CGOLD: f64 = 0.381_966_011_250_105_1;
    let (mut lo, mut hi) = if a < b { (a, b) } else { (b, a) };
    let mut x = lo + CGOLD * (hi - lo);
    let mut w = x;
    let mut v = x;
    let mut fx = -g(x);
    let mut evals = 1;
    let mut fw = fx;
    let mut fv = fx;
    let mut d: f64 = 0.0;
    let mut e: f64 = 0.0;
    for _ in 0..100 {
        let xm = 0.5 * (lo + hi);
        let tol1 = t_tol.max(1e-15 * x.abs());
        let tol2 = 2.0 * tol1;
        if (x - xm).abs() <= tol2 - 0.5 * (hi - lo) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let etemp = e;
            e = d;
            if p.abs() < (0.5 * q * etemp).abs() && p > q * (lo - x) && p < q * (hi - x) {
                d = p / q;
                let u = x + d;
                if u - lo < tol2 || hi - u < tol2 {
                    d = if xm - x >= 0.0 { tol1 } else { -tol1 };
                }
                golden = false;
            }
        }
        if golden {
            e = if x >= xm { lo - x } else { hi - x };
            d = CGOLD * e;
        }
        let u = if d.abs() >= tol1 {
            x + d
        } else {
            x + tol1 * d.signum()
        };
        let fu = -g(u);
        evals += 1;
        if fu <= fx {
            if u >= x {
                lo = x;
            } else {
                hi = x;
            }
            v = w;
            fv = fw;
            w = x;
            fw = fx;
            x = u;
            fx = fu;
        } else {
            if u < x {
                lo = u;
            } else {
                hi = u;
            }
            if fu <= fw || w == x {
                v = w;
                fv = fw;
                w = u;
                fw = fu;
            } else if fu <= fv || v == x || v == w {
                v = u;
                fv = fu;
            }
        }
    }
    let mut best = (x, -fx);
    if ga > best.1 {
        best = (a, ga);
    }
    if gb > best.1 {
        best = (b, gb);
    }
    (best.0, best.1, evals)
}

/// Minimises f on [lo, hi] by Brent's golden-section / parabolic method
/// ([`maximize`] of −f) to an abscissa tolerance `t_tol` (the bracket ends
/// within about 4·`t_tol`). Returns (x, f(x), evaluations). On a smooth
/// objective it needs a fraction of a plain golden section's evaluations
/// for the same bracket (unit test below).
pub fn brent_min(lo: f64, hi: f64, t_tol: f64, mut f: impl FnMut(f64) -> f64) -> (f64, f64, u32) {
    let (x, g, n) = maximize(
        |x| -f(x),
        lo,
        hi,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        t_tol,
    );
    (x, -g, n)
}

/// Golden-section search for the minimum of a unimodal `f` on [lo, hi]:
/// `iters` shrinkings by the golden ratio (one evaluation each), then the
/// middle of what is left.
pub fn golden_min(mut lo: f64, mut hi: f64, iters: usize, f: impl Fn(f64) -> f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iters {
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_on_new_side() {
        // Root of cos at π/2, crossing from + to −.
        let (t, gt, n) = bracket_root(f64::cos, 1.0, 1f64.cos(), 2.0, 2f64.cos(), 1e-15, |g| {
            g.abs() < 1e-12
        });
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-11);
        assert!(gt <= 0.0);
        assert!(n < 12, "{n} evaluations");
        // The other direction.
        let (t, gt, _) = bracket_root(f64::cos, 2.0, 2f64.cos(), 1.0, 1f64.cos(), 1e-15, |g| {
            g.abs() < 1e-12
        });
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-11 && gt >= 0.0);
        // Steep exponential.
        let f = |t: f64| (50.0 * t).exp() - 2.0;
        let (t, gt, n) = bracket_root(f, 0.0, f(0.0), 1.0, f(1.0), 1e-16, |g| g.abs() < 1e-12);
        assert!(
            (t - 2f64.ln() / 50.0).abs() < 1e-13 && gt >= 0.0 && n < 30,
            "{t} {n}"
        );
        // A flat-ish crossing still terminates on the new side.
        let f = |t: f64| (t - 0.3).powi(3);
        let (t, gt, _) = bracket_root(f, 0.0, f(0.0), 1.0, f(1.0), 1e-14, |g| g.abs() < 1e-30);
        assert!(gt >= 0.0 && (t - 0.3).abs() < 1e-4, "{t} {gt}");
    }

    #[test]
    fn maximum_found() {
        let g = |t: f64| 1.0 - (t - 0.7).powi(2);
        let (t, v, n) = maximize(g, 0.0, 2.0, g(0.0), g(2.0), 1e-10);
        assert!((t - 0.7).abs() < 1e-7 && (v - 1.0).abs() < 1e-14, "{t} {v}");
        assert!(n < 40);
        // Monotone: the end wins.
        let (t, _, _) = maximize(|t| t, 0.0, 1.0, 0.0, 1.0, 1e-10);
        assert_eq!(t, 1.0);
    }

    /// On a smooth but not quadratic objective, Brent reaches the bracket
    /// a 19-iteration golden section reaches in far fewer evaluations
    /// (the force fit's searches: docs/rig-logs.md); on a kinked one
    /// (|x − a|, where parabolas do not help) it still converges.
    #[test]
    fn brent_min_needs_fewer_evaluations_than_golden() {
        let f = |x: f64| (x - 1.3).powi(2) + 0.3 * (x - 1.3).powi(4) + (2.0 * x).cos() * 0.01;
        // The true minimum, by a long golden section.
        let truth = golden_min(0.0, 4.0, 90, f);
        let width = 4.0 * 0.618_034f64.powi(19);
        let (x, fx, n) = brent_min(0.0, 4.0, width / 4.0, f);
        assert!((x - truth).abs() < width, "{x} vs {truth}");
        assert_eq!(fx, f(x));
        assert!(n <= 12, "{n} evaluations (golden: 21)");
        let (x, _, n) = brent_min(-1.0, 3.0, 1e-9, |x: f64| (x - 0.37).abs());
        assert!((x - 0.37).abs() < 5e-9, "{x}");
        assert!(n < 100, "{n}");
    }
}
