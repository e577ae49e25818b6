//! Where the recipe's window sits on the tips' lattice when the tips found
//! do not say.
//!
//! With the tips of an end column (or row) all missed, every placement of
//! the window that covers the tips found scores the same, and the housing
//! outline's centre broke the tie. Small faint tips under heavy noise are
//! missed at the part's ends most (vignetting, a dim corner), and there the
//! coarse housing outline is also least certain: a window one pitch off
//! puts real tips outside the recipe and empty places inside it, each then
//! read missing. The tips that were missed still stand above the noise on
//! the coarse top-hat at their lattice nodes, the empty places beyond the
//! part's end do not: each tied placement is scored by that evidence.

use super::detect::CoarseSearch;
use super::gray::Coarse;
use super::grid::{self, Lattice, Placement};

/// How far (σ of the difference) the tips' evidence for another placement
/// must exceed the housing's pick before it overrules it.
const EVIDENCE_SIGMAS: f64 = 3.0;

/// The least evidence gain that overrules the pick, in tips, however clean
/// the image: structure (a housing edge) is not noise.
const MIN_GAIN: f64 = 0.3;

/// How far around a node its evidence is averaged, in tip widths either
/// side: the top-hat at one point holds one sample of noise, the tip's core
/// a whole patch of it. Rust 955 104 (6.5 px tips at σ 11.5 DN, blur
/// 2.5 px): the missed end tip's single-point evidence beat the empty place
/// beyond the part's other end by 0.525 against a margin of 0.526, and the
/// window stood a pitch off.
const NODE_REACH_TIP: f64 = 0.25;

/// The coarse top-hat averaged over a (2r + 1)² patch of coarse pixels
/// around a full-resolution point; `None` outside the image.
fn patch_mean(th: &Coarse, p: (f64, f64), r: i64) -> Option<f64> {
    let (cx, cy) = th.from_full(p.0, p.1);
    let (xmax, ymax) = ((th.w - 1) as f64, (th.h - 1) as f64);
    if cx < 0.0 || cy < 0.0 || cx > xmax || cy > ymax {
        return None;
    }
    let mut sum = 0.0;
    for dy in -r..=r {
        for dx in -r..=r {
            sum += th.bilinear(cx + dx as f64, cy + dy as f64) as f64;
        }
    }
    Some(sum / ((2 * r + 1) * (2 * r + 1)) as f64)
}

/// Tip evidence of one lattice node: the coarse top-hat around it (a patch
/// of `r` coarse pixels either side) over what that patch holds on a tip,
/// clamped to [0, 1] (a bright housing edge counts no more than a tip).
fn node_evidence(th: &Coarse, lat: &Lattice, tip_unit: f64, r: i64, a: i64, b: i64) -> f64 {
    let p = lat.to_image(a as f64, b as f64);
    patch_mean(th, p, r).map_or(0.0, |v| (v / tip_unit).clamp(0.0, 1.0))
}

