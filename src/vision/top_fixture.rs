//! Top view: where to look for debris on the fixture (the background
//! outside the housing) that the candidate search never offers.
//!
//! On a bright part the fixture is itself bright: debris there, painted at
//! a tip's rim level, stands 0.1–0.35 of the tip contrast above it (Rust
//! 830 771, 840 809, 830 274). That is under the coarse threshold, and
//! the faint pass (`top_faint`) wants a peak 4 × the 95th percentile of
//! its neighbourhood's top-hat, which the fixture's own noise reaches
//! (830 771: peak 0.26 of the tip contrast, the ring's 95th percentile
//! 0.09). Here the fixture's noise is read once, robustly, from the
//! top-hat over the fixture itself, and every blob that rises `SEED_SIGMAS`
//! above it becomes a place to measure; the decision is left to the full
//! resolution measure of a protrusion (`top_shoulder`) and the extras'
//! own tests, which texture, gradients and the housing's edge do not pass.
//! The fixture is told from the housing by the grid, not by the housing's
//! outline: on a bright fixture that outline is often not found, or found
//! around the fixture itself (830 771: ±4.7 mm across a ±1.6 mm housing),
//! and debris inside it was never looked at. Beyond 0.4 pitch from the
//! outer tips lies the housing's margin (0.45 pitch or more in both
//! renderers), its edge and the fixture.
//!
//! A dark part's fixture hides debris the same way (Python 590 171: the
//! fixture at the housing's level, so no outline at all and debris 6 tips
//! from the row counted "inside the housing" and refused at 0.49 of the tip
//! level; 620 290: debris across the edge of a housing on a black fixture,
//! a shoulder of the fixture, set aside as "part of a larger structure"),
//! so the pass runs on both polarities, with one more test on dark parts
//! (`LOCAL_SIGMAS`). The seventeenth round kept the outline pass
//! (`shoulder_extra` on refused candidates) to bright parts because a dark
//! part's chamfer band is a ridge; on the Rust sets 830 000 and 860 000
//! this pass found no extra on a dark part's chamfer band (measured: no
//! verdict changed). What it does find beyond debris: texture clumps on a
//! dark housing's margin strip beyond the grid (Python 650 263, two extras
//! on a part that fails anyway), and debris reported on its protruding
//! part, up to a tip from its area centroid (620 062, 620 290).

use super::detect::CoarseSearch;
use super::fit::Similarity;
use super::label;

/// How far above the fixture's median top-hat (in robust σ of it) a blob's
/// peak must rise to be measured. This σ is read at the blob's own scale
/// (the residual smoothed over 0.7 tip widths), so unlike the pixel noise
/// the protrusion tests use it holds the fixture's texture and JPEG blocks:
/// it is the one measure that can tell a texture clump from debris. At 4 σ
/// a clump of a low-contrast textured fixture passed (Python 590 341,
/// JPEG 63: 4.6 σ, 0.36 of the tip contrast) and was then "165 σ" above the
/// pixel noise; the faintest debris found on the tuning sets stands 6.1 σ
/// (Python 590 117) and 7.2 σ (620 154), debris on clean fixtures 29–43 σ.
const SEED_SIGMAS: f32 = 5.0;
/// On a dark part, how far above its own neighbourhood's residual (median
/// and robust σ over the fixture 1–4 tip widths from its peak) a blob's
/// peak must also rise. A dark part's fixture can be the darkest thing in
/// the image (the Python renderer draws it at 30–250 DN under a 150–215
/// housing), so in sign space it stands above the housing and the tips,
/// and the dark clumps of its texture beside the housing's edge are what
/// rises: 5.1–5.5 σ of the whole fixture's residual (Python 650 307,
/// 590 079), but 3.9–4.5 σ of their own neighbourhood's, where the texture
/// is coarser than the fixture's median. Debris stands 8.3–30 σ there
/// (620 290, 590 171, 590 133, 620 338). Bright parts keep the global test
/// alone: debris beside a bright housing's corner stands 5.0 σ locally
/// (590 117), the neighbourhood holding the corner's shading.
const LOCAL_SIGMAS: f32 = 6.0;
/// The lowest peak measured, as a fraction of the typical tip contrast.
const SEED_LEVEL: f32 = 0.1;
/// How many places are measured at most (the highest peaks first).
const MAX_SEEDS: usize = 40;

/// A place on the fixture worth measuring as debris.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FixtureSeed {
    /// Full-resolution pixels.
    pub at: (f64, f64),
    /// How far its peak rises above the fixture's median top-hat, in robust
    /// σ of it (the fixture's noise and texture at the blob's scale);
    /// infinite on a fixture with neither.
    pub z: f32,
}

