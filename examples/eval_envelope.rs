//! Accuracy over the whole imaging envelope: draws N random cases from
//! `pinsight::vision::synth_envelope`, inspects them in parallel and prints
//! the overall figures and, per factor, where the wrong verdicts sit.
//!
//!   cargo run --release --example eval_envelope -- [N] [FIRST_SEED] [--save DIR] [--list] [--view side|top]
//!
//! `--view side` (or `top`) judges only the cases drawn with that view,
//! skipping the others before they are rendered: the side views are a
//! minority of the draws, and a change to their pipeline is measured on
//! them alone.
//!
//! `--save DIR` writes each wrongly judged image, and each with an ok pin's
//! centre more than a pixel off (PNG, 16-bit where the case was), its truth
//! and its recipe for a closer look; `--list` prints one line per wrong case
//! and one per image with centres off, by their share of the squared error; `--bound` adds, for the top views' ok pins, the
//! Cramér–Rao lower bound on the centre error (what any unbiased
//! measurement could reach in that image) beside the measured error.
use pinsight::vision::synth_envelope::{EnvelopeCase, Factors, Rendered};
use pinsight::vision::{self, InspectOptions, Verdict};
use rayon::prelude::*;
use std::time::Instant;

struct Outcome {
    f: Factors,
    error: Option<String>,
    verdict_ok: bool,
    pins: usize,
    pin_wrong: usize,
    ok_sq: Vec<f64>,
    /// Top view, truly ok pins: (centre error px, Cramér–Rao bound px).
    top_ok: Vec<(f64, f64)>,
    /// Side view: measured − true height of each pin measured, px.
    h_err_px: Vec<f64>,
    detail: String,
    secs_inspect: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let first: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    let save = args
        .iter()
        .position(|a| a == "--save")
        .and_then(|i| args.get(i + 1))
        .map(std::path::PathBuf::from);
    let list = args.iter().any(|a| a == "--list");
    let bound = args.iter().any(|a| a == "--bound");
    let view: Option<String> = args
        .iter()
        .position(|a| a == "--view")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.to_lowercase());
    if let Some(seed) = args
        .iter()
        .position(|a| a == "--show")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse::<u64>().ok())
    {
        show(seed);
        return;
    }
    if let Some(d) = &save {
        std::fs::create_dir_all(d).expect("create --save dir");
    }
    let t0 = Instant::now();
    let outcomes: Vec<Outcome> = (first..first + n)
        .into_par_iter()
        .filter_map(|seed| {
            let case = EnvelopeCase::draw(seed);
            if let Some(v) = &view
                && format!("{:?}", case.factors.view).to_lowercase() != *v
            {
                return None;
            }
            let r = case.render().expect("render");
            let t = Instant::now();
            let res =
                vision::inspect_gray(&case.recipe, &r.gray, r.info.clone(), &InspectOptions::default());
            let secs_inspect = t.elapsed().as_secs_f64();
            let mut o = Outcome {
                f: case.factors.clone(),
                error: None,
                verdict_ok: false,
                pins: r.truth.pins.len(),
                pin_wrong: 0,
                ok_sq: Vec::new(),
                top_ok: Vec::new(),
                h_err_px: Vec::new(),
                detail: String::new(),
                secs_inspect,
            };
            match res {
                Err(e) => {
                    o.error = Some(e.to_string());
                    o.pin_wrong = o.pins;
                    o.detail = format!("ERROR {e}");
                }
                Ok(ins) => {
                    let c = r.compare(&case.factors, &ins);
                    o.verdict_ok = c.verdict_ok;
                    o.pin_wrong = c.status_mismatches.len();
                    o.ok_sq = Rendered::ok_centre_errors(&c).iter().map(|e| e * e).collect();
                    o.h_err_px = c.height_errors.iter().map(|e| e / case.factors.mm_per_px).collect();
                    if bound {
                        let b = case.centre_bounds();
                        o.top_ok = c
                            .centre_errors
                            .iter()
                            .filter(|e| e.2 == pinsight::vision::PinStatus::Ok)
                            .filter_map(|e| {
                                let (_, _, bp) = b.iter().find(|q| q.0 == e.0 && q.1 == e.1)?;
                                Some((e.3.hypot(e.4), *bp))
                            })
                            .collect();
                    }
                    if !c.verdict_ok || o.pin_wrong > 0 {
                        o.detail = format!(
                            "verdict {:?} (truth {:?}), pins {:?}, extras found {}/{} spurious {}{}",
                            ins.verdict,
                            r.truth.verdict,
                            c.status_mismatches,
                            c.extras_found,
                            c.extras_truth,
                            c.extras_spurious,
                            ins.extras
                                .iter()
                                .map(|e| format!(" [extra ({:.0},{:.0}) a {:.2}]", e.x_px, e.y_px, e.area_ratio))
                                .collect::<String>()
                        );
                    }
                }
            }
            // Saved too: a right verdict with an ok pin more than a pixel off.
            let wrong = o.error.is_some() || !o.verdict_ok || o.ok_sq.iter().any(|&e| e > 1.0);
            if wrong && let Some(d) = &save {
                let stem = d.join(format!("env-{seed:05}"));
                let _ = r.gray.to_display_u8().save(stem.with_extension("png"));
                let _ = std::fs::write(
                    stem.with_extension("json"),
                    serde_json::to_string_pretty(&r.truth).unwrap_or_default(),
                );
                let _ = std::fs::write(
                    stem.with_extension("toml"),
                    toml::to_string(&case.recipe).unwrap_or_default(),
                );
            }
            Some(o)
        })
        .collect();
    let wall = t0.elapsed().as_secs_f64();
    report(&outcomes, wall, list);
}

