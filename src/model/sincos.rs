//! sin and cos of an angle that moves little between calls (the crank and
//! rod angles over the stages of one integration step), by rotating the
//! last fully computed pair: sin(b + d), cos(b + d) from sin b, cos b and
//! short series of sin d, cos d. libm's `sin_cos` was a fifth of a
//! simulation's instructions (two calls per right-hand side); the rotation
//! costs about half of one. Accuracy: |d| ≤ [`REACH`] keeps the series'
//! truncation below 2e-25 and the result within a few ulps of `sin_cos`.
//!
//! The base lives in a `Cell`: a model evaluates through `&self`. Results
//! depend on the order of the calls only at the level of rounding, and the
//! order is deterministic.

use std::cell::Cell;

/// Largest |angle − base| served by rotation (rad); further away the pair
/// is computed afresh and becomes the new base.
pub const REACH: f64 = 0.25;

/// A cached base angle with its sine and cosine.
#[derive(Debug, Clone, Default)]
pub struct SinCos {
    base: Cell<(f64, f64, f64)>,
}

impl SinCos {
    pub fn new() -> Self {
        Self {
            base: Cell::new((0.0, 0.0, 1.0)),
        }
    }

    /// (sin x, cos x).
    #[inline(always)]
    pub fn get(&self, x: f64) -> (f64, f64) {
        let (b, sb, cb) = self.base.get();
        let d = x - b;
        if d.abs() <= REACH {
            let (sd, cd) = small(d);
            (sb * cd + cb * sd, cb * cd - sb * sd)
        } else {
            let (s, c) = x.sin_cos();
            self.base.set((x, s, c));
            (s, c)
        }
    }
}

/// sin d and cos d for |d| ≤ REACH: Taylor series to d¹⁵ and d¹⁶ (the
/// next terms are below 2e-25), in Horner form on d².
#[inline(always)]
fn small(d: f64) -> (f64, f64) {
    let z = d * d;
    let mut s = 1.0 - z * (1.0 / 210.0);
    for k in [156.0, 110.0, 72.0, 42.0, 20.0, 6.0] {
        s = 1.0 - z * (1.0 / k) * s;
    }
    let mut c = 1.0 - z * (1.0 / 240.0);
    for k in [182.0, 132.0, 90.0, 56.0, 30.0, 12.0, 2.0] {
        c = 1.0 - z * (1.0 / k) * c;
    }
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
        // At the reach's edge.
        for d in [REACH, -REACH, 0.999 * REACH] {
            let (s, c) = small(d);
            assert!(
                (s - d.sin()).abs() < 2.0 * f64::EPSILON
                    && (c - d.cos()).abs() < 2.0 * f64::EPSILON
            );
        }
    }
}
