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

/// Tip evidence of one lattice node: the coarse top-hat there over the
/// tips' typical contrast, clamped to [0, 1] (a bright housing edge counts
/// no more than a tip).
fn node_evidence(th: &Coarse, lat: &Lattice, tip_contrast: f32, a: i64, b: i64) -> f64 {
    let p = lat.to_image(a as f64, b as f64);
    let (cx, cy) = th.from_full(p.0, p.1);
    if cx < 0.0 || cy < 0.0 || cx > (th.w - 1) as f64 || cy > (th.h - 1) as f64 {
        return 0.0;
    }
    (th.bilinear(cx, cy) / tip_contrast.max(1e-6)).clamp(0.0, 1.0) as f64
}

/// The placement among those tied with `picked` (same count of members
/// covered) whose window holds clearly more tip evidence than `picked`'s;
/// `None` when `picked` is best or the difference is within the noise.
pub(crate) fn settle_by_evidence(
    cs: &CoarseSearch,
    lat: &Lattice,
    members: &[(i64, i64)],
    rows: u32,
    cols: u32,
    skipped: &dyn Fn(u32, u32) -> bool,
    picked: &Placement,
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
    // The top-hat's noise (robust spread, mostly background), in tip units.
    let mut sample: Vec<f64> = cs.tophat.iter().step_by(7).map(|&v| v as f64).collect();
    let med = grid::median(&mut sample)?;
    let mut dev: Vec<f64> = sample.iter().map(|v| (v - med).abs()).collect();
    let sigma = 1.4826 * grid::median(&mut dev)? / cs.tip_contrast as f64;
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
            .map(|&(a, b)| node_evidence(&th, lat, cs.tip_contrast, a, b))
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
        let margin = (EVIDENCE_SIGMAS * sigma * n_diff.sqrt()).max(0.3);
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
                let mut v = (0.1 * rng.normal()) as f32;
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
        let members: Vec<(i64, i64)> = (1..8).map(|a| (a, 0)).collect();
        let off = Placement {
            col0: 1,
            row0: 0,
            score: 7,
            ambiguous: true,
        };
        let right = Placement { col0: 0, ..off };
        for seed in 1..=5 {
            for faint in [0.5f32, 0.55] {
                let mut levels = vec![1.0f32; 8];
                levels[0] = faint;
                let (cs, lat) = search(&levels, seed);
                let p = settle_by_evidence(&cs, &lat, &members, 1, 8, &none, &off);
                assert_eq!(p.map(|p| p.col0), Some(0), "faint {faint} seed {seed}");
                let p = settle_by_evidence(&cs, &lat, &members, 1, 8, &none, &right);
                assert_eq!(p, None, "faint {faint} seed {seed}");
            }
            let mut levels = vec![1.0f32; 8];
            levels[0] = 0.0;
            let (cs, lat) = search(&levels, seed);
            assert_eq!(
                settle_by_evidence(&cs, &lat, &members, 1, 8, &none, &off),
                None
            );
            assert_eq!(
                settle_by_evidence(&cs, &lat, &members, 1, 8, &none, &right),
                None
            );
        }
    }
}