fn pct(a: usize, b: usize) -> String {
    if b == 0 {
        "-".into()
    } else {
        format!("{:.2} %", 100.0 * a as f64 / b as f64)
    }
}

fn report(o: &[Outcome], wall: f64, list: bool) {
    let n = o.len();
    let right = o.iter().filter(|x| x.verdict_ok).count();
    let errors = o.iter().filter(|x| x.error.is_some()).count();
    let pins: usize = o.iter().map(|x| x.pins).sum();
    let pins_wrong: usize = o.iter().map(|x| x.pin_wrong).sum();
    let sq: Vec<f64> = o.iter().flat_map(|x| x.ok_sq.iter().cloned()).collect();
    let rms = (sq.iter().sum::<f64>() / sq.len().max(1) as f64).sqrt();
    let mut sorted = sq.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let p99 = sorted
        .get(((sorted.len() as f64) * 0.99) as usize)
        .map(|v| v.sqrt())
        .unwrap_or(0.0);
    let median = sorted
        .get(sorted.len() / 2)
        .map(|v| v.sqrt())
        .unwrap_or(0.0);
    let good = o.iter().filter(|x| x.f.defects.is_empty()).count();
    let mpx: f64 = o
        .iter()
        .map(|x| x.f.width as f64 * x.f.height as f64 / 1e6)
        .sum();
    let t_insp: f64 = o.iter().map(|x| x.secs_inspect).sum();
    println!(
        "{n} images ({good} good parts, {:.0} Mpx in all) in {wall:.1} s wall (inspection {:.1} ms/image mean on one core)",
        mpx,
        1e3 * t_insp / n as f64
    );
    println!(
        "connector verdicts right {right}/{n} = {}; errors {errors}; pin statuses right {}/{pins} = {}; ok-pin centre RMS {rms:.4} px over {} pins (median {median:.3} px, 99th percentile {p99:.3} px)",
        pct(right, n),
        pins - pins_wrong,
        pct(pins - pins_wrong, pins),
        sq.len()
    );
    let mut h: Vec<f64> = o.iter().flat_map(|x| x.h_err_px.iter().cloned()).collect();
    if !h.is_empty() {
        let mean = h.iter().sum::<f64>() / h.len() as f64;
        let rms = (h.iter().map(|e| e * e).sum::<f64>() / h.len() as f64).sqrt();
        h.sort_by(|a, b| a.total_cmp(b));
        println!(
            "side-view pin heights: error mean {mean:+.3} px, RMS {rms:.3} px, median {:+.3} px over {} pins",
            h[h.len() / 2],
            h.len()
        );
    }
    let bounded: Vec<(f64, f64)> = o.iter().flat_map(|x| x.top_ok.iter().cloned()).collect();
    if !bounded.is_empty() {
        let rms = |v: &[f64]| (v.iter().map(|e| e * e).sum::<f64>() / v.len().max(1) as f64).sqrt();
        let errs: Vec<f64> = bounded.iter().map(|p| p.0).collect();
        let bounds: Vec<f64> = bounded.iter().map(|p| p.1).collect();
        let fine: Vec<(f64, f64)> = bounded.iter().cloned().filter(|p| p.0 <= 1.0).collect();
        let below = bounds.iter().filter(|b| **b <= 0.1).count();
        println!(
            "top view, ok pins ({}): centre RMS {:.4} px; Cramér–Rao lower bound on that RMS {:.4} px (any unbiased measurement); within 1 px ({:.2} %): RMS {:.4} px against a bound of {:.4} px; pins whose bound allows 0.10 px RMS: {:.1} %",
            bounded.len(),
            rms(&errs),
            rms(&bounds),
            100.0 * fine.len() as f64 / bounded.len() as f64,
            rms(&fine.iter().map(|p| p.0).collect::<Vec<_>>()),
            rms(&fine.iter().map(|p| p.1).collect::<Vec<_>>()),
            100.0 * below as f64 / bounds.len() as f64,
        );
    }
    // Numeric factors: four equal-width bins over the observed range.
    println!(
        "\nper factor: bin, images, verdicts right, errors, pin statuses right, ok-pin RMS px{}",
        if bounded.is_empty() {
            ""
        } else {
            "; top view ok pins within 1 px: RMS px, bound px"
        }
    );
    let names: Vec<&str> = o[0].f.numeric().iter().map(|p| p.0).collect();
    for (k, name) in names.iter().enumerate() {
        let vals: Vec<f64> = o.iter().map(|x| x.f.numeric()[k].1).collect();
        let (lo, hi) = vals
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| {
                (a.0.min(v), a.1.max(v))
            });
        let nb = 4;
        for b in 0..nb {
            let a0 = lo + (hi - lo) * b as f64 / nb as f64;
            let a1 = lo + (hi - lo) * (b + 1) as f64 / nb as f64;
            let sel: Vec<&Outcome> = o
                .iter()
                .zip(&vals)
                .filter(|(_, v)| **v >= a0 && (**v < a1 || (b == nb - 1 && **v <= a1)))
                .map(|p| p.0)
                .collect();
            line(&format!("{name} {a0:.3}–{a1:.3}"), &sel);
        }
    }
    let cats: Vec<&str> = o[0].f.categories().iter().map(|p| p.0).collect();
    for (k, name) in cats.iter().enumerate() {
        let mut keys: Vec<String> = o.iter().map(|x| x.f.categories()[k].1.clone()).collect();
        keys.sort();
        keys.dedup();
        if name == &"defects" {
            // Too many combinations: by kind present.
            for kind in [
                "good part",
                "missing",
                "bent",
                "damaged",
                "extra",
                "short",
                "high",
            ] {
                let sel: Vec<&Outcome> = o
                    .iter()
                    .filter(|x| {
                        if kind == "good part" {
                            x.f.defects.is_empty()
                        } else {
                            x.f.defects.iter().any(|d| d == kind)
                        }
                    })
                    .collect();
                line(&format!("defects: {kind}"), &sel);
            }
            continue;
        }
        for key in keys {
            let sel: Vec<&Outcome> = o.iter().filter(|x| x.f.categories()[k].1 == key).collect();
            line(&format!("{name}: {key}"), &sel);
        }
    }
    let wrong: Vec<&Outcome> = o.iter().filter(|x| !x.verdict_ok).collect();
    println!("\n{} wrong verdicts", wrong.len());
    if list {
        for x in wrong.iter().chain(
            o.iter()
                .filter(|x| x.verdict_ok && x.pin_wrong > 0)
                .collect::<Vec<_>>()
                .iter(),
        ) {
            println!("seed {}: {}", describe(&x.f), x.detail);
        }
        // Where the ok-pin centre RMS comes from: the images with an ok pin
        // more than a pixel off (a grid a pitch off puts every pin a pitch
        // off), largest share of the squared error first.
        let total: f64 = o.iter().flat_map(|x| x.ok_sq.iter()).sum();
        let mut off: Vec<&Outcome> = o
            .iter()
            .filter(|x| x.ok_sq.iter().any(|&e| e > 1.0))
            .collect();
        off.sort_by(|a, b| {
            b.ok_sq
                .iter()
                .sum::<f64>()
                .total_cmp(&a.ok_sq.iter().sum::<f64>())
        });
        for x in off {
            let sum: f64 = x.ok_sq.iter().sum();
            let max = x.ok_sq.iter().cloned().fold(0.0, f64::max).sqrt();
            println!(
                "centres off: seed {}: {} ok pins, worst {max:.2} px, {:.1} % of the ok-pin squared error",
                describe(&x.f),
                x.ok_sq.len(),
                100.0 * sum / total.max(f64::MIN_POSITIVE)
            );
        }
    }
    let _ = Verdict::Pass;
}

