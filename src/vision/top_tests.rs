//! Unit tests of `vision::top` (beside it, so the module reads on its own).

use super::super::synth::{Rng, Scene};
use super::super::{InspectOptions, PinStatus, Recipe, inspect_gray, truth};

fn recipe(rows: u32, cols: u32, scale_known: bool) -> Recipe {
    let mm = if scale_known {
        "mm_per_px = 0.03\n"
    } else {
        ""
    };
    Recipe::from_toml_str(
        &format!(
            "part_number = \"F\"\nview = \"top\"\nrows = {rows}\ncols = {cols}\npitch_mm = [2.54, 2.54]\npin_mm = 0.64\npin_shape = \"square\"\npolarity = \"bright\"\n{mm}[tolerance]\nposition_mm = 0.12\n"
        ),
        "t",
    )
    .unwrap()
}

/// The scene rendered and inspected, with its truth.
fn inspect_scene(sc: &Scene) -> (super::super::Inspection, truth::Truth) {
    let (g, t) = sc.render();
    let ins = inspect_gray(
        &sc.recipe,
        &g,
        Default::default(),
        &InspectOptions::default(),
    )
    .unwrap();
    (ins, t)
}

/// Statuses found and true, row-major.
fn statuses(sc: &Scene) -> (Vec<PinStatus>, Vec<PinStatus>) {
    let (ins, t) = inspect_scene(sc);
    let c = truth::compare(&ins, &t, 15.0);
    assert!(c.extras_spurious == 0, "{:?}", ins.extras);
    (
        ins.pins.iter().map(|p| p.status).collect(),
        t.pins.iter().map(|p| p.defect).collect(),
    )
}

/// One pin of two or three bent across the row by 1.6 tolerances: the
/// pins' own fit turns and shifts onto it (two pins: it shows nothing),
/// the housing's outline does not move, so the bent pin is found and
/// the others stay ok; a good part turned, shifted and blurred stays
/// ok throughout.
#[test]
fn a_bent_pin_of_two_or_three_is_placed_by_the_housing() {
    for (cols, known) in [(2, true), (3, true), (2, false), (3, false)] {
        let r = recipe(1, cols, known);
        for (k, dir) in [(0usize, 1.0), (cols as usize - 1, -1.0)] {
            let mut sc = Scene::nominal(&r, 0.03);
            sc.rotation_deg = 3.0 * dir;
            sc.centre_px.0 += 7.3;
            sc.noise_dn = 3.0;
            sc.pins[k].offset_mm = (0.0, dir * 1.6 * 0.12);
            let (found, truth) = statuses(&sc);
            assert_eq!(truth[k], PinStatus::Bent);
            assert_eq!(found, truth, "1×{cols} scale known {known}, pin {k}");
        }
        for s in 0..6 {
            let mut sc = Scene::nominal(&r, 0.03);
            sc.randomise(&mut Rng::new(40 + s), 5.0, 20.0, 1.5);
            sc.noise_dn = 4.0;
            sc.seed = 90 + s;
            let (found, truth) = statuses(&sc);
            assert!(truth.iter().all(|t| *t == PinStatus::Ok));
            assert_eq!(found, truth, "good 1×{cols} scale known {known}, seed {s}");
        }
    }
}

/// A 2 × 2 part with two opposite pins missing, the scale not given: the
/// two tips left stand a diagonal apart, with no neighbour along a row or
/// a column. They are still the part's lattice (the recipe's pitch-to-tip
/// ratio along the diagonal), so the part is judged, not an error: the two
/// tips ok, the two others missing.
#[test]
fn two_opposite_tips_of_a_two_by_two_part_are_its_lattice() {
    let r = recipe(2, 2, false);
    for (gone, rot) in [([0usize, 3usize], 3.0), ([1, 2], -4.0), ([0, 3], -1.5)] {
        let mut sc = Scene::nominal(&r, 0.03);
        sc.rotation_deg = rot;
        sc.noise_dn = 4.0;
        sc.blur_px = 1.0;
        for k in gone {
            sc.pins[k].present = false;
        }
        let (found, truth) = statuses(&sc);
        assert_eq!(truth[gone[0]], PinStatus::Missing);
        assert_eq!(found, truth, "pins {gone:?} missing, rotation {rot}");
    }
}

/// A damaged tip of 0.45–0.5 × the width (0.2–0.25 × the area), flat
/// where the intact tips are domed, under blur comparable to it: its peak
/// stays under half the intact tips' level, so the coarse search passes it
/// by and the empty position's second look took it for housing structure
/// (the pin read missing). It sits on its position, compact and filled,
/// where a missing pin leaves only its dark clearance hole: damaged. A
/// missing pin of the same part stays missing, the others ok.
#[test]
fn a_small_blurred_damaged_tip_is_damaged_not_missing() {
    use super::super::synth::Damage;
    for (i, (blur, scale)) in [(2.0, 0.45), (2.2, 0.5), (1.9, 0.45)]
        .into_iter()
        .enumerate()
    {
        let r = recipe(1, 6, false);
        let mut sc = Scene::nominal(&r, 0.08);
        sc.blur_px = blur;
        sc.noise_dn = 2.0;
        sc.rotation_deg = 1.5 - i as f64;
        sc.centre_px.0 += 0.37 * i as f64;
        sc.pins[2].damage = Damage::Scaled(scale);
        sc.pins[4].present = false;
        let (ins, t) = inspect_scene(&sc);
        let found: Vec<PinStatus> = ins.pins.iter().map(|p| p.status).collect();
        let truth: Vec<PinStatus> = t.pins.iter().map(|p| p.defect).collect();
        assert_eq!(truth[2], PinStatus::Damaged);
        assert_eq!(truth[4], PinStatus::Missing);
        assert_eq!(found, truth, "blur {blur} scale {scale}: {:?}", ins.pins[2]);
        let why = ins.pins[2].reason.as_deref().unwrap_or_default();
        assert!(
            why.contains("second look"),
            "blur {blur} scale {scale}: {why}"
        );
    }
}
