//! `find_housing` on drawn scenes whose edges are known exactly.

use super::*;
use crate::rng::SplitMix64;

/// A one-row part of five positions, the first pin missing (its empty
/// hole darker than the housing), on a brighter fixture: the housing
/// spans lattice a ∈ [−2.6, 2.6], b ∈ [−0.6, 0.6] (22 px pitch), with a
/// chamfer band `band` lattice units wide inside each edge, 20 below the
/// housing. Pixel noise of σ `sigma`. Sampled at one coarse pixel per
/// full pixel (k = 1).
fn scene(seed: u64, sigma: f64, band: f64) -> (Coarse, Lattice) {
    let lat = Lattice {
        theta: 0.03,
        px: 22.0,
        py: 22.0,
        origin: (160.0, 90.0),
    };
    let (w, h) = (320usize, 180usize);
    let mut rng = SplitMix64::<7>::new(seed);
    let mut data = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let (a, b) = lat.to_lattice((x as f64, y as f64));
            let inside = a.abs() <= 2.6 && b.abs() <= 0.6;
            let in_band = inside && (a.abs() > 2.6 - band || b.abs() > 0.6 - band);
            let tip = (-1..=2).any(|i| (a - i as f64).hypot(b) * 22.0 < 4.0);
            let hole = (a + 2.0).hypot(b) * 22.0 < 5.0;
            let level = if !inside {
                100.0
            } else if tip {
                140.0
            } else if hole {
                30.0
            } else if in_band {
                40.0
            } else {
                60.0
            };
            data[y * w + x] = (level + sigma * rng.normal()) as f32;
        }
    }
    let coarse = Coarse {
        w,
        h,
        k: 1,
        data,
        quantum: 0.0,
    };
    (coarse, lat)
}

/// The edges found on `n` noise draws: the largest error (lattice units)
/// of each side.
fn worst_errors(n: u64, sigma: f64, band: f64) -> [f64; 4] {
    let truth = [-2.6, 2.6, -0.6, 0.6];
    let mut worst = [0f64; 4];
    for seed in 0..n {
        let (coarse, lat) = scene(seed, sigma, band);
        let found = find_housing(&coarse, &lat, (-1, 2), (0, 0), 8.0, 12.0)
            .expect("a 40-level step is found");
        for i in 0..4 {
            worst[i] = worst[i].max((found[i] - truth[i]).abs());
        }
    }
    worst
}

#[test]
fn edges_found_under_heavy_noise_with_an_end_pin_missing() {
    // σ 15 against a 40-level step, as Rust 941 473 and 961 450 (where
    // single-line profiles read the fixture's noise beyond the edge as its
    // outermost step, and the grid stood a pitch off). A tenth of a pitch
    // is 2.2 px; the pitch's half, which would shift the grid, is 11.
    let worst = worst_errors(20, 15.0, 0.0);
    for (side, e) in worst.iter().enumerate() {
        assert!(*e < 0.1, "side {side}: worst error {e:.3} pitch");
    }
}

#[test]
fn the_outer_edge_not_the_chamfer_band() {
    // A band 0.15 pitch wide inside every edge, darker than the housing:
    // two steps, fixture → band and band → housing; the outer one is the
    // housing's edge.
    let worst = worst_errors(10, 3.0, 0.15);
    for (side, e) in worst.iter().enumerate() {
        assert!(*e < 0.1, "side {side}: worst error {e:.3} pitch");
    }
}

#[test]
fn no_edge_without_a_step() {
    // A fixture and housing of one level: nothing to find.
    let (coarse, lat) = scene(1, 2.0, 0.0);
    let coarse = coarse.with_data(vec![60.0; coarse.data.len()]);
    assert!(find_housing(&coarse, &lat, (-1, 2), (0, 0), 8.0, 12.0).is_none());
}
