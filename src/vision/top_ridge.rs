//! Top view: the level of a straight ridge through a blob left over, so
//! that a clump of a band is told from debris lying on the housing.
//!
//! A dark part's chamfer band is darker than the housing, so in sign space
//! it is a ridge along the housing's edge, and at low contrast, strong
//! noise or JPEG the band's half-level mask breaks into clumps, each a
//! blob clear of its window (Rust 945 815: eleven along one band, contrast
//! 0.39, noise 14.6 DN, JPEG 53, one whose core read 0.60 of the tip
//! level). The end of a band cut off by the orientation mark is such a
//! blob too (945 927). What debris has and a clump does not is its own
//! edge all round: a ridge is as bright a little way off on both sides
//! along its length. So the sides of a straight line through the blob's
//! centre are read in every direction, each as the mean over a small disc
//! beyond the blob's reach, and the ridge is the direction whose dimmer
//! side is brightest; a blob is debris only if its core stands clear of
//! that level, as it must of its surround.

use super::gray::{Plane, Px};
use super::tip_levels::{contrast_ratio, disc_mean};

/// How many directions over a half turn are read. At the reach used
/// (about 1.5 tip widths) a step of 5° moves a side disc by 0.13 tip
/// widths across the line, less than the narrowest band's half width.
const DIRECTIONS: usize = 36;

/// Where a ridge's sides are read (pixels).
#[derive(Debug, Clone, Copy)]
pub(super) struct Probe {
    /// Distance of each side's disc from the blob's centre.
    pub reach: f64,
    /// Radius of each side's disc.
    pub r_disc: f64,
    /// A side nearer a tip than this is not read.
    pub clear: f64,
}

/// The level of the brightest straight ridge through `c`: over every
/// direction, the lower of the mean levels of two discs of radius
/// `p.r_disc` at ±`p.reach` from `c`, as fractions of the way from the
/// local background `b` to the local tip level `t` (sign space); the
/// highest of these. A side within `p.clear` of a tip (`tips`) or off the
/// image says nothing of a ridge (a tip beside debris is no band), and
/// that direction is not read. `None` when no direction could be read.
pub(super) fn ridge_level<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    c: (f64, f64),
    p: Probe,
    (t, b): (f32, f32),
    tips: &[(f64, f64)],
) -> Option<f64> {
    let Probe {
        reach,
        r_disc,
        clear,
    } = p;
    let inside = |p: (f64, f64)| {
        p.0 - r_disc >= 0.0
            && p.1 - r_disc >= 0.0
            && p.0 + r_disc <= plane.w as f64 - 1.0
            && p.1 + r_disc <= plane.h as f64 - 1.0
            && tips.iter().all(|q| (q.0 - p.0).hypot(q.1 - p.1) >= clear)
    };
    let mut best: Option<f64> = None;
    for k in 0..DIRECTIONS {
        let a = std::f64::consts::PI * k as f64 / DIRECTIONS as f64;
        let (dx, dy) = (reach * a.cos(), reach * a.sin());
        let sides = [(c.0 + dx, c.1 + dy), (c.0 - dx, c.1 - dy)];
        if !sides.iter().all(|&p| inside(p)) {
            continue;
        }
        let mut lower = f64::INFINITY;
        for p in sides {
            let m = disc_mean(plane, sign, p, r_disc)?;
            lower = lower.min(contrast_ratio(m as f32, t, b));
        }
        best = Some(best.map_or(lower, |v: f64| v.max(lower)));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An 80 × 80 image at background 100, tip level 200 (so level 0.5 is
    /// 150), with a horizontal band at `band` through row 40, 5 px wide,
    /// and discs of radius 4 at (40, 40) and at `tips`, at 200.
    fn scene(band: Option<u16>, tips: &[(f64, f64)]) -> Vec<u16> {
        let mut d = vec![100u16; 80 * 80];
        for y in 0..80 {
            for x in 0..80 {
                if let Some(v) = band
                    && (y as i64 - 40).abs() <= 2
                {
                    d[y * 80 + x] = v;
                }
                let on = |c: &(f64, f64)| (x as f64 - c.0).hypot(y as f64 - c.1) <= 4.0;
                if on(&(40.0, 40.0)) || tips.iter().any(on) {
                    d[y * 80 + x] = 200;
                }
            }
        }
        d
    }

    /// The ridge through `c` in `d`, read 12 px out over discs of 1.5 px,
    /// sides within `clear` of `tips` unread.
    fn ridge(d: &[u16], c: (f64, f64), tips: &[(f64, f64)], clear: f64) -> Option<f64> {
        let p = Plane {
            w: 80,
            h: 80,
            data: d,
        };
        let probe = Probe {
            reach: 12.0,
            r_disc: 1.5,
            clear,
        };
        ridge_level(&p, 1.0, c, probe, (200.0, 100.0), tips)
    }

    #[test]
    fn a_band_through_the_blob_reads_at_its_own_level_and_a_bare_housing_at_zero() {
        let r = ridge(&scene(Some(150), &[]), (40.0, 40.0), &[], 3.0).unwrap();
        assert!((r - 0.5).abs() < 1e-6, "{r}");
        let r = ridge(&scene(None, &[]), (40.0, 40.0), &[], 3.0).unwrap();
        assert!(r.abs() < 1e-6, "{r}");
    }

    #[test]
    fn a_tip_on_one_side_is_no_ridge_and_sides_off_the_image_are_not_read() {
        // Tips at ±12 px along the row make the band's direction unreadable;
        // every other direction sees the bare housing.
        let tips = [(28.0, 40.0), (52.0, 40.0)];
        let d = scene(None, &tips);
        let r = ridge(&d, (40.0, 40.0), &tips, 6.0).unwrap();
        assert!(r < 0.05, "{r}");
        // Without the tips named, the row through them reads as a ridge.
        let r = ridge(&d, (40.0, 40.0), &[], 6.0).unwrap();
        assert!(r > 0.95, "{r}");
        // A blob at the image's corner has no direction whose sides both
        // lie inside.
        assert!(ridge(&d, (2.0, 2.0), &[], 6.0).is_none());
    }
}
