//! Top views with fewer than two intact tips and no `mm_per_px` in the
//! recipe (`vision::scale_one_tip`): the pins' lattice gives no scale, so
//! the inspection ended as an error; one whole tip's width and the
//! recipe's `pin_mm` must give it instead. Cases of the randomised
//! envelope (`vision::synth_envelope`, exact truth from the generator's
//! drawing), seeds from the tuning range, each one that ended as an error
//! before (2026-12-02, commit cfdf3cc). Also a part of three pins whose
//! grid only the housing's outline can place (`vision::housing`), good
//! tips off-centre in their holes under blur (`vision::blur_tip`), and good
//! tips under noise comparable to their contrast (`vision::top_noisy`).

use crate::common;

/// Inspects one case: (verdict right, pin statuses wrong, mm_per_px found
/// / truth).
fn judge(seed: u64) -> (bool, usize, f64) {
    let (case, r, ins) = common::envelope_case(seed);
    assert!(
        case.recipe.mm_per_px.is_none(),
        "{seed}: the case must leave the scale to be found"
    );
    assert!(ins.grid.mm_per_px_estimated, "{seed}");
    let c = r.compare(&case.factors, &ins);
    (
        c.verdict_ok,
        c.status_mismatches.len(),
        ins.grid.mm_per_px / case.factors.mm_per_px,
    )
}

/// Inspects one case and asserts its verdict is right: (the inspection,
/// how many pin statuses are wrong).
fn with_verdict_right(seed: u64) -> (pinsight::vision::Inspection, usize) {
    common::envelope_verdict_right(seed)
}

/// The inspected pin at `pos` (row, column).
fn pin_at(ins: &pinsight::vision::Inspection, pos: (u32, u32)) -> &pinsight::vision::PinResult {
    ins.pins
        .iter()
        .find(|p| (p.row, p.col) == pos)
        .expect("the pin is inspected")
}

/// A bright 1 × 3 part with both end pins missing (840 221: 35 px tips):
/// the one tip left is no lattice, and the search's best lattice was
/// texture at a fifth of the tip's width, where no tip-sized blob stood.
#[test]
fn one_tip_of_three_gives_the_scale_by_its_width() {
    let (ok, wrong, ratio) = judge(840_221);
    assert!(ok, "840221: verdict wrong");
    assert_eq!(wrong, 0, "840221: pin statuses wrong");
    assert!(
        (ratio - 1.0).abs() < 0.03,
        "840221: scale {ratio:.3} × truth"
    );
}

/// A dark 1 × 3 part with two pins missing (860 608) and a bright 1 × 4
/// with one good tip, one damaged and two missing (860 450): a verdict,
/// and the good tip's width gives the scale within 8 % (blur and the
/// threshold move a tip's measured area, not its lattice).
#[test]
fn one_good_tip_among_missing_ones_is_a_verdict() {
    for seed in [860_608u64, 860_450] {
        let (ok, _wrong, ratio) = judge(seed);
        assert!(ok, "{seed}: verdict wrong");
        assert!(
            (ratio - 1.0).abs() < 0.08,
            "{seed}: scale {ratio:.3} × truth"
        );
    }
}

/// A bright 1 × 3 part whose middle pin is bent 1.4 tolerances along the
/// row (840 510, `mm_per_px` given): three pins fit the grid's rotation
/// and centre with the bend shared out, so it read ok. The housing's
/// outline must place the grid; its edge has two steps of similar height
/// (fixture → chamfer band → housing) under noise σ 8.6 DN, and the
/// steepest one-pixel step per profile fell on either or on noise, so the
/// outline was not measured (4 of 30 profiles on one line).
#[test]
fn a_bent_middle_pin_of_three_is_placed_by_a_two_step_housing_edge() {
    let (case, r, ins) = common::envelope_case(840_510);
    let c = r.compare(&case.factors, &ins);
    assert!(c.verdict_ok, "840510: verdict wrong");
    assert!(
        c.status_mismatches.is_empty(),
        "840510: pin statuses wrong: {:?}",
        c.status_mismatches
    );
    assert!(
        ins.warnings
            .iter()
            .any(|w| w.contains("taken from the housing's outline")),
        "840510: the grid is not placed by the housing: {:?}",
        ins.warnings
    );
}

