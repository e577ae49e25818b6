//! Tests of the scale estimate ([`super`]): lattices, fallbacks and
//! the periodicity's rescue of faint tips.

use super::*;

fn recipe(rows: u32, cols: u32, skip: &str) -> Recipe {
    Recipe::from_toml_str(
        &format!(
            "part_number = \"T\"\nview = \"top\"\nrows = {rows}\ncols = {cols}\npitch_mm = [2.0, 2.0]\npin_mm = 0.5\npin_shape = \"round\"\npolarity = \"bright\"\n{skip}\n[tolerance]\nposition_mm = 0.1\n"
        ),
        "t",
    )
    .unwrap()
}

#[test]
fn most_matched_counts_positions_with_a_neighbour_further_on() {
    assert_eq!(most_matched(&recipe(3, 2, "")), 5);
    assert_eq!(most_matched(&recipe(1, 4, "")), 3);
    assert_eq!(most_matched(&recipe(2, 10, "")), 19);
    // (0,1) skipped: (0,0) still has (1,0) below, (1,0) has (1,1)
    // beside it, (1,1) has nothing further on.
    assert_eq!(most_matched(&recipe(2, 2, "skip = [[0, 1]]")), 2);
}

fn cand(w: f64, pts: Vec<(f64, f64)>) -> Candidate {
    Candidate {
        score: pts.len() as i64,
        support: pts.len(),
        spacings: Vec::new(),
        widths: Vec::new(),
        w,
        peak: 1.0,
        boxes: vec![[0.0; 4]; pts.len()],
        pts,
    }
}

#[test]
fn blobs_inside_larger_tips_are_counted() {
    let large = cand(40.0, vec![(100.0, 100.0), (250.0, 100.0)]);
    // Two fragments inside the first tip (within 0.6 × 40 = 24 px),
    // one inside the second, one between the tips.
    let small = cand(
        8.0,
        vec![(110.0, 95.0), (90.0, 112.0), (262.0, 100.0), (175.0, 100.0)],
    );
    assert!((share_inside(&small, &large) - 0.75).abs() < 1e-12);
    assert_eq!(share_inside(&cand(8.0, vec![]), &large), 0.0);
}

/// Evenly spaced bumps along the frame's top edge (a top-hat ridge cut
/// by noise) at the pitch the recipe implies for 6 px tips: no tips.
#[test]
fn bumps_along_the_frames_edge_are_no_lattice() {
    let (w, h) = (200usize, 80usize);
    let mut data = vec![10f32; w * h];
    for i in 0..7 {
        let x0 = 10 + 24 * i;
        for y in 0..4 {
            for x in x0..x0 + 6 {
                data[y * w + x] = 100.0;
            }
        }
    }
    let mut coarse = Coarse {
        w,
        h,
        k: 1,
        data,
        quantum: 0.0,
    };
    let r = recipe(1, 6, "");
    assert_eq!(score_candidate(&r, &coarse, 6.0, 1.0).score, 0);
    // The same bumps inside the frame are a lattice.
    coarse.data.rotate_right(20 * w);
    assert_eq!(score_candidate(&r, &coarse, 6.0, 1.0).score, 6);
}

#[test]
fn equal_scores_go_to_the_stronger_blobs() {
    // Every other tip at twice the width (the ladder's first) against
    // the tips at their own width: one spacing each.
    let mut wide = cand(17.0, vec![(44.0, 784.0)]);
    wide.peak = 0.35;
    let mut own = cand(6.9, vec![(100.0, 785.0)]);
    own.peak = 0.80;
    assert_eq!(best_candidate(&[wide, own]), Some(1));
    let (mut a, b) = (cand(17.0, vec![(1.0, 1.0)]), cand(6.9, vec![(1.0, 1.0)]));
    a.peak = b.peak;
    assert_eq!(best_candidate(&[a, b]), Some(0));
}

fn estimate_on(r: &Recipe, mm_per_px: f64, missing: &[u32]) -> Result<ScaleEstimate, VisionError> {
    use super::super::gray::GrayData;
    use super::super::synth::Scene;
    let mut scene = Scene::nominal(r, mm_per_px);
    scene.blur_px = 0.8;
    for p in scene.pins.iter_mut() {
        if missing.contains(&p.col) {
            p.present = false;
        }
    }
    let (g, _) = scene.render();
    let (w, h) = (g.width as usize, g.height as usize);
    let fs = g.full_scale();
    match &g.data {
        GrayData::U8(d) => estimate(
            &Plane {
                w,
                h,
                data: d.as_slice(),
            },
            1.0,
            r,
            fs,
        ),
        GrayData::U16(d) => estimate(
            &Plane {
                w,
                h,
                data: d.as_slice(),
            },
            1.0,
            r,
            fs,
        ),
    }
}