/// One case's factors on one line (the `--list` lines).
fn describe(f: &Factors) -> String {
    format!(
        "{} {:?} {:?} {:?} {}x{} {}x{} {:.4} mm/px{} tip {:.1} px rot {:.1} c {:.2} noise {:.1} blur {:.2} vig {:.2} grad {:.2} gain {:.2} {:?} {}bit{} defects {:?}",
        f.seed,
        f.view,
        f.polarity,
        f.pin_shape,
        f.rows,
        f.cols,
        f.width,
        f.height,
        f.mm_per_px,
        if f.scale_in_recipe { "" } else { " (est.)" },
        f.tip_px,
        f.rotation_deg,
        f.contrast,
        f.noise_dn,
        f.blur_px,
        f.vignetting,
        f.gradient,
        f.gain,
        f.jpeg_quality,
        f.bits,
        if f.colour { " colour" } else { "" },
        f.defects,
    )
}

fn line(label: &str, sel: &[&Outcome]) {
    let n = sel.len();
    let right = sel.iter().filter(|x| x.verdict_ok).count();
    let err = sel.iter().filter(|x| x.error.is_some()).count();
    let pins: usize = sel.iter().map(|x| x.pins).sum();
    let pw: usize = sel.iter().map(|x| x.pin_wrong).sum();
    let sq: Vec<f64> = sel.iter().flat_map(|x| x.ok_sq.iter().cloned()).collect();
    let rms = (sq.iter().sum::<f64>() / sq.len().max(1) as f64).sqrt();
    let fine: Vec<(f64, f64)> = sel
        .iter()
        .flat_map(|x| x.top_ok.iter().cloned())
        .filter(|p| p.0 <= 1.0)
        .collect();
    let bound = if fine.is_empty() {
        String::new()
    } else {
        let m = fine.len() as f64;
        format!(
            " {:.3} {:.3}",
            (fine.iter().map(|p| p.0 * p.0).sum::<f64>() / m).sqrt(),
            (fine.iter().map(|p| p.1 * p.1).sum::<f64>() / m).sqrt()
        )
    };
    println!(
        "  {label:34} {n:6} {:>9} {err:4} {:>9} {rms:.3}{bound}",
        pct(right, n),
        pct(pins - pw, pins)
    );
}

