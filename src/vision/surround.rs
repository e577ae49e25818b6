//! The housing's level around the tips, as one plane through the tips' own
//! surrounds: the level a blurred tip's disc energy is taken against when
//! the coarse background does not follow the housing.
//!
//! The coarse background (an opening then a closing, `morph::background_square`)
//! follows the housing and fills the clearance holes, but a one-row housing
//! narrower than the closing's window, between two bands of a fixture
//! brighter than itself, is raised toward the fixture (Rust 950 588: a
//! bright 1 × 12, the housing at 39 DN, its background read 54–62 DN with
//! tips 75 DN above the housing). A tip's energy inside its disc
//! (190 px there) against a level 20 DN high loses most of itself, and what
//! is left follows the background's own ripple: the ok tips' energy ratios
//! read 0.25–1.53 in a clean image, three of them "damaged". Each tip's own
//! surround (the median of its window's border) does follow the housing, but
//! one per tip adds its noise times the disc's pixel count (the seventh
//! round's ring, not kept); a plane through all of them averages it away
//! and keeps the gradient and most of the vignetting across a part.

use super::grid;

/// How far above the tips' own surrounds (median over the tips, as a
/// fraction of their median contrast over it) the coarse background may
/// stand before the plane replaces it. Where it follows the housing the
/// two differ by a blurred hole's rim in the window's border, a few
/// hundredths of the tip contrast.
pub(crate) const RAISED: f64 = 0.15;

/// The report's note where the plane replaced the coarse background.
pub(crate) fn raised_note() -> String {
    format!(
        "the housing's background stood over {RAISED:.2} of the tip contrast above the tips' surrounds (a narrow housing beside a brighter fixture): tip energies taken against a plane through the surrounds"
    )
}

/// `level = a + b (x − x0) + c (y − y0)`, full-resolution pixels, `sign`
/// space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SurroundPlane {
    a: f64,
    b: f64,
    c: f64,
    x0: f64,
    y0: f64,
}

impl SurroundPlane {
    /// The plane's level at (x, y).
    pub fn at(&self, x: f64, y: f64) -> f32 {
        (self.a + self.b * (x - self.x0) + self.c * (y - self.y0)) as f32
    }

    /// The plane through the tips' surrounds `tips` ((x, y, level over the
    /// surround, surround), `sign` space) when the coarse background
    /// (`bg_at`) stands more than [`RAISED`] of the tips' contrast above
    /// them; `None` when it does not or fewer than three tips are given.
    pub fn if_background_raised(
        tips: &[(f64, f64, f32, f32)],
        bg_at: impl Fn(f64, f64) -> f32,
    ) -> Option<SurroundPlane> {
        if tips.len() < 3 {
            return None;
        }
        let mut raised: Vec<f64> = tips
            .iter()
            .map(|t| (bg_at(t.0, t.1) - t.3) as f64)
            .collect();
        let mut contrast: Vec<f64> = tips.iter().map(|t| (t.2 - t.3) as f64).collect();
        let (raised, contrast) = (grid::median(&mut raised)?, grid::median(&mut contrast)?);
        if contrast <= 0.0 || raised <= RAISED * contrast {
            return None;
        }
        let pts: Vec<(f64, f64, f64)> = tips.iter().map(|t| (t.0, t.1, t.3 as f64)).collect();
        let first = Self::fit(&pts)?;
        // Once more without the surrounds 3 robust σ off the first plane
        // (a tip beside debris or the housing's corner).
        let res: Vec<f64> = pts
            .iter()
            .map(|p| (p.2 - first.at(p.0, p.1) as f64).abs())
            .collect();
        let sigma = 1.4826 * grid::median(&mut res.clone())?;
        let kept: Vec<(f64, f64, f64)> = pts
            .iter()
            .zip(&res)
            .filter(|(_, r)| **r <= 3.0 * sigma)
            .map(|(p, _)| *p)
            .collect();
        if kept.len() >= 3 && kept.len() < pts.len() {
            Self::fit(&kept)
        } else {
            Some(first)
        }
    }

