//! The vision pipeline on images from the project's own generator
//! (`pinsight::vision::synth`: anti-aliased, exact sub-pixel truth):
//! accuracy clean and at noise σ = 8 DN, and the cases the interop set does
//! not cover (a whole end column missing, an end pin missing on a one-row
//! part, every damage kind, extras near and far, 16-bit data, the scale
//! estimated from the pitch).

use pinsight::vision::synth::{Damage, Rng, Scene, SceneExtra};
use pinsight::vision::{self, InspectOptions, Inspection, PinStatus, Recipe, Verdict, truth};
use std::path::Path;

fn recipe(name: &str) -> Recipe {
    Recipe::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures/interop/images")
            .join(name),
    )
    .unwrap()
}

fn run(scene: &Scene) -> (Inspection, truth::Truth) {
    let (g, t) = scene.render();
    let ins = vision::inspect_gray(
        &scene.recipe,
        &g,
        Default::default(),
        &InspectOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", scene.recipe.part_number));
    (ins, t)
}

fn assert_matches(ins: &Inspection, t: &truth::Truth, what: &str) -> truth::Comparison {
    let c = truth::compare(ins, t, 15.0);
    assert!(
        c.status_mismatches.is_empty(),
        "{what}: {:?}",
        c.status_mismatches
    );
    assert!(
        c.verdict_ok,
        "{what}: verdict {:?} vs {:?}",
        ins.verdict, t.verdict
    );
    assert_eq!(c.extras_found, c.extras_truth, "{what}: extras");
    assert_eq!(
        c.extras_spurious, 0,
        "{what}: spurious extras {:?}",
        ins.extras
    );
    c
}

/// Centre RMS over ok pins of random scenes (pose, blur 0–1.2 px, small
/// offsets) for the top-view recipes, at a noise level.
fn rms_over_scenes(noise: f64, seeds: u64) -> f64 {
    let (mut sq, mut k) = (0.0, 0usize);
    for name in ["hdr-2x10.toml", "rnd-1x8.toml", "hdr-2x5-dark.toml"] {
        let r = recipe(name);
        for s in 0..seeds {
            let mut sc = Scene::nominal(&r, r.mm_per_px.unwrap());
            sc.randomise(&mut Rng::new(100 + s), 5.0, 25.0, 1.2);
            sc.noise_dn = noise;
            sc.seed = 1000 + s;
            let (ins, t) = run(&sc);
            let c = assert_matches(&ins, &t, &format!("{name} seed {s} noise {noise}"));
            for e in c.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
                sq += e.3 * e.3 + e.4 * e.4;
                k += 1;
            }
        }
    }
    (sq / k as f64).sqrt()
}

#[test]
fn centre_accuracy_clean_and_at_noise_sigma_8() {
    let clean = rms_over_scenes(0.0, 3);
    let noisy = rms_over_scenes(8.0, 3);
    println!(
        "synthetic top view: ok-pin centre RMS clean {clean:.4} px, noise σ=8 DN {noisy:.4} px"
    );
    assert!(clean <= 0.05, "clean RMS {clean}");
    assert!(noisy <= 0.15, "σ=8 RMS {noisy}");
}

#[test]
fn side_view_heights_clean_and_noisy() {
    for noise in [0.0, 8.0] {
        let r = recipe("side-1x10.toml");
        let mut sc = Scene::nominal(&r, 0.03);
        sc.randomise(&mut Rng::new(5), 2.0, 20.0, 1.0);
        sc.noise_dn = noise;
        sc.pins[2].height_mm = 3.25; // high
        sc.pins[6].height_mm = 2.8; // short
        let (ins, t) = run(&sc);
        let c = assert_matches(&ins, &t, "side");
        let worst = c.height_errors.iter().fold(0f64, |a, e| a.max(e.abs()));
        let rms = c.rms(|_| true).unwrap();
        println!("side view noise {noise}: max |height error| {worst:.4} mm, tip RMS {rms:.4} px");
        assert!(worst < 0.01, "{worst}");
        assert!(rms < if noise > 0.0 { 0.15 } else { 0.08 }, "{rms}");
    }
}