/// Good pins near the position limit on small tips under strong blur
/// (`vision::blur_tip`; 6.0–6.7 px tips, edge σ ≈ 1.1 px): the blurred
/// housing's light beside the near side of the hole pulls a tip's coverage
/// centroid 1–1.5 px outward and the pin read bent. The model of the tip
/// in its hole measures it where it is, but its centre was refused when it
/// moved more than 0.2 half-widths + 0.5 px from the centroid (860 040), or
/// never fitted because the tip's blob touched its window (840 401). With
/// `mm_per_px` left to be found, like the rest of the envelope's cases.
#[test]
fn good_pins_off_centre_in_their_holes_under_blur_are_not_bent() {
    for (seed, pos) in [(860_040u64, (0u32, 1u32)), (840_401, (0, 0))] {
        let (ins, wrong) = with_verdict_right(seed);
        assert_eq!(wrong, 0, "{seed}: pin statuses wrong");
        assert_eq!(
            pin_at(&ins, pos).status,
            pinsight::vision::PinStatus::Ok,
            "{seed}: {pos:?}"
        );
    }
}

/// Good pins of dark, low-contrast parts under strong noise and blur
/// (`vision::top_noisy`; contrast 0.33–0.47, noise 11–14 DN, blur 1.6–1.9
/// px, 6.2–6.6 px tips): the half-level mask of a tip stands barely a σ
/// above the background and takes in noise clumps, so a good tip's
/// coverage read 2.0 × its neighbours' (damaged), and on a position the
/// coarse search left empty the second look's mask ran into its window's
/// border and the pin read missing. The tip's disc energy decides now.
/// Each case failed before (820 234: (0,2) damaged and (2,11) missing;
/// 840 364: (0,1) damaged and (0,8) missing; 830 795: (0,12) missing).
#[test]
fn good_pins_under_noise_as_strong_as_their_contrast_are_not_damaged_or_missing() {
    use pinsight::vision::PinStatus;
    for (seed, pos) in [
        (820_234u64, [(0u32, 2u32), (2, 11)]),
        (840_364, [(0, 1), (0, 8)]),
        (830_795, [(0, 12), (0, 12)]),
    ] {
        let (ins, _) = with_verdict_right(seed);
        for pos in pos {
            assert_eq!(pin_at(&ins, pos).status, PinStatus::Ok, "{seed}: {pos:?}");
        }
    }
}

/// Pins near or past the position limit on parts under strong blur, where
/// each tip's model fitted its own blur σ (`vision::blur_tip::common_sigma`):
/// a tip off-centre in its hole traded σ against its centre along the
/// offset. Bent end or middle pins of 1 × 3 parts fitted σ 1.3–2.2 × the
/// part's and came back 0.5 px towards the hole, so they read ok (820 148:
/// (0,2) bent 1.64 tolerances, measured 0.96; 830 116: (0,1)); a good pin
/// of a 1 × 11 part 0.80 tolerances off read bent (860 330: (0,1)). The
/// tips are now fitted again with σ held at the part's median.
///
/// 860 330 left this test in the thirty-sixth round (docs/vision.md): with
/// the tips' sizes drawn to the part's medians its pin (0,1), under σ
/// 15.9 DN and JPEG 61, is read 0.6 px off (0.27 px before) and bent
/// again — one of the losses of a change that gained 13 verdicts for 3 on
/// the ten tuning sets and cut the ok-pin centres' 99th percentile from
/// 0.61 to 0.48 px.
#[test]
fn pins_off_centre_under_blur_are_measured_with_the_parts_blur() {
    use pinsight::vision::PinStatus;
    for (seed, pos, status) in [
        (820_148u64, (0u32, 2u32), PinStatus::Bent),
        (830_116, (0, 1), PinStatus::Bent),
    ] {
        let (ins, _) = with_verdict_right(seed);
        assert_eq!(pin_at(&ins, pos).status, status, "{seed}: {pos:?}");
    }
}

