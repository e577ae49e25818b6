use super::*;
use crate::rng::SplitMix64;

#[test]
fn step_noise_is_the_noise_not_the_edge() {
    // Six segments of a short profile (40 samples), each the same blurred
    // step of 30 levels at sample 20 plus independent N(0, 2) noise: a box
    // difference over w = 6 samples a side has σ = 2 √(2/6) = 1.155, while
    // the edge's flanks fill most of the profile's strengths.
    let (n, w, sigma) = (40usize, 6usize, 2.0);
    let expect = sigma * (2.0 / w as f64).sqrt();
    let mut rng = SplitMix64::<7>::new(11);
    let trials = 40;
    let mut sum = 0.0;
    for _ in 0..trials {
        let segs: Vec<(f64, Vec<f64>)> = (0..6)
            .map(|k| {
                let prof: Vec<f64> = (0..n)
                    .map(|i| {
                        let x = (i as f64 - 20.0) / 2.0;
                        30.0 * 0.5 * (1.0 + x.tanh()) + sigma * rng.normal()
                    })
                    .collect();
                (k as f64, box_steps(&prof, w))
            })
            .collect();
        sum += step_noise(&segs, w);
    }
    let mean = sum / trials as f64;
    assert!(
        (mean / expect - 1.0).abs() < 0.08,
        "step noise {mean:.3} against {expect:.3}"
    );
}

/// An 8-bit image `w` × `h` of a dark housing (`half_mm` half sides) on a
/// bright fixture, turned by `theta` about (`cx`, `cy`) px at `s` px/mm,
/// its edges anti-aliased, with N(0, `sigma`) noise.
fn housing_image(
    (w, h): (usize, usize),
    s: f64,
    (theta, cx, cy): (f64, f64, f64),
    half_mm: (f64, f64),
    sigma: f64,
) -> Vec<u8> {
    let mut rng = SplitMix64::<7>::new(5);
    let (sn, cs) = theta.sin_cos();
    let mut data = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f64 - cx, y as f64 - cy);
            let (u, v) = (cs * dx + sn * dy, -sn * dx + cs * dy);
            let cover_u = (0.5 + half_mm.0 * s - u.abs()).clamp(0.0, 1.0);
            let cover_v = (0.5 + half_mm.1 * s - v.abs()).clamp(0.0, 1.0);
            let level = 200.0 - 120.0 * cover_u * cover_v + sigma * rng.normal();
            data[y * w + x] = level.round().clamp(0.0, 255.0) as u8;
        }
    }
    data
}

/// The housing's true pose against a fit turned 0.04 rad and shifted
/// (1.5, −2) px from it: what `measure_pose` should return.
fn pose_scene(w: usize, h: usize) -> (Vec<u8>, Similarity, (f64, f64), f64) {
    let s = 20.0;
    let (theta, cx, cy) = (0.03, 0.5 * w as f64, 0.5 * h as f64);
    let data = housing_image((w, h), s, (theta, cx, cy), (5.0, 1.5), 3.0);
    let sim = Similarity {
        s,
        theta: theta + 0.04,
        tx: cx + 1.5,
        ty: cy - 2.0,
    };
    (data, sim, sim.inverse(cx, cy), -0.04)
}

#[test]
fn four_sides_give_the_housings_rotation_and_centre() {
    let (w, h) = (300, 140);
    let (data, sim, centre, dtheta) = pose_scene(w, h);
    let plane = Plane { w, h, data: &data };
    // The coarse outline a few tenths of a mm off each true side.
    let rect = [-5.2, 4.9, -1.4, 1.6];
    let pose = measure_pose(&plane, &sim, rect, (4.0, 0.5)).expect("a pose");
    assert!((pose.dtheta - dtheta).abs() < 0.002, "{pose:?}");
    let err = (pose.centre_mm.0 - centre.0).hypot(pose.centre_mm.1 - centre.1);
    assert!(
        err * sim.s < 0.1,
        "centre {:?} against {centre:?}",
        pose.centre_mm
    );
    assert!(!pose.long_sides_only);
}

#[test]
fn the_long_sides_alone_give_the_rotation_where_the_ends_leave_the_image() {
    // 10 mm of housing at 20 px/mm in a 180 px wide crop: both ends'
    // profiles leave the image.
    let (w, h) = (180, 140);
    let (data, sim, centre, dtheta) = pose_scene(w, h);
    let plane = Plane { w, h, data: &data };
    let rect = [-5.2, 4.9, -1.4, 1.6];
    let at = sampler(&plane, &sim);
    let end = Side {
        normal_u: true,
        dir: 1.0,
        edge: rect[1],
        lo: rect[2],
        hi: rect[3],
        half: 4.0,
    };
    assert_eq!(
        measure_side(&at, sim.s, end).err(),
        Some(SideFail::LeavesImage)
    );
    let pose = measure_pose(&plane, &sim, rect, (4.0, 0.5)).expect("a pose from two sides");
    assert!((pose.dtheta - dtheta).abs() < 0.002, "{pose:?}");
    // Across the long sides the housing's centre; along them the fit's.
    assert!(
        (pose.centre_mm.1 - centre.1).abs() * sim.s < 0.1,
        "{pose:?} against {centre:?}"
    );
    assert_eq!(pose.centre_mm.0, 0.0);
    assert!(pose.long_sides_only);
}

#[test]
fn two_sides_that_disagree_give_no_pose() {
    // One long side turned by a housing-dark wedge rising 0.05 mm per mm
    // in the fit's frame (about 0.09 rad from the true side): the long
    // sides disagree on the rotation, and the ends leave the image.
    let (w, h) = (180, 140);
    let (mut data, sim, _, _) = pose_scene(w, h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = sim.inverse(x as f64, y as f64);
            let bottom = 1.5 + 0.05 * (u + 5.0);
            if v > 1.3 && v < bottom {
                data[y * w + x] = 80;
            }
        }
    }
    let plane = Plane { w, h, data: &data };
    let rect = [-5.2, 4.9, -1.4, 1.6];
    let at = sampler(&plane, &sim);
    // Each long side is straight on its own; it is their turns that differ.
    let long = |dir: f64, edge: f64| Side {
        normal_u: false,
        dir,
        edge,
        lo: rect[0],
        hi: rect[1],
        half: 0.5,
    };
    let top = measure_side(&at, sim.s, long(-1.0, rect[2])).expect("the top side");
    let bottom = measure_side(&at, sim.s, long(1.0, rect[3])).expect("the bottom side");
    assert!(bottom.dtheta - top.dtheta > 0.05, "{top:?} {bottom:?}");
    assert_eq!(measure_pose(&plane, &sim, rect, (4.0, 0.5)), None);
}

#[test]
fn a_flat_side_has_no_edge() {
    // A side clipped to full scale: every step strength is 0. Taken as a
    // threshold of 0, the last sample of every segment passed and made a
    // perfectly straight side (Rust 920 909).
    let (w, h) = (180, 140);
    let data = vec![255u8; w * h];
    let plane = Plane { w, h, data: &data };
    let sim = Similarity {
        s: 20.0,
        theta: 0.0,
        tx: 90.0,
        ty: 70.0,
    };
    let at = sampler(&plane, &sim);
    let side = Side {
        normal_u: false,
        dir: 1.0,
        edge: 1.5,
        lo: -3.0,
        hi: 3.0,
        half: 0.5,
    };
    assert_eq!(measure_side(&at, sim.s, side).err(), Some(SideFail::NoStep));
}
