//! The vision pipeline against the interop set (images rendered by another
//! renderer, with ground truth; fixtures/interop/images) and the rig log
//! with camera images (fixtures/interop/logs/run-2000-images.mcap).
//!
//! Every verdict and every pin status must agree with the truth; pin-centre
//! RMS error ≤ 0.05 px on the clean images and ≤ 0.15 px with Gaussian
//! noise σ = 8 DN added. The measured figures are printed (run with
//! `--nocapture`).

use crate::common;

use pinsight::vision::batch::{self, ItemStatus, RecipeBook};
use pinsight::vision::synth::Rng;
use pinsight::vision::{self, GrayData, InspectOptions, PinStatus, Recipe, truth};
use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/images")
}

struct Case {
    name: String,
    image: PathBuf,
    truth: truth::Truth,
    recipe: Recipe,
}

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for j in common::truth_files(&dir()) {
        let t = truth::Truth::from_json(&std::fs::read_to_string(&j).unwrap()).unwrap();
        let stem = j.file_stem().unwrap().to_string_lossy().to_string();
        let image = common::image_beside(&j);
        let recipe = Recipe::load(&dir().join(&t.recipe)).unwrap();
        v.push(Case {
            name: stem,
            image,
            truth: t,
            recipe,
        });
    }
    assert_eq!(v.len(), 40);
    v
}

fn rms(sq: &[f64]) -> f64 {
    (sq.iter().sum::<f64>() / sq.len() as f64).sqrt()
}

#[test]
fn every_verdict_status_and_extra_agrees_and_centres_are_accurate() {
    let opts = InspectOptions::default();
    let (mut all, mut clean, mut jpeg, mut nf) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut heights = Vec::new();
    let mut worst_area: f64 = 0.0;
    for c in cases() {
        let ins = vision::inspect_path(&c.recipe, &c.image, &opts)
            .unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let cmp = truth::compare(&ins, &c.truth, 15.0);
        assert!(cmp.verdict_ok, "{}: verdict", c.name);
        assert!(
            cmp.status_mismatches.is_empty(),
            "{}: {:?}",
            c.name,
            cmp.status_mismatches
        );
        assert_eq!(
            cmp.extras_found, cmp.extras_truth,
            "{}: extras missed",
            c.name
        );
        assert_eq!(cmp.extras_spurious, 0, "{}: spurious extras", c.name);
        let is_jpeg = c.image.extension().is_some_and(|x| x == "jpg");
        let noise_free = c.truth.noise_sigma().unwrap_or(1.0) < 0.05 && !is_jpeg;
        for e in cmp.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
            let sq = e.3 * e.3 + e.4 * e.4;
            all.push(sq);
            if is_jpeg {
                jpeg.push(sq);
            } else {
                clean.push(sq);
            }
            if noise_free {
                nf.push(sq);
            }
        }
        heights.extend(cmp.height_errors.iter().map(|h| h.abs()));
        for (t, f) in &cmp.area_ratios {
            worst_area = worst_area.max((f - t).abs());
        }
    }
    let (r_all, r_png, r_jpg) = (rms(&all), rms(&clean), rms(&jpeg));
    let r_nf = rms(&nf);
    let h = heights.iter().cloned().fold(0.0, f64::max);
    println!(
        "interop: ok-pin centre RMS all {r_all:.4} px ({} pins), lossless {r_png:.4} px ({}), noise-free lossless {r_nf:.4} px ({}), JPEG {r_jpg:.4} px ({}); max |height error| {h:.4} mm; max |area ratio error| {worst_area:.3}",
        all.len(),
        clean.len(),
        nf.len(),
        jpeg.len()
    );
    assert!(r_nf <= 0.05, "noise-free RMS {r_nf}");
    assert!(r_png <= 0.05, "lossless RMS {r_png}");
    assert!(r_all <= 0.05, "overall RMS {r_all}");
    assert!(h < 0.01);
}

#[test]
fn centres_with_added_noise_sigma_8() {
    // Gaussian noise σ = 8 DN (scaled to the container for 16-bit) on every
    // lossless interop image; the truth is unchanged.
    let opts = InspectOptions::default();
    let mut sq = Vec::new();
    let mut verdicts = (0, 0);
    let mut rng = Rng::new(2024);
    for c in cases()
        .into_iter()
        .filter(|c| c.image.extension().is_some_and(|x| x != "jpg"))
    {
        let (mut g, info) = vision::image_io::load_path(&c.image).unwrap();
        match &mut g.data {
            GrayData::U8(d) => d.iter_mut().for_each(|v| {
                *v = (*v as f64 + 8.0 * rng.normal()).round().clamp(0.0, 255.0) as u8
            }),
            GrayData::U16(d) => {
                // 12-bit data in 16 bits: scale σ to the data's range.
                let max = *d.iter().max().unwrap() as f64;
                let s = if max < 4096.0 { 4095.0 / 255.0 } else { 257.0 };
                d.iter_mut().for_each(|v| {
                    *v = (*v as f64 + 8.0 * s * rng.normal())
                        .round()
                        .clamp(0.0, 65535.0) as u16
                })
            }
        }
        let ins = vision::inspect_gray(&c.recipe, &g, info, &opts)
            .unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let cmp = truth::compare(&ins, &c.truth, 15.0);
        verdicts.1 += 1;
        if cmp.verdict_ok && cmp.status_mismatches.is_empty() {
            verdicts.0 += 1;
        }
        for e in cmp.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
            sq.push(e.3 * e.3 + e.4 * e.4);
        }
    }
    let r = rms(&sq);
    println!(
        "interop + noise σ=8 DN: ok-pin centre RMS {r:.4} px over {} pins; verdicts {}/{}",
        sq.len(),
        verdicts.0,
        verdicts.1
    );
    assert!(r <= 0.15, "RMS {r}");
}

#[test]
fn rig_log_images_match_the_truth_file() {
    let log =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/logs/run-2000-images.mcap");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(log.with_extension("truth.json")).unwrap())
            .unwrap();
    let (items, errors) = batch::collect_items(&[log]);
    assert!(errors.is_empty());
    let book = RecipeBook::new(vec![Recipe::load(&dir().join("hdr-2x10.toml")).unwrap()]);
    let results = batch::run_batch(
        &items,
        &book,
        &InspectOptions::default(),
        &pinsight::progress::Progress::hidden(),
    );
    let want = truth["images"].as_array().unwrap();
    assert_eq!(results.len(), want.len());
    for (r, w) in results.iter().zip(want) {
        assert_eq!(r.meta.cycle, w["cycle_index"].as_u64());
        let expect = if w["verdict"] == "pass" {
            ItemStatus::Pass
        } else {
            ItemStatus::Fail
        };
        assert_eq!(r.status, expect, "{}", r.name);
        assert_eq!(r.meta.motor_rpm, Some(2000.0));
    }
}