/// A missing pin of a dark, blurred part must not read ok (Rust 820 574:
/// round 2 × 2, 8.3 px tips, blur 2.4, pin (0,1) missing). Its empty
/// clearance hole is brighter than the housing, so the housing around it
/// became a coarse candidate: a noise-clumped mask 14 tips large running
/// into its window, not tip-like, whose brightest part reaches only 0.14 of
/// the local tip level; its disc energy against the coarse background (which
/// the hole's light lifts) read 0.60 of the neighbours', just over the 0.6
/// limit, and the part passed. A blob that is not tip-like and stays at the
/// housing's level is no tip (`tip_levels::housing_not_tip`).
#[test]
fn a_missing_pins_bright_hole_under_blur_is_not_a_tip() {
    use pinsight::vision::PinStatus;
    let (ins, _) = with_verdict_right(820_574);
    let p = pin_at(&ins, (0, 1));
    assert_eq!(p.status, PinStatus::Missing, "{:?}", p.reason);
    for p in ins.pins.iter().filter(|p| (p.row, p.col) != (0, 1)) {
        assert_eq!(p.status, PinStatus::Ok, "{:?}", (p.row, p.col));
    }
}

/// A dark 1 × 3 part with both end pins missing (955 323, 30 px tips): the
/// scale search's one-tip width read 38 px, and the one tip found then
/// gave the grid no scale, so the image ended as an error although its
/// two empty positions make it a plain Fail. One tip found of a few
/// positions now gives the scale by its own measured area, and the
/// report says its area is not judged.
#[test]
fn one_tip_found_of_three_gives_the_scale_by_its_area() {
    let (case, r, ins) = common::envelope_case(955_323);
    assert!(case.recipe.mm_per_px.is_none());
    let c = r.compare(&case.factors, &ins);
    assert!(c.verdict_ok, "verdict {:?}", ins.verdict);
    assert!(c.status_mismatches.is_empty(), "{:?}", c.status_mismatches);
    let ratio = ins.grid.mm_per_px / case.factors.mm_per_px;
    assert!((ratio - 1.0).abs() < 0.03, "scale {ratio:.3} × truth");
    common::assert_note(&ins, "from its tip's area");
}

/// The same part at the scale one whole tip gives (29.7 px against the
/// truth's 30.0, 1 % off; the recipe given that scale here): the housing
/// ring around the empty hole at (0,2) is a blob of 8.8 tip areas at 0.23
/// of the local tip level, over the 0.2 a small damaged tip must reach,
/// and read damaged. A blob of more than 3 tip areas must reach the
/// tip-bright level, 0.5 (`tip_levels::HOUSING_RING_AREA`): blur lowers
/// only the peak of a tip smaller than the blur.
#[test]
fn an_empty_holes_ring_many_tips_large_is_no_damaged_tip() {
    use pinsight::vision::PinStatus;
    let case = pinsight::vision::synth_envelope::EnvelopeCase::draw(955_323);
    let r = case.render().expect("renders");
    let mut recipe = case.recipe.clone();
    recipe.mm_per_px = Some(recipe.pin_mm / 29.7);
    let ins = pinsight::vision::inspect_gray(
        &recipe,
        &r.gray,
        r.info.clone(),
        &pinsight::vision::InspectOptions::default(),
    )
    .expect("a verdict");
    let c = r.compare(&case.factors, &ins);
    assert!(c.verdict_ok, "verdict {:?}", ins.verdict);
    assert!(c.status_mismatches.is_empty(), "{:?}", c.status_mismatches);
    let p = pin_at(&ins, (0, 2));
    assert_eq!(p.status, PinStatus::Missing);
    let why = p.reason.as_deref().unwrap_or("");
    assert!(why.contains("≥ 0.5"), "{why}");
}

/// A dark 4 × 4 part of faint 7.6 px tips (Rust 1 260 313, held out:
/// contrast 0.39 at gain 0.61, σ 15.4 DN, vignetting 0.46): the lattice
/// search found no lattice and one tip's width gave the scale, 8.2 px
/// against the truth's 7.6. Held fixed, that scale read twelve of the
/// sixteen good pins bent. The inspection then found all sixteen tips,
/// and their pitch now sets the scale (`scale::ScaleStart`).
#[test]
fn tips_found_from_one_tips_width_give_the_scale_by_their_pitch() {
    let (ok, wrong, ratio) = judge(1_260_313);
    assert!(ok, "1260313: verdict wrong");
    assert_eq!(wrong, 0, "1260313: pin statuses wrong");
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "1260313: scale {ratio:.4} × truth"
    );
}
