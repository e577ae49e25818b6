//! sin and cos of an angle that moves little between calls (the crank and
//! rod angles over the stages of one integration step), by rotating a
//! nearby base angle: sin(b + d), cos(b + d) from sin b, cos b and short
//! series of sin d, cos d. libm's `sin_cos` was a fifth of a simulation's
//! instructions (two calls per right-hand side).
//!
//! The base is the multiple of 1/32 rad nearest to the angle, so |d| ≤
//! 1/64 and the series need three Horner steps each: within one
//! integration step every stage waits for the last, and the rod angle's
//! sine and cosine are on the right-hand side's critical path (the series
//! to d¹⁵ that a reach of 0.25 rad needed were ~30 cycles longer). The
//! result is a function of the angle alone, not of the calls before it
//! (a run gives the same numbers whatever else evaluated the model in
//! between, e.g. the curves' grid). The last two bases' sin b, cos b are
//! kept (libm computes them when the angle moves to another one, a few
//! hundred times per crank revolution). Accuracy: the series' truncation
//! is below 1e-19 (relative) and the result within a few ulps of
//! `sin_cos`.
//!
//! The cache lives in a `Cell`: a model evaluates through `&self`.

use std::cell::Cell;

/// Spacing of the base angles (rad): |angle − base| ≤ SPACING / 2.
pub const SPACING: f64 = 1.0 / 32.0;

/// The last two base angles with their sine and cosine.
#[derive(Debug, Clone)]
pub struct SinCos {
    bases: Cell<[(f64, f64, f64); 2]>,
}

impl Default for SinCos {
    fn default() -> Self {
        Self::new()
    }
}

impl SinCos {
    pub fn new() -> Self {
        Self {
            bases: Cell::new([(0.0, 0.0, 1.0), (f64::NAN, f64::NAN, f64::NAN)]),
        }
    }

    /// (sin x, cos x).
    #[inline(always)]
    pub fn get(&self, x: f64) -> (f64, f64) {
        if !(x.abs() < 1e15) {
            // Far out (or not a number): no base in reach of the cast.
            return x.sin_cos();
        }
        // The nearest multiple of SPACING (x·32 rounded half away from
        // zero by a truncating cast; exact: a power-of-two scale), and the
        // exact remainder d (|d| ≤ 1/64).
        let k = (x * (1.0 / SPACING) + 0.5f64.copysign(x)) as i64 as f64;
        let b = k * SPACING;
        let d = x - b;
        let bases = self.bases.get();
        let (sb, cb) = if bases[0].0 == b {
            (bases[0].1, bases[0].2)
        } else if bases[1].0 == b {
            (bases[1].1, bases[1].2)
        } else {
            let (s, c) = b.sin_cos();
            self.bases.set([(b, s, c), bases[0]]);
            (s, c)
        };
        let (sd, cd) = small(d);
        (sb * cd + cb * sd, cb * cd - sb * sd)
    }
}

/// sin d and cos d for |d| ≤ 1/64: Taylor series to d⁷ and d⁶ in Horner
/// form on d² (the next terms, d⁹/9! relative to d and d⁸/8!, are below
/// 1e-20 and 1e-19).
#[inline(always)]
fn small(d: f64) -> (f64, f64) {
    let z = d * d;
    let s = 1.0 - z * (1.0 / 6.0) * (1.0 - z * (1.0 / 20.0) * (1.0 - z * (1.0 / 42.0)));
    let c = 1.0 - z * (1.0 / 2.0) * (1.0 - z * (1.0 / 12.0) * (1.0 - z * (1.0 / 30.0)));
    (d * s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against libm over steps small and large, forward and back.
    #[test]
    fn rotation_agrees_with_libm() {
        let sc = SinCos::new();
        let mut x = 3.0;
        let mut worst: f64 = 0.0;
        let mut k = 0u64;
        for i in 0..200_000 {
            // Steps of all sizes, some jumping back (event location).
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (k >> 11) as f64 / (1u64 << 53) as f64;
            x += (u - 0.45) * if i % 97 == 0 { 1.0 } else { 0.01 };
            let (s, c) = sc.get(x);
            let (s0, c0) = x.sin_cos();
            worst = worst.max((s - s0).abs()).max((c - c0).abs());
        }
        assert!(worst < 8.0 * f64::EPSILON, "worst {worst:e}");
        // A function of the angle alone: the same bits after another history.
        let fresh = SinCos::new();
        for x in [3.0, -0.7, 1e3 + 0.01, 0.015625, -0.015625, 2.0 * SPACING] {
            assert_eq!(fresh.get(x), sc.get(x), "x = {x}");
            assert_eq!(SinCos::new().get(x), sc.get(x), "x = {x}");
        }
        // At the edge of the series' range.
        let edge = SPACING / 2.0;
        for d in [edge, -edge, 0.999 * edge] {
            let (s, c) = small(d);
            assert!(
                (s - d.sin()).abs() < 2.0 * f64::EPSILON
                    && (c - d.cos()).abs() < 2.0 * f64::EPSILON
            );
        }
    }

    /// Over the whole range a run meets and far beyond (±1e4 rad, random
    /// angles, no history): within 2 ulps of 1 of std's sin and cos, and
    /// within 1e-15 relative where the value is not near a zero (a
    /// truncated series or a wrong base would be off by far more).
    #[test]
    fn agrees_with_std_over_large_angles() {
        let sc = SinCos::new();
        let mut k = 7u64;
        let (mut worst_abs, mut worst_rel): (f64, f64) = (0.0, 0.0);
        for _ in 0..1_000_000 {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (k >> 11) as f64 / (1u64 << 53) as f64;
            let x = (u - 0.5) * 2e4;
            let (s, c) = sc.get(x);
            let (s0, c0) = x.sin_cos();
            for (v, v0) in [(s, s0), (c, c0)] {
                worst_abs = worst_abs.max((v - v0).abs());
                if v0.abs() > 0.1 {
                    worst_rel = worst_rel.max(((v - v0) / v0).abs());
                }
            }
        }
        assert!(worst_abs <= 2.0 * f64::EPSILON, "worst abs {worst_abs:e}");
        assert!(worst_rel <= 1e-15, "worst rel {worst_rel:e}");
        // Bases and halfway points, signs, and beyond the cast's reach.
        for x in [
            0.0,
            -0.0,
            SPACING,
            -SPACING,
            1.5 * SPACING,
            -1.5 * SPACING,
            1e4,
            -1e4,
            1e16,
            -3e17,
        ] {
            let (s, c) = sc.get(x);
            let (s0, c0) = x.sin_cos();
            assert!(
                (s - s0).abs() <= 2.0 * f64::EPSILON && (c - c0).abs() <= 2.0 * f64::EPSILON,
                "x = {x}"
            );
        }
        assert!(sc.get(f64::NAN).0.is_nan());
    }
}
