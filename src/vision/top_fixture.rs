//! Top view: where to look for debris on a bright part's fixture (the
//! background outside the housing) that the candidate search never
//! offers.
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

use super::detect::CoarseSearch;
use super::fit::Similarity;
use super::housing::rect_distance;
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
/// The lowest peak measured, as a fraction of the typical tip contrast.
const SEED_LEVEL: f32 = 0.1;
/// How many places are measured at most (the highest peaks first).
const MAX_SEEDS: usize = 40;

/// Full-resolution places on the fixture worth measuring as debris:
/// coarse residual blobs outside `grid` (the grid's extent grown by 0.4
/// pitch, part frame, mm), tip-sized or smaller, whose peak
/// rises `SEED_SIGMAS` robust σ above the fixture's median top-hat and
/// `SEED_LEVEL` of the tip contrast.
pub(super) fn fixture_seeds(
    cs: &CoarseSearch,
    sim: &Similarity,
    grid: [f64; 4],
    pin_px: f64,
) -> Vec<(f64, f64)> {
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
    let on_fixture: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = cs.coarse.to_full((i % w) as f64, (i / w) as f64);
            let (u, v) = sim.inverse(x, y);
            rect_distance(u, v, grid) > 0.0
        })
        .collect();
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
    let mut out: Vec<(f32, (f64, f64))> = Vec::new();
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
        out.push((best.0, cs.coarse.to_full(best.1 as f64, best.2 as f64)));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out.truncate(MAX_SEEDS);
    out.into_iter().map(|(_, p)| p).collect()
}
