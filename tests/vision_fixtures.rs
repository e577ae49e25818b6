//! The project's own synthetic fixtures (fixtures/vision, written by
//! `cargo run --release --example gen_images`): every verdict, pin status
//! and extra right; centre RMS ≤ 0.15 px on the σ = 8 DN images and
//! ≤ 0.05 px on the others.

use pinsight::vision::{self, InspectOptions, PinStatus, Recipe, truth};
use std::path::{Path, PathBuf};

#[test]
fn synthetic_fixtures_agree_with_their_truth() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/vision");
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    assert!(jsons.len() >= 10);
    let (mut noisy, mut quiet) = (Vec::new(), Vec::new());
    for j in &jsons {
        let t = truth::Truth::from_json(&std::fs::read_to_string(j).unwrap()).unwrap();
        let stem = j.file_stem().unwrap().to_string_lossy().to_string();
        let img = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                p.file_stem().is_some_and(|s| s.to_string_lossy() == stem)
                    && p.extension().is_some_and(|x| x != "json")
            })
            .unwrap();
        let recipe = Recipe::load(&dir.join(&t.recipe)).unwrap();
        let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
            .unwrap_or_else(|e| panic!("{stem}: {e}"));
        let c = truth::compare(&ins, &t, 15.0);
        assert!(
            c.verdict_ok && c.status_mismatches.is_empty(),
            "{stem}: {:?}",
            c.status_mismatches
        );
        assert_eq!(
            (c.extras_found, c.extras_spurious),
            (c.extras_truth, 0),
            "{stem}: extras"
        );
        let target = if t.noise_sigma().unwrap_or(0.0) >= 8.0 {
            &mut noisy
        } else {
            &mut quiet
        };
        for e in c.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
            target.push(e.3 * e.3 + e.4 * e.4);
        }
    }
    let rms = |v: &[f64]| (v.iter().sum::<f64>() / v.len() as f64).sqrt();
    let (rn, rq) = (rms(&noisy), rms(&quiet));
    println!(
        "fixtures/vision: ok-pin centre RMS σ=8 DN {rn:.4} px ({} pins), σ ≤ 4 DN {rq:.4} px ({} pins)",
        noisy.len(),
        quiet.len()
    );
    assert!(rn <= 0.15, "{rn}");
    assert!(rq <= 0.05, "{rq}");
}