    /// Least squares through `pts` (x, y, level). Points on one line (a
    /// one-row part) leave the slope across it undetermined: a small ridge
    /// on the slopes sets it to zero there and changes nothing otherwise.
    pub(crate) fn fit(pts: &[(f64, f64, f64)]) -> Option<SurroundPlane> {
        let n = pts.len() as f64;
        if n < 1.0 {
            return None;
        }
        let x0 = pts.iter().map(|p| p.0).sum::<f64>() / n;
        let y0 = pts.iter().map(|p| p.1).sum::<f64>() / n;
        let a = pts.iter().map(|p| p.2).sum::<f64>() / n;
        let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &(x, y, z) in pts {
            let (dx, dy, dz) = (x - x0, y - y0, z - a);
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
            sxz += dx * dz;
            syz += dy * dz;
        }
        let ridge = 1e-9 * (sxx + syy) + 1e-12;
        let (sxx, syy) = (sxx + ridge, syy + ridge);
        let det = sxx * syy - sxy * sxy;
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let b = (syy * sxz - sxy * syz) / det;
        let c = (sxx * syz - sxy * sxz) / det;
        Some(SurroundPlane { a, b, c, x0, y0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tips on a 1 × 6 row along a tilted line and a 3 × 3 grid, their
    /// surrounds on the plane 40 + 0.05 x − 0.02 y, tip contrast 75.
    fn tips(one_row: bool) -> Vec<(f64, f64, f32, f32)> {
        let plane = |x: f64, y: f64| (40.0 + 0.05 * x - 0.02 * y) as f32;
        let xy: Vec<(f64, f64)> = if one_row {
            (0..6)
                .map(|i| (30.0 + 27.0 * i as f64, 130.0 + 1.2 * i as f64))
                .collect()
        } else {
            (0..9)
                .map(|i| (50.0 + 30.0 * (i % 3) as f64, 40.0 + 30.0 * (i / 3) as f64))
                .collect()
        };
        xy.into_iter()
            .map(|(x, y)| (x, y, plane(x, y) + 75.0, plane(x, y)))
            .collect()
    }

    #[test]
    fn a_background_raised_toward_the_fixture_is_replaced_by_the_tips_surrounds() {
        for one_row in [true, false] {
            let t = tips(one_row);
            let p = SurroundPlane::if_background_raised(&t, |_, _| 60.0).expect("raised by 20");
            for &(x, y, _, s) in &t {
                assert!(
                    (p.at(x, y) - s).abs() < 1e-3,
                    "{one_row}: {} vs {s}",
                    p.at(x, y)
                );
            }
            // Off the row, the slope across it is zero, not invented.
            if one_row {
                let (x, y) = (t[2].0, t[2].1);
                assert!((p.at(x, y + 10.0) - p.at(x, y)).abs() < 0.05);
            }
        }
    }

    #[test]
    fn a_background_that_follows_the_housing_is_kept_and_an_odd_surround_is_left_out() {
        let t = tips(false);
        // 5 DN (0.07 of the contrast) above the surrounds: the coarse
        // background stays.
        assert!(SurroundPlane::if_background_raised(&t, |_, _| t[0].3 + 5.0).is_none());
        // One tip's surround 30 DN off (debris in its window's border).
        let mut t = tips(false);
        t[4].3 += 30.0;
        let p = SurroundPlane::if_background_raised(&t, |_, _| 70.0).unwrap();
        let (x, y) = (t[0].0, t[0].1);
        assert!((p.at(x, y) - t[0].3).abs() < 1e-3);
        // Fewer than three tips: nothing to fit.
        assert!(SurroundPlane::if_background_raised(&t[..2], |_, _| 70.0).is_none());
    }
}
