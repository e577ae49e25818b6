//! ∫|f| dt over the reported window from a smooth primitive F of f,
//! closed at the zeros of f located on each step's dense output (a kink
//! inside a step would cost O(h²) per sign change): the time averages of
//! |Δs| (primitive: the quadrature Q_s) and |Δv| (primitive: Δs).

use crate::solver::roots::{bracket_root, maximize};

/// Whether f, going from fa to fb with slopes dfa, dfb, may have a zero
/// inside: a sign change, or an extremum turning back towards zero.
pub(super) fn may_have_zero(fa: f64, fb: f64, dfa: f64, dfb: f64) -> bool {
    if fa * fb < 0.0 {
        return true;
    }
    let sg = fa.signum();
    fa != 0.0 && fb != 0.0 && sg * dfa < 0.0 && sg * dfb > 0.0
}

/// ∫|f| dt assembled from a smooth primitive F between the zeros of f.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct AbsIntegral {
    pub(super) total: f64,
    /// F at the start of the current piece (last zero of f).
    pub(super) piece_start: f64,
}

impl AbsIntegral {
    /// Accounts for the segment [ta, tb] on which f goes from fa to fb with
    /// slopes dfa, dfb: finds the zeros of f (one sign change, or two around
    /// an interior extremum) on the dense output and closes a piece at each.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn segment<Fz: Fn(f64) -> f64, Fp: Fn(f64) -> f64>(
        &mut self,
        ta: f64,
        tb: f64,
        (fa, fb): (f64, f64),
        (dfa, dfb): (f64, f64),
        f: Fz,
        prim: Fp,
        evals: &mut u64,
    ) {
        let t_tol = (tb - ta) * 1e-9;
        let close = |z: f64, this: &mut Self, evals: &mut u64| {
            let fz = prim(z);
            *evals += 1;
            this.total += (fz - this.piece_start).abs();
            this.piece_start = fz;
        };
        if !may_have_zero(fa, fb, dfa, dfb) {
            return;
        }
        if fa * fb < 0.0 {
            let (z, _, n) = bracket_root(&f, ta, fa, tb, fb, t_tol, |_| false);
            *evals += n as u64;
            close(z, self, evals);
        } else if fa != 0.0 && fb != 0.0 {
            let sg = fa.signum();
            if sg * dfa < 0.0 && sg * dfb > 0.0 {
                let (tm, vm, n) = maximize(|t| -sg * f(t), ta, tb, -sg * fa, -sg * fb, t_tol);
                *evals += n as u64;
                if vm > 0.0 {
                    let fm = -sg * vm;
                    let (z1, _, n1) = bracket_root(&f, ta, fa, tm, fm, t_tol, |_| false);
                    let (z2, _, n2) = bracket_root(&f, tm, fm, tb, fb, t_tol, |_| false);
                    *evals += (n1 + n2) as u64;
                    close(z1, self, evals);
                    close(z2, self, evals);
                }
            }
        }
    }

    /// Closes the last piece at the window's end, where the primitive is `f_end`.
    pub(super) fn finish(&mut self, f_end: f64) -> f64 {
        self.total + (f_end - self.piece_start).abs()
    }
}