/// The placement among those tied with `picked` (same count of members
/// covered) whose window holds clearly more tip evidence than `picked`'s;
/// `None` when `picked` is best or the difference is within the noise.
/// `(rows, cols)` is the recipe's window; `pin_px` the tip's width, which
/// sets the patch the evidence is averaged over.
pub(crate) fn settle_by_evidence(
    cs: &CoarseSearch,
    lat: &Lattice,
    members: &[(i64, i64)],
    (rows, cols): (u32, u32),
    skipped: &dyn Fn(u32, u32) -> bool,
    picked: &Placement,
    pin_px: f64,
) -> Option<Placement> {
    let (_, ties) = grid::best_placements(members, rows, cols, skipped)?;
    if ties.len() < 2 || !(cs.tip_contrast > 0.0) {
        return None;
    }
    let th = Coarse {
        w: cs.coarse.w,
        h: cs.coarse.h,
        k: cs.coarse.k,
        data: cs.tophat.clone(),
        quantum: cs.coarse.quantum,
    };
    let (k, c) = (th.k as f64, (th.k as f64 - 1.0) / 2.0);
    // The noise of the evidence averaged over patches of `r` (robust
    // spread over a sample of patches, mostly background) and a tip's
    // evidence under it: the tips' typical contrast, or what the same
    // patch holds on the members (their median) where that is less (a
    // patch over a round or blurred tip holds less than its peak).
    let noise_and_unit = |r: i64| -> Option<(f64, f64)> {
        let mut sample: Vec<f64> = (0..th.h)
            .step_by(5)
            .flat_map(|y| (0..th.w).step_by(5).map(move |x| (x, y)))
            .filter_map(|(x, y)| patch_mean(&th, (x as f64 * k + c, y as f64 * k + c), r))
            .collect();
        let med = grid::median(&mut sample)?;
        let mut dev: Vec<f64> = sample.iter().map(|v| (v - med).abs()).collect();
        let mut at_members: Vec<f64> = members
            .iter()
            .filter_map(|&(a, b)| patch_mean(&th, lat.to_image(a as f64, b as f64), r))
            .collect();
        let unit = grid::median(&mut at_members)
            .filter(|&u| u > 0.0)
            .map_or(cs.tip_contrast as f64, |u| u.min(cs.tip_contrast as f64));
        Some((1.4826 * grid::median(&mut dev)? / unit, unit))
    };
    // Averaged only where the noise, not the floor, sets the margin: a
    // patch holds less of a small (damaged) tip than its peak does.
    let (sigma0, unit0) = noise_and_unit(0)?;
    let patch_r = (NODE_REACH_TIP * pin_px / k).round().max(0.0) as i64;
    let (r, sigma, tip_unit) =
        if patch_r > 0 && EVIDENCE_SIGMAS * sigma0 * std::f64::consts::SQRT_2 > MIN_GAIN {
            let (s, u) = noise_and_unit(patch_r)?;
            (patch_r, s, u)
        } else {
            (0, sigma0, unit0)
        };
    let nodes = |row0: i64, col0: i64| -> Vec<(i64, i64)> {
        let mut v = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if !skipped(r, c) {
                    v.push((c as i64 + col0, r as i64 + row0));
                }
            }
        }
        v
    };
    let evidence = |n: &[(i64, i64)]| -> f64 {
        n.iter()
            .map(|&(a, b)| node_evidence(&th, lat, tip_unit, r, a, b))
            .sum()
    };
    let mine = nodes(picked.row0, picked.col0);
    let mut best: Option<(f64, (i64, i64))> = None;
    for &(row0, col0) in &ties {
        if (row0, col0) == (picked.row0, picked.col0) {
            continue;
        }
        let theirs = nodes(row0, col0);
        let only_theirs: Vec<(i64, i64)> = theirs
            .iter()
            .filter(|n| !mine.contains(n))
            .copied()
            .collect();
        let only_mine: Vec<(i64, i64)> = mine
            .iter()
            .filter(|n| !theirs.contains(n))
            .copied()
            .collect();
        let gain = evidence(&only_theirs) - evidence(&only_mine);
        let n_diff = (only_theirs.len() + only_mine.len()) as f64;
        let margin = (EVIDENCE_SIGMAS * sigma * n_diff.sqrt()).max(MIN_GAIN);
        if gain > margin && best.is_none_or(|b| gain > b.0) {
            best = Some((gain, (row0, col0)));
        }
    }
    best.map(|(_, (row0, col0))| Placement {
        row0,
        col0,
        score: picked.score,
        ambiguous: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::synth::Rng;

    /// A coarse top-hat (k = 1, 400 × 60) of a 1 × 8 row of tips 40 px
    /// apart from x = 40: peaks of `levels[i]` at node i (Gaussian, σ 2 px)
    /// on noise of σ 0.1 (tip units; the coarse search's 6 σ floor is then
    /// 0.6 of a tip); nodes past the row's far end hold nothing.
    fn search(levels: &[f32], seed: u64) -> (CoarseSearch, Lattice) {
        search_noisy(levels, seed, 0.0, 0.1)
    }

    /// The same with the top-hat's noise of σ `noise` about a floor `base`.
    fn search_noisy(levels: &[f32], seed: u64, base: f32, noise: f64) -> (CoarseSearch, Lattice) {
        let (w, h) = (400usize, 60usize);
        let lat = Lattice {
            theta: 0.0,
            px: 40.0,
            py: 40.0,
            origin: (40.0, 30.0),
        };
        let mut rng = Rng::new(seed);
        let mut th = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut v = base + (noise * rng.normal()) as f32;
                for (i, &l) in levels.iter().enumerate() {
                    let (nx, ny) = lat.to_image(i as f64, 0.0);
                    let d2 = (x as f64 - nx).powi(2) + (y as f64 - ny).powi(2);
                    v += l * (-d2 / 8.0).exp() as f32;
                }
                th[y * w + x] = v.max(0.0);
            }
        }
        let cs = CoarseSearch {
            coarse: Coarse {
                w,
                h,
                k: 1,
                data: vec![0.0; w * h],
                quantum: 0.0,
            },
            tophat: th,
            background: vec![0.0; w * h],
            tip_contrast: 1.0,
            threshold: 0.35,
            noise_floor: 0.0,
            blobs: Vec::new(),
        };
        (cs, lat)
    }

    /// Members at nodes 1–7 of a 1 × 8 window, and the placements one
    /// pitch off (nodes 1–8) and right (0–7).
    fn seven_members() -> (Vec<(i64, i64)>, Placement, Placement) {
        let off = Placement {
            col0: 1,
            row0: 0,
            score: 7,
            ambiguous: true,
        };
        (
            (1..8).map(|a| (a, 0)).collect(),
            off,
            Placement { col0: 0, ..off },
        )
    }

    /// The end tip (node 0) is faint, below the coarse search's noise
    /// floor (0.5–0.55 of a tip against 6 σ = 0.6), so it is
    /// no member: the window at nodes 0–7 and the one at 1–8 cover the
    /// seven members alike. Node 8 is empty (past the part's end): the
    /// evidence moves a pick one pitch off back onto the part, and leaves
    /// a right pick alone; with no evidence either way (node 0 empty too)
    /// the pick stands.
    #[test]
    fn a_missed_end_tip_places_the_window_by_its_contrast() {
        let none = |_: u32, _: u32| false;
        let (members, off, right) = seven_members();
        for seed in 1..=5 {
            for faint in [0.5f32, 0.55] {
                let mut levels = vec![1.0f32; 8];
                levels[0] = faint;
                let (cs, lat) = search(&levels, seed);
                let p = settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &off, 6.0);
                assert_eq!(p.map(|p| p.col0), Some(0), "faint {faint} seed {seed}");
                let p = settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &right, 6.0);
                assert_eq!(p, None, "faint {faint} seed {seed}");
            }
            let mut levels = vec![1.0f32; 8];
            levels[0] = 0.0;
            let (cs, lat) = search(&levels, seed);
            assert_eq!(
                settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &off, 6.0),
                None
            );
            assert_eq!(
                settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &right, 6.0),
                None
            );
        }
    }

    /// Under noise (σ 0.3 of a tip per pixel) one point per node cannot
    /// tell a tip (0.8 of the others, missed) from an empty place: the
    /// margin is 3 σ √2 = 1.3 tips. The mean over a patch of a quarter tip
    /// either side (8 px tips: 5 × 5 px) can, and still leaves a right pick
    /// alone and an undecided one undecided (Rust 955 104).
    #[test]
    fn under_noise_the_evidence_is_averaged_over_the_tips_core() {
        let none = |_: u32, _: u32| false;
        let (members, off, right) = seven_members();
        for seed in 1..=5 {
            let mut levels = vec![1.0f32; 8];
            levels[0] = 0.8;
            let (cs, lat) = search_noisy(&levels, seed, 0.5, 0.3);
            let p = settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &off, 8.0);
            assert_eq!(p.map(|p| p.col0), Some(0), "seed {seed}");
            let p = settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &right, 8.0);
            assert_eq!(p, None, "seed {seed}");
            levels[0] = 0.0;
            let (cs, lat) = search_noisy(&levels, seed, 0.5, 0.3);
            let p = settle_by_evidence(&cs, &lat, &members, (1, 8), &none, &off, 8.0);
            assert_eq!(p, None, "seed {seed}: no evidence either way");
        }
    }
}