/// One case in detail: factors, truth, and the inspection.
fn show(seed: u64) {
    let case = EnvelopeCase::draw(seed);
    let r = case.render().expect("render");
    println!(
        "{}",
        serde_json::to_string(&case.factors).unwrap_or_default()
    );
    println!(
        "recipe: {}",
        toml::to_string(&case.recipe).unwrap_or_default()
    );
    match vision::inspect_gray(
        &case.recipe,
        &r.gray,
        r.info.clone(),
        &InspectOptions::default(),
    ) {
        Err(e) => println!("ERROR {e}"),
        Ok(ins) => {
            println!(
                "verdict {:?} (truth {:?}); grid {:?}",
                ins.verdict, r.truth.verdict, ins.grid
            );
            for (p, t) in ins.pins.iter().zip(&r.truth.pins) {
                println!(
                    "  ({},{}) {:?} (truth {:?}) at {:?},{:?} truth {:?},{:?} nominal {:.1},{:.1} area {:?} (truth {:?}) off {:?} height {:?} (truth {:?}){}",
                    p.row,
                    p.col,
                    p.status,
                    t.defect,
                    p.x_px.map(|v| (v * 100.0).round() / 100.0),
                    p.y_px.map(|v| (v * 100.0).round() / 100.0),
                    t.x_px.map(|v| (v * 100.0).round() / 100.0),
                    t.y_px.map(|v| (v * 100.0).round() / 100.0),
                    p.nominal_x_px,
                    p.nominal_y_px,
                    p.area_ratio,
                    t.area_ratio,
                    p.offset_mm,
                    p.height_mm,
                    t.height_mm,
                    p.reason
                        .as_deref()
                        .map(|r| format!(" — {r}"))
                        .unwrap_or_default()
                );
            }
            for e in &ins.extras {
                println!("  extra {}", serde_json::to_string(e).unwrap_or_default());
            }
            for e in &r.truth.extras {
                println!("  truth extra {:.1},{:.1}", e.x_px, e.y_px);
            }
            for e in &ins.ignored {
                println!("  ignored {}", serde_json::to_string(e).unwrap_or_default());
            }
            for w in &ins.warnings {
                println!("  note: {w}");
            }
        }
    }
}
