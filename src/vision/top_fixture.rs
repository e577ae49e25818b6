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
use super::housing::outside_rect;
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

/// Full-resolution places on the fixture worth measuring as debris:
/// coarse residual blobs outside `grid` (the grid's extent grown by 0.4
/// pitch, part frame, mm), tip-sized or smaller, whose peak
/// rises `SEED_SIGMAS` robust σ above the fixture's median top-hat and
/// `SEED_LEVEL` of the tip contrast; on a dark part (`dark`) also
/// `LOCAL_SIGMAS` above its neighbourhood's.
pub(super) fn fixture_seeds(
    cs: &CoarseSearch,
    sim: &Similarity,
    grid: [f64; 4],
    pin_px: f64,
    dark: bool,
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
    // Row by row (an index's `i % w` and `i / w` cost more than the test).
    let to_part = sim.inverse_map();
    let mut on_fixture = Vec::with_capacity(w * h);
    for yc in 0..h {
        on_fixture.extend((0..w).map(|xc| {
            let (x, y) = cs.coarse.to_full(xc as f64, yc as f64);
            let (u, v) = to_part(x, y);
            outside_rect(u, v, grid)
        }));
    }
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
        if dark {
            let z = local_sigmas(&th, w, h, &on_fixture, (best.1, best.2), pin_c, best.0);
            if z < LOCAL_SIGMAS {
                continue;
            }
        }
        out.push((best.0, cs.coarse.to_full(best.1 as f64, best.2 as f64)));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out.truncate(MAX_SEEDS);
    out.into_iter().map(|(_, p)| p).collect()
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