/// Full-resolution places on the fixture worth measuring as debris:
/// coarse residual blobs outside `grid` (the grid's extent grown by 0.4
/// pitch, part frame, mm), tip-sized or smaller, whose peak
/// rises `SEED_SIGMAS` robust σ above the fixture's median top-hat and
/// `SEED_LEVEL` of the tip contrast; on a dark part (`dark`) also
/// `LOCAL_SIGMAS` above its neighbourhood's. The highest first.
pub(super) fn fixture_seeds(
    cs: &CoarseSearch,
    sim: &Similarity,
    grid: [f64; 4],
    pin_px: f64,
    dark: bool,
) -> Vec<FixtureSeed> {
    let (w, h) = (cs.coarse.w, cs.coarse.h);
    if cs.coarse.data.len() != w * h || w < 3 || h < 3 {
        return Vec::new();
    }
    // Debris is 0.45–2.5 tips in area: a box 0.7 tip widths wide keeps most
    // of its peak and takes the pixel noise down by the box's width.
    let pin_c = pin_px / cs.coarse.k as f64;
    let m = (0.35 * pin_c).round() as usize;
    let smooth = super::morph::box_mean(&cs.coarse.data, w, h, m);
    // What rises above a grey opening 2.6 tip widths wide: the fixture's
    // outline beside a dark (convex) housing, a gradient or vignetting is
    // unchanged by it (the coarse search's top-hat is not: its background
    // under the fixture's rim beside the housing is the housing's, and
    // the whole rim stands out, 830 771).
    let r_se = (1.3 * pin_c).ceil().max(2.0) as usize;
    let open = super::morph::open_square(&smooth, w, h, r_se);
    let th: Vec<f32> = smooth.iter().zip(&open).map(|(a, b)| a - b).collect();
    let to_full = |x, y| cs.coarse.to_full(x, y);
    let on_fixture = outside_grid(w, h, &to_full, sim, grid);
    let mut vals: Vec<f32> = (0..w * h)
        .filter(|&i| on_fixture[i])
        .map(|i| th[i])
        .collect();
    if vals.len() < 64 {
        return Vec::new();
    }
    let med = super::measure::percentile(&mut vals, 0.5);
    let mut dev: Vec<f32> = vals.iter().map(|v| (v - med).abs()).collect();
    let sigma = 1.4826 * super::measure::percentile(&mut dev, 0.5);
    let level = (med + SEED_SIGMAS * sigma).max(SEED_LEVEL * cs.tip_contrast);
    let lab = label::label(w, h, |x, y| on_fixture[y * w + x] && th[y * w + x] > level);
    let tip_area_c = pin_c * pin_c;
    let mut out: Vec<(f32, FixtureSeed)> = Vec::new();
    for b in &lab.blobs {
        if b.area as f64 > 3.0 * tip_area_c {
            continue;
        }
        let mut best = (f32::NEG_INFINITY, 0usize, 0usize);
        for &ri in &b.runs {
            let r = &lab.runs[ri as usize];
            for x in r.x0..r.x1 {
                let v = th[r.y as usize * w + x as usize];
                if v > best.0 {
                    best = (v, x as usize, r.y as usize);
                }
            }
        }
        if dark {
            let z = local_sigmas(&th, w, h, &on_fixture, (best.1, best.2), pin_c, best.0);
            if z < LOCAL_SIGMAS {
                continue;
            }
        }
        let z = if sigma > 0.0 {
            (best.0 - med) / sigma
        } else {
            f32::INFINITY
        };
        let at = cs.coarse.to_full(best.1 as f64, best.2 as f64);
        out.push((best.0, FixtureSeed { at, z }));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out.truncate(MAX_SEEDS);
    out.into_iter().map(|(_, p)| p).collect()
}

/// Which pixels of a `w` × `h` image (whose pixel (x, y) sits at
/// `to_full(x, y)` in the full frame, increasing in each coordinate) lie
/// outside `grid` ([u0, u1, v0, v1], part frame, mm): whether
/// `rect_distance` of `sim.inverse` of each pixel is positive, found as a
/// run per row (see [`monotone_run`]).
fn outside_grid(
    w: usize,
    h: usize,
    to_full: &dyn Fn(f64, f64) -> (f64, f64),
    sim: &Similarity,
    grid: [f64; 4],
) -> Vec<bool> {
    let to_part = sim.inverse_map();
    let mut out = vec![true; w * h];
    for yc in 0..h {
        let uv = |xc: usize| {
            let (x, y) = to_full(xc as f64, yc as f64);
            to_part(x, y)
        };
        // Written as "not beyond the bound", as `rect_distance` reads it: a
        // NaN coordinate counts as inside there, and so here.
        let tests: [&dyn Fn(usize) -> bool; 4] = [
            &|xc| !(uv(xc).0 < grid[0]),
            &|xc| !(uv(xc).0 > grid[1]),
            &|xc| !(uv(xc).1 < grid[2]),
            &|xc| !(uv(xc).1 > grid[3]),
        ];
        let (a, b) = tests.iter().fold((0, w), |(a, b), t| {
            let (ta, tb) = monotone_run(w, t);
            (a.max(ta), b.min(tb))
        });
        if a < b {
            out[yc * w + a..yc * w + b].fill(false);
        }
    }
    out
}

/// The run [a, b) of 0..n where `holds` is true, for a test that is
/// monotone along the row (true on a prefix, a suffix, all or none).
///
/// Why a search: the fixture's mask asks of every coarse pixel whether it
/// lies outside the grid's rectangle in the part frame. Along a row, each
/// of the part-frame coordinates is monotone in x (every operation of
/// [`Similarity::inverse_map`] is
/// monotone in its one varying operand, rounding included), so each of the
/// rectangle's four bounds holds on a prefix or a suffix, and the pixels
/// inside on one run: found with O(log n) evaluations of the very
/// expression a per-pixel test would evaluate, with the same answer.
fn monotone_run(n: usize, holds: &dyn Fn(usize) -> bool) -> (usize, usize) {
    if n == 0 {
        return (0, 0);
    }
    let (first, last) = (holds(0), holds(n - 1));
    if first == last {
        return if first { (0, n) } else { (0, 0) };
    }
    // The first index where `holds` differs from `first`.
    let (mut lo, mut hi) = (0usize, n - 1); // holds(lo) == first != holds(hi)
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if holds(mid) == first {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if first { (0, hi) } else { (hi, n) }
}

/// How many robust σ `peak` at `at` stands above the residual `th` of the
/// fixture around it: its median and 1.4826·MAD over the fixture's coarse
/// pixels 1–4 tip widths (`pin_c`, coarse px) from `at`, the blob's own
/// peak left out. Infinite when fewer than 16 such pixels (a blob at the
/// image's corner beside the housing): there is nothing to compare with,
/// and the global test has already passed it.
fn local_sigmas(
    th: &[f32],
    w: usize,
    h: usize,
    on_fixture: &[bool],
    at: (usize, usize),
    pin_c: f64,
    peak: f32,
) -> f32 {
    let (bx, by) = (at.0 as i64, at.1 as i64);
    let ro = (4.0 * pin_c).ceil() as i64;
    let ri = pin_c.max(1.0);
    let mut near: Vec<f32> = Vec::new();
    for y in (by - ro).max(0)..(by + ro + 1).min(h as i64) {
        for x in (bx - ro).max(0)..(bx + ro + 1).min(w as i64) {
            let i = y as usize * w + x as usize;
            let d = ((x - bx) as f64).hypot((y - by) as f64);
            if on_fixture[i] && d > ri && d <= ro as f64 {
                near.push(th[i]);
            }
        }
    }
    if near.len() < 16 {
        return f32::INFINITY;
    }
    let med = super::measure::percentile(&mut near, 0.5);
    let mut dev: Vec<f32> = near.iter().map(|v| (v - med).abs()).collect();
    let sigma = 1.4826 * super::measure::percentile(&mut dev, 0.5);
    (peak - med) / sigma.max(1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The runs found by search are the per-pixel test, pixel for pixel,
        /// at any rotation (both signs of sine and cosine), scale, offset and
        /// grid, including grids wholly outside the image or covering it.
        #[test]
        fn outside_grid_is_the_per_pixel_test(
            w in 1usize..60, h in 1usize..40, k in 1usize..8,
            theta in -3.2f64..3.2, s in 2.0f64..80.0,
            tx in -200.0f64..400.0, ty in -200.0f64..400.0,
            u0 in -10.0f64..10.0, du in 0.0f64..12.0,
            v0 in -10.0f64..10.0, dv in 0.0f64..12.0,
        ) {
            let sim = Similarity { s, theta, tx, ty };
            let grid = [u0, u0 + du, v0, v0 + dv];
            let kf = k as f64;
            let to_full = |x: f64, y: f64| (x * kf + (kf - 1.0) / 2.0, y * kf + (kf - 1.0) / 2.0);
            let got = outside_grid(w, h, &to_full, &sim, grid);
            for y in 0..h {
                for x in 0..w {
                    let (fx, fy) = to_full(x as f64, y as f64);
                    let (u, v) = sim.inverse(fx, fy);
                    let want = crate::vision::housing::rect_distance(u, v, grid) > 0.0;
                    prop_assert_eq!(got[y * w + x], want, "({}, {})", x, y);
                }
            }
        }
    }

    #[test]
    fn a_nan_similarity_leaves_every_pixel_inside_as_rect_distance_does() {
        let sim = Similarity {
            s: f64::NAN,
            theta: 0.0,
            tx: 0.0,
            ty: 0.0,
        };
        let (u, v) = sim.inverse(3.0, 4.0);
        assert!(!(crate::vision::housing::rect_distance(u, v, [0.0, 1.0, 0.0, 1.0]) > 0.0));
        let k = |x: f64, y: f64| (x, y);
        assert!(
            outside_grid(5, 3, &k, &sim, [0.0, 1.0, 0.0, 1.0])
                .iter()
                .all(|&o| !o)
        );
    }

    #[test]
    fn monotone_run_finds_prefixes_suffixes_and_the_empty_run() {
        assert_eq!(monotone_run(10, &|i| i < 4), (0, 4));
        assert_eq!(monotone_run(10, &|i| i >= 7), (7, 10));
        assert_eq!(monotone_run(10, &|_| true), (0, 10));
        assert_eq!(monotone_run(10, &|_| false), (0, 0));
        assert_eq!(monotone_run(1, &|_| true), (0, 1));
        assert_eq!(monotone_run(0, &|_| true), (0, 0));
        assert_eq!(monotone_run(2, &|i| i == 1), (1, 2));
    }
}