/// A 1 × 5 part with pins 1 and 3 missing: the tips left lie two
/// pitches apart, a lattice of the recipe's ratio at twice the tip
/// width. Measured at full resolution they are a quarter of that
/// width's area, so the scale is read from spacings of two pitches,
/// the tips' own width deciding.
#[test]
fn every_other_tip_is_not_the_lattice() {
    let r = recipe(1, 5, "");
    // 0.5 mm tips at 0.04 mm/px: 12.5 px, pitch 50 px.
    let e = estimate_on(&r, 0.04, &[1, 3]).expect("a scale");
    assert!((e.pin_px / 12.5 - 1.0).abs() < 0.05, "{e:?}");
    // Every pin present: the lattice itself, as before.
    let e = estimate_on(&r, 0.04, &[]).expect("a scale");
    assert!((e.pin_px / 12.5 - 1.0).abs() < 0.05, "{e:?}");
    // 1 × 3 without its middle pin: one spacing of two pitches.
    let e = estimate_on(&recipe(1, 3, ""), 0.04, &[1]).expect("a scale");
    assert!((e.pin_px / 12.5 - 1.0).abs() < 0.05, "{e:?}");
}

/// An 8-bit synthetic scene of the recipe at `mm_per_px`, with (contrast,
/// noise σ in DN, blur σ in px) `look`, its noise seed and a rotation:
/// the samples, width, height and full scale.
pub(in crate::vision) fn faint_scene(
    r: &Recipe,
    mm_per_px: f64,
    look: (f64, f64, f64),
    seed: u64,
    rotation_deg: f64,
) -> (Vec<u8>, usize, usize, f32) {
    use super::super::gray::GrayData;
    use super::super::synth::Scene;
    let mut scene = Scene::nominal(r, mm_per_px);
    (scene.contrast, scene.noise_dn, scene.blur_px) = look;
    scene.seed = seed;
    scene.rotation_deg = rotation_deg;
    let (g, _) = scene.render();
    let fs = g.full_scale();
    let GrayData::U8(d) = g.data else {
        panic!("8-bit scene");
    };
    (d, g.width as usize, g.height as usize, fs)
}

/// The scale estimate on a faint scene: `contrast`, `noise_dn`, blur
/// `blur_px`, with the coarse search's smoothing `smoothing` only.
fn estimate_faint(
    r: &Recipe,
    mm_per_px: f64,
    contrast: f64,
    noise_dn: f64,
    blur_px: f64,
    seed: u64,
    smoothing: Option<Smoothing>,
) -> Result<ScaleEstimate, VisionError> {
    let (d, w, h, fs) = faint_scene(r, mm_per_px, (contrast, noise_dn, blur_px), seed, 2.0);
    let plane = Plane {
        w,
        h,
        data: d.as_slice(),
    };
    match smoothing {
        Some(sm) => estimate_smoothed(&plane, 1.0, r, fs, sm, 1.0, None).map(|(e, _)| e),
        None => estimate(&plane, 1.0, r, fs),
    }
}

/// Small faint tips under heavy noise (7 px tips, blur 2 px, σ 15 DN)
/// over a ladder of contrasts: where the coarse search's usual
/// half-tip box finds no lattice (the tips' top-hat peaks stand below
/// the noise floor's 6 σ), the second pass with the wider box finds the
/// scene's scale (0.5 mm tips at 0.07 mm/px: 7.14 px) at least once,
/// and never a wrong one; where the first pass finds a lattice, the
/// estimate is the first pass's, or the period's where the first pass's
/// was a lattice of several pitches on too few pairs (and then right).
#[test]
fn small_faint_tips_are_found_by_the_second_pass() {
    let r = recipe(2, 8, "");
    let truth = 0.5 / 0.07;
    let (n, b) = (15.0, 2.0);
    let mut rescued = 0;
    for c in [0.12, 0.16, 0.2, 0.25, 0.3, 0.35] {
        for seed in 1..=2 {
            let first = estimate_faint(&r, 0.07, c, n, b, seed, Some(Smoothing::Normal));
            let full = estimate_faint(&r, 0.07, c, n, b, seed, None);
            match (&first, &full) {
                // The first pass's estimate stands, unless it was a
                // lattice of several pitches on a pair or two, which
                // gives way to the period; then the period is right
                // (contrast 0.3, seed 1: 9.62 px held by one pair, the
                // period 7.137 px).
                (Ok(a), Ok(e)) if a != e => {
                    assert!(
                        e.from_period && (e.pin_px / truth - 1.0).abs() < 0.05,
                        "contrast {c} seed {seed}: {a:?} became {e:?}"
                    );
                }
                (Ok(_), Ok(_)) => {}
                (Err(_), Ok(e)) => {
                    assert!(
                        (e.pin_px / truth - 1.0).abs() < 0.05,
                        "contrast {c} seed {seed}: {e:?}"
                    );
                    rescued += 1;
                }
                (_, Err(_)) => {}
            }
            eprintln!("contrast {c} seed {seed}: first {first:?}, full {full:?}");
        }
    }
    assert!(
        rescued >= 1,
        "no scene where only the second pass found the tips"
    );
}