#[test]
fn whole_end_column_missing_is_placed_by_the_housing() {
    let r = recipe("hdr-2x10.toml");
    for end in [0u32, 9] {
        let mut sc = Scene::nominal(&r, 0.03);
        sc.randomise(&mut Rng::new(9 + end as u64), 4.0, 20.0, 0.8);
        for p in sc.pins.iter_mut().filter(|p| p.col == end) {
            p.present = false;
        }
        let (ins, t) = run(&sc);
        assert_matches(&ins, &t, &format!("end column {end} missing"));
        assert!(ins.grid.anchored_by_housing);
        assert_eq!(ins.counts.missing, 2);
    }
}

#[test]
fn end_pin_missing_on_one_row_parts() {
    for (name, m) in [("rnd-1x8.toml", 0.025), ("side-1x6.toml", 0.025)] {
        let r = recipe(name);
        for end in [0usize, r.cols as usize - 1] {
            let mut sc = Scene::nominal(&r, m);
            sc.randomise(&mut Rng::new(3 + end as u64), 2.0, 15.0, 0.6);
            sc.pins[end].present = false;
            let (ins, t) = run(&sc);
            assert_matches(&ins, &t, &format!("{name}: end pin {end} missing"));
            assert!(ins.grid.anchored_by_housing, "{name} {end}");
        }
    }
}

#[test]
fn damage_kinds_bent_pins_and_extras() {
    let r = recipe("hdr-2x10.toml");
    let mut sc = Scene::nominal(&r, 0.03);
    sc.randomise(&mut Rng::new(77), 3.0, 20.0, 0.9);
    sc.noise_dn = 3.0;
    sc.pins[1].damage = Damage::Scaled(0.68); // area 0.46: shrunk
    sc.pins[3].damage = Damage::Scaled(1.33); // area 1.77: enlarged
    sc.pins[5].damage = Damage::Chipped(0.45); // area 0.55 (+ octagon corners)
    sc.pins[12].damage = Damage::Burr(0.55);
    sc.pins[7].offset_mm = (0.13, -0.05); // bent 0.139 mm
    sc.pins[15].offset_mm = (0.0, 0.085); // near tolerance, ok
    // Debris on the housing between the rows, and one far away (ignored).
    sc.extras.push(SceneExtra {
        u_mm: 1.27,
        v_mm: 0.0,
        r_mm: 0.25,
        opacity: 1.0,
    });
    sc.extras.push(SceneExtra {
        u_mm: 16.0,
        v_mm: 0.0,
        r_mm: 0.3,
        opacity: 1.0,
    });
    let (g, mut t) = sc.render();
    // The far blob is more than one pitch from the housing: not an extra.
    t.extras.truncate(1);
    t.verdict = Verdict::Fail;
    let ins = vision::inspect_gray(&r, &g, Default::default(), &InspectOptions::default()).unwrap();
    assert_matches(&ins, &t, "damage");
    assert_eq!(ins.counts.damaged, 4);
    assert_eq!(ins.counts.bent, 1);
    assert_eq!(
        ins.ignored
            .iter()
            .filter(|e| e
                .ignored_because
                .as_deref()
                .is_some_and(|s| s.contains("housing")))
            .count(),
        1
    );
}

#[test]
fn sixteen_bit_dark_polarity_and_estimated_scale() {
    let mut r = recipe("hdr-2x8-auto.toml");
    assert!(r.mm_per_px.is_none());
    let mut sc = Scene::nominal(&r, 0.0271);
    sc.randomise(&mut Rng::new(4), 5.0, 20.0, 1.0);
    sc.sixteen_bit = true;
    sc.noise_dn = 2.0;
    sc.pins[4].offset_mm = (0.1, 0.1);
    let (ins, t) = run(&sc);
    assert_matches(&ins, &t, "auto scale 16 bit");
    assert!(ins.grid.mm_per_px_estimated);
    assert!(
        (ins.grid.mm_per_px / 0.0271 - 1.0).abs() < 2e-3,
        "{}",
        ins.grid.mm_per_px
    );

    r.polarity = vision::Polarity::Dark;
    r.mm_per_px = Some(0.025);
    let mut sc = Scene::nominal(&r, 0.025);
    sc.randomise(&mut Rng::new(8), 5.0, 20.0, 1.0);
    sc.sixteen_bit = true;
    sc.pins[2].present = false;
    let (ins, t) = run(&sc);
    assert_matches(&ins, &t, "dark 16 bit");
}
