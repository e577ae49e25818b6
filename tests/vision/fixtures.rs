//! The project's own synthetic fixtures (fixtures/vision, written by
//! `cargo run --release --example gen_images`): every verdict, pin status
//! and extra right; centre RMS ≤ 0.15 px on the σ = 8 DN images and
//! ≤ 0.05 px on the others.

use crate::common;

use pinsight::vision::{self, InspectOptions, PinStatus, Recipe, truth};
use std::path::Path;

#[test]
fn synthetic_fixtures_agree_with_their_truth() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/vision");
    let jsons = common::truth_files(&dir);
    assert!(jsons.len() >= 10);
    let (mut noisy, mut quiet) = (Vec::new(), Vec::new());
    for j in &jsons {
        let t = truth::Truth::from_json(&std::fs::read_to_string(j).unwrap()).unwrap();
        let stem = j.file_stem().unwrap().to_string_lossy().to_string();
        let img = common::image_beside(j);
        let recipe = Recipe::load(&dir.join(&t.recipe)).unwrap();
        let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
            .unwrap_or_else(|e| panic!("{stem}: {e}"));
        explains_itself(&stem, &ins);
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

/// The number standing before `marker` in `s` (e.g. "1.32" in
/// "= 1.32 × position_mm").
fn number_before(s: &str, marker: &str) -> f64 {
    let head = &s[..s
        .find(marker)
        .unwrap_or_else(|| panic!("no `{marker}` in `{s}`"))];
    let tok = head.split_whitespace().last().unwrap();
    tok.parse().unwrap_or_else(|_| panic!("`{tok}` in `{s}`"))
}

/// Every failing pin and counted extra is named in `failed_because` with
/// its numbers against the limit, and those numbers are the measurements
/// (a passing connector has no such line).
fn explains_itself(stem: &str, ins: &vision::Inspection) {
    let bad: Vec<_> = ins
        .pins
        .iter()
        .filter(|p| p.status != PinStatus::Ok)
        .collect();
    assert_eq!(
        ins.failed_because.len(),
        bad.len() + ins.extras.len(),
        "{stem}: {:#?}",
        ins.failed_because
    );
    let tol = &ins.tolerance;
    for p in bad {
        let head = format!("pin row {} col {} {}: ", p.row, p.col, p.status.as_str());
        let line = ins
            .failed_because
            .iter()
            .find(|l| l.starts_with(&head))
            .unwrap_or_else(|| panic!("{stem}: no `{head}` in {:#?}", ins.failed_because));
        match p.status {
            PinStatus::Bent => {
                let k = number_before(line, "× position_mm");
                let want = p.offset_mm.unwrap() / tol.position_mm;
                assert!(k > 1.0 && (k - want).abs() < 0.006, "{stem}: {line}");
            }
            PinStatus::Damaged => {
                let a = number_before(line, "× nominal");
                let [lo, hi] = tol.tip_area.unwrap();
                assert!(a < lo || a > hi, "{stem}: {line}");
                assert!((a - p.area_ratio.unwrap()).abs() < 0.006, "{stem}: {line}");
            }
            PinStatus::Short | PinStatus::High => {
                let k = number_before(line, "× height_tol_mm");
                let h = p.height_mm.unwrap();
                let want = (h - tol.height_mm.unwrap()).abs() / tol.height_tol_mm.unwrap();
                assert!(k > 1.0 && (k - want).abs() < 0.006, "{stem}: {line}");
            }
            PinStatus::Missing => assert!(line.contains("no "), "{stem}: {line}"),
            PinStatus::Ok => unreachable!(),
        }
    }
    for e in &ins.extras {
        let head = format!("extra at ({:.1}, {:.1}) px: ", e.x_px, e.y_px);
        let line = ins
            .failed_because
            .iter()
            .find(|l| l.starts_with(&head))
            .unwrap_or_else(|| panic!("{stem}: no `{head}` in {:#?}", ins.failed_because));
        if ins.view == vision::View::Top {
            // Area, level against the local tip level, SNR, distance.
            let a = number_before(line, "of a tip");
            assert!((a - e.area_ratio).abs() < 0.006, "{stem}: {line}");
            assert!(line.contains("σ above the local noise"), "{stem}: {line}");
            assert!(line.contains("local tip level"), "{stem}: {line}");
        } else {
            assert!(
                line.contains("mm high") || line.contains("of the silhouette"),
                "{stem}: {line}"
            );
        }
    }
}
