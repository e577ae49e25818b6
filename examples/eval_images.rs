//! Evaluates the vision pipeline on a folder of images with ground truth
//! (default: fixtures/interop/images): verdicts, per-pin statuses, centre
//! RMS error, area ratios, extras, time per image.
//!
//! cargo run --release --example eval_images -- [DIR] [centroid|weighted|coverage] [-v]

use pinsight::vision::{self, InspectOptions, Localiser, PinStatus, Recipe, truth};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = args
        .iter()
        .find(|a| !a.starts_with('-') && Path::new(a).is_dir())
        .cloned()
        .unwrap_or_else(|| "fixtures/interop/images".into());
    let loc = if args.iter().any(|a| a == "centroid") {
        Localiser::Centroid
    } else if args.iter().any(|a| a == "weighted") {
        Localiser::Weighted
    } else {
        Localiser::Coverage
    };
    let verbose = args.iter().any(|a| a == "-v");
    let opts = InspectOptions { localiser: loc };
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    let (mut all_ok, mut all_n, mut v_ok) = (0.0, 0usize, 0usize);
    let mut sq_ok = Vec::new();
    for j in &jsons {
        let t = truth::Truth::from_json(&std::fs::read_to_string(j).unwrap()).unwrap();
        let recipe = Recipe::load(&Path::new(&dir).join(&t.recipe)).unwrap();
        let stem = j.file_stem().unwrap().to_string_lossy().to_string();
        let img = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|p| {
                // The truth (.json) and a recipe named after the image
                // (.toml, as the Python renderer writes) share its stem.
                p.file_stem().is_some_and(|s| s.to_string_lossy() == stem)
                    && p.extension().is_some_and(|x| x != "json" && x != "toml")
            })
            .unwrap();
        let t0 = Instant::now();
        let r = vision::inspect_path(&recipe, &img, &opts);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        match r {
            Err(e) => println!("{stem:12} ERROR {e}"),
            Ok(ins) => {
                let c = truth::compare(&ins, &t, 15.0);
                let rms_ok = c.rms(|s| s == PinStatus::Ok).unwrap_or(f64::NAN);
                let rms_all = c.rms(|_| true).unwrap_or(f64::NAN);
                for e in c.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
                    sq_ok.push(e.3 * e.3 + e.4 * e.4);
                }
                all_ok += 0.0;
                all_n += 1;
                if c.verdict_ok {
                    v_ok += 1;
                }
                let worst_h = c.height_errors.iter().map(|e| e.abs()).fold(0.0, f64::max);
                let worst_area = c
                    .area_ratios
                    .iter()
                    .map(|(t, f)| (f - t).abs())
                    .fold(0.0, f64::max);
                println!(
                    "{stem:12} {:5} {} rms_ok {:.3} rms_all {:.3} mism {:?} extras {}/{} spur {} area_err_max {:.3} h_err_max {:.4} scale {:.5} {:.1} ms {}",
                    format!("{:?}", ins.verdict),
                    if c.verdict_ok { "OK " } else { "BAD" },
                    rms_ok,
                    rms_all,
                    c.status_mismatches,
                    c.extras_found,
                    c.extras_truth,
                    c.extras_spurious,
                    worst_area,
                    worst_h,
                    ins.grid.mm_per_px,
                    ms,
                    if verbose {
                        format!("{:?}", ins.warnings)
                    } else {
                        String::new()
                    }
                );
                if verbose {
                    for (t, f) in &c.area_ratios {
                        if (f - t).abs() > 0.05 {
                            print!(" area {t:.3}->{f:.3}");
                        }
                    }
                    for e in &c.centre_errors {
                        if e.3.hypot(e.4) > 0.1 || args.iter().any(|a| a == "-e") {
                            print!(" [{},{} {:?} {:.2},{:.2}]", e.0, e.1, e.2, e.3, e.4);
                        }
                    }
                    for e in &ins.extras {
                        print!(" extra({:.0},{:.0} a{:.2})", e.x_px, e.y_px, e.area_ratio);
                    }
                    for e in &ins.ignored {
                        print!(
                            " ign({:.0},{:.0} {})",
                            e.x_px,
                            e.y_px,
                            e.ignored_because.clone().unwrap_or_default()
                        );
                    }
                    println!();
                }
            }
        }
    }
    let _ = all_ok;
    println!(
        "verdicts {v_ok}/{all_n}; ok-pin centre RMS {:.4} px over {} pins ({:?})",
        (sq_ok.iter().sum::<f64>() / sq_ok.len().max(1) as f64).sqrt(),
        sq_ok.len(),
        loc
    );
}
// (errors listing helper used with -e)