/// Rows of small faint tips (0.3 mm at 0.044 mm/px: 6.8 px, blur
/// 2.4 px, σ 14 DN, tilted 2.8°) at contrasts 0.12–0.22: the blob
/// passes find no lattice whose tips hold on most of them (no lattice
/// at all, or one unchecked pair), and the estimate is then the
/// pins' periodicity's: within 1 % of the scene's pitch wherever one is
/// given, and one is given on most of those scenes. Every blob pass
/// fails on those, so they were errors before the periodicity.
#[test]
fn tips_too_faint_for_the_blob_passes_give_the_scale_by_their_period() {
    let truth = 1.0 / 0.044;
    let (mut unheld, mut rescued) = (0, 0);
    for (rows, cols) in [(1u32, 14u32), (2, 18)] {
        let r = Recipe::from_toml_str(
            &format!(
                "part_number = \"T\"\nview = \"top\"\nrows = {rows}\ncols = {cols}\npitch_mm = [1.0, 1.0]\npin_mm = 0.3\npin_shape = \"round\"\npolarity = \"bright\"\n[tolerance]\nposition_mm = 0.13\n"
            ),
            "t",
        )
        .unwrap();
        for c in [0.12, 0.15, 0.18, 0.22] {
            for seed in 1..=2 {
                let (d, w, h, fs) = faint_scene(&r, 0.044, (c, 14.0, 2.4), seed, -2.8);
                let plane = Plane {
                    w,
                    h,
                    data: d.as_slice(),
                };
                let held = |sm| {
                    matches!(
                        estimate_smoothed(&plane, 1.0, &r, fs, sm, 1.0, None),
                        Ok((_, Held::Pitch))
                    )
                };
                if held(Smoothing::Normal) || held(Smoothing::Faint) {
                    continue;
                }
                unheld += 1;
                // Every blob pass fails here: the estimate was an error.
                assert!(
                    estimate_smoothed(&plane, 1.0, &r, fs, Smoothing::Normal, NARROW_SEARCH, None)
                        .is_err()
                );
                if let Ok(e) = estimate(&plane, 1.0, &r, fs) {
                    assert!(
                        (e.pitch_px / truth - 1.0).abs() < 0.01,
                        "{rows} x {cols}, contrast {c}, seed {seed}: pitch {:.2} px, truth {truth:.2}",
                        e.pitch_px
                    );
                    rescued += 1;
                }
            }
        }
    }
    // Measured: 14 scenes unheld, 13 of them given the scale.
    assert!(unheld >= 12, "the blob passes held on all but {unheld}");
    assert!(rescued + 2 >= unheld, "{rescued} of {unheld} given a scale");
}

/// The tips' areas veto a changed scale only when clearly nearer the
/// estimate's (`areas_allow`'s doc): the two cases it lets through
/// (areas measured on Rust seeds 965 725 and 955 473, scale factors their
/// tips' lattices proposed), the one it stops (925 232) and the blurred
/// tips of Python seed 730 124, 12 % off.
#[test]
fn tip_areas_veto_a_scale_only_clearly_against_them() {
    assert!(areas_allow(&[1.23, 1.21, 1.19, 1.19], 31.4 / 26.7));
    assert!(areas_allow(&[0.70, 0.68, 0.68], 49.2 / 60.7));
    assert!(areas_allow(&[1.32, 1.16, 1.07, 1.01], 72.44 / 64.46));
    assert!(!areas_allow(&[1.50, 1.48, 1.46], 23.9 / 28.0));
    // Areas that agree with the estimate keep it against a change of a
    // fifth; none say nothing.
    assert!(!areas_allow(&[1.0, 1.02, 0.97], 1.2));
    assert!(!areas_allow(&[1.0, 1.02, 0.97], 1.0 / 1.2));
    assert!(!areas_allow(&[], 1.05));
}
