//! Issue 16's targets on faulty lines (`pinsight::process::synth`): logs
//! whose cycles carry insertion faults of random kind and size, on heads
//! whose speed and sensors are drawn at random too (every factor at once),
//! judged by `pinsight monitor` with the fixture recipe
//! `fixtures/process/side-1x6.process.toml` after learning its envelope on
//! the log's first good cycles. The truth is the generator's draw, never
//! the monitor's own output:
//! - process NOK recall ≥ 99 % over the faulty cycles, false NOK ≤ 0.5 %
//!   over the good ones;
//! - with the connectors' photographs, the report's confusion table
//!   (process NOK × vision fail) equals the truth file's, connector by
//!   connector.

use crate::common;

use pinsight::process::synth::{FaultyLineConfig, LineTruth, faulty_line};
use pinsight::rig::synth::faults::{FaultRates, InsertionFault};
use pinsight::rig::synth::{SynthConfig, WriteSettings, write};
use pinsight::vision::Recipe;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

use common::run as pinsight;

fn recipe() -> Recipe {
    Recipe::load(&root().join("fixtures/vision/side-1x6.toml")).unwrap()
}

/// Writes a faulty line into `dir`, returns the log's path and its truth.
fn write_line(dir: &Path, name: &str, cfg: &FaultyLineConfig) -> (PathBuf, LineTruth) {
    let (log, truth) = faulty_line(cfg);
    let mut cur = std::io::Cursor::new(Vec::new());
    write(&log, &mut cur, &WriteSettings::default()).unwrap();
    let p = dir.join(format!("{name}.mcap"));
    std::fs::write(&p, cur.into_inner()).unwrap();
    (p, truth)
}

/// The fixture recipe with its envelope learned on the log's first 40 good cycles.
fn learned_recipe(dir: &Path, log: &Path) -> PathBuf {
    let r = dir.join(format!(
        "{}.process.toml",
        log.file_stem().unwrap().to_string_lossy()
    ));
    std::fs::copy(root().join("fixtures/process/side-1x6.process.toml"), &r).unwrap();
    let (code, out, err) = pinsight(&[
        "monitor",
        log.to_str().unwrap(),
        "--process",
        r.to_str().unwrap(),
        "--learn",
        "40",
        "--csv",
    ]);
    assert!(code == 0 || code == 1, "{out}{err}");
    r
}

/// A head drawn at random: speed, encoder, ripple, laser and load-cell
/// noise, lags and zeros all at once.
fn random_head(seed: u64, cycles: f64) -> SynthConfig {
    let mut r = pinsight::rng::SplitMix64::<0x7E57_0016>::new(seed);
    SynthConfig {
        motor_rpm: r.range(1000.0, 2000.0),
        revolutions: cycles + 1.6,
        start_theta: std::f64::consts::PI + r.range(0.05, 0.95) * std::f64::consts::TAU,
        encoder_counts: [2048, 4096, 8192][(r.uniform() * 3.0) as usize % 3],
        speed_ripple: r.range(0.0, 0.01),
        ripple_phase: r.range(0.0, std::f64::consts::TAU),
        speed_noise: r.range(0.0, 0.005),
        laser_zero_mm: r.range(8.0, 12.0),
        laser_lag_s: 1.0 / (std::f64::consts::TAU * r.range(2000.0, 5000.0)),
        laser_noise_mm: r.range(0.0005, 0.004),
        force_lag_s: 1.0 / (std::f64::consts::TAU * r.range(800.0, 3000.0)),
        force_noise_n: r.range(0.02, 0.12),
        force_tare_n: r.range(-0.3, 0.3),
        force_drift_n: r.range(-0.1, 0.1),
        seed,
        ..SynthConfig::default()
    }
}

#[test]
fn nok_recall_and_false_nok_over_random_heads() {
    let dir = tempfile::tempdir().unwrap();
    // (fault kind → (caught, drawn)); good cycles (flagged, seen).
    let mut per_fault: BTreeMap<InsertionFault, (usize, usize)> = BTreeMap::new();
    let (mut false_nok, mut good) = (0usize, 0usize);
    let mut rows = Vec::new();
    for seed in 1..=6u64 {
        let cfg = FaultyLineConfig {
            rig: random_head(seed, 220.0),
            rates: FaultRates::default(),
            recipe: recipe(),
            debris_rate: 0.0,
            images: false,
        };
        let (log, truth) = write_line(dir.path(), &format!("head{seed}"), &cfg);
        let r = learned_recipe(dir.path(), &log);
        let (code, json, err) = pinsight(&[
            "monitor",
            log.to_str().unwrap(),
            "--process",
            r.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(code, 1, "{err}");
        let run: Value = serde_json::from_str(&json).unwrap();
        let cycles = run["logs"][0]["report"]["Ok"]["cycles"].as_array().unwrap();
        let by_index: BTreeMap<u64, &Value> = cycles
            .iter()
            .map(|c| (c["index"].as_u64().unwrap(), c))
            .collect();
        // Every connector of the truth is a complete cycle of the log.
        assert_eq!(by_index.len(), truth.connectors.len(), "seed {seed}");
        for t in &truth.connectors {
            let v = by_index[&t.cycle];
            let nok = v["status"] == "nok";
            assert_ne!(
                v["status"], "not_evaluated",
                "seed {seed} cycle {}",
                t.cycle
            );
            match t.fault {
                Some(f) => {
                    let e = per_fault.entry(f).or_default();
                    e.1 += 1;
                    if nok {
                        e.0 += 1;
                    } else {
                        rows.push(format!(
                            "seed {seed} cycle {} {f:?} missed: {:?}",
                            t.cycle, t.draw
                        ));
                    }
                }
                None => {
                    good += 1;
                    if nok {
                        false_nok += 1;
                        rows.push(format!(
                            "seed {seed} cycle {} good called NOK: {}",
                            t.cycle, v["failed"]
                        ));
                    }
                }
            }
        }
    }
    let (caught, drawn) = per_fault
        .values()
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let recall = caught as f64 / drawn as f64;
    let false_rate = false_nok as f64 / good as f64;
    println!("per fault (caught, drawn): {per_fault:?}; good {good}, false NOK {false_nok}");
    for r in rows.iter().take(40) {
        println!("  {r}");
    }
    assert!(drawn >= 200 && good >= 900, "{drawn} {good}");
    for f in InsertionFault::ALL {
        assert!(
            per_fault.get(&f).is_some_and(|e| e.1 >= 30),
            "{f:?}: {per_fault:?}"
        );
    }
    assert!(recall >= 0.99, "recall {recall}");
    assert!(false_rate <= 0.005, "false NOK {false_rate}");
}

#[test]
fn the_connectors_story_matches_the_truth_file() {
    let dir = tempfile::tempdir().unwrap();
    for seed in [3u64, 11] {
        let cfg = FaultyLineConfig {
            rig: random_head(seed + 100, 60.0),
            rates: FaultRates {
                fault_rate: 0.3,
                ..FaultRates::default()
            },
            recipe: recipe(),
            debris_rate: 0.12,
            images: true,
        };
        let (log, truth) = write_line(dir.path(), &format!("story{seed}"), &cfg);
        let r = learned_recipe(dir.path(), &log);
        let out = dir.path().join(format!("out{seed}"));
        let (code, json, err) = pinsight(&[
            "monitor",
            log.to_str().unwrap(),
            "--process",
            r.to_str().unwrap(),
            "-r",
            "fixtures/vision/side-1x6.toml",
            "--json",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 1, "{err}");
        let run: Value = serde_json::from_str(&json).unwrap();
        let story = &run["logs"][0]["story"];
        let got: Vec<(u64, String, String)> = story["connectors"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| {
                (
                    c["cycle"].as_u64().unwrap(),
                    c["process"].as_str().unwrap().to_string(),
                    c["vision"].as_str().unwrap_or("none").to_string(),
                )
            })
            .collect();
        let want: Vec<(u64, String, String)> = truth
            .connectors
            .iter()
            .map(|c| {
                (
                    c.cycle,
                    if c.process_nok { "nok" } else { "ok" }.to_string(),
                    serde_json::to_value(c.vision)
                        .unwrap()
                        .as_str()
                        .unwrap()
                        .to_string(),
                )
            })
            .collect();
        assert_eq!(got, want, "seed {seed}");
        let confusion: pinsight::process::story::Confusion =
            serde_json::from_value(run["confusion"].clone()).unwrap();
        assert_eq!(confusion, truth.confusion, "seed {seed}");
        // Both kinds of disagreement occur and are listed with reasons.
        assert!(
            truth.confusion.process_ok_vision_fail > 0,
            "{:?}",
            truth.confusion
        );
        let csv = std::fs::read_to_string(out.join("connectors.csv")).unwrap();
        assert_eq!(csv.lines().count(), truth.connectors.len() + 1);
        for c in truth
            .connectors
            .iter()
            .filter(|c| c.debris && !c.process_nok)
        {
            let row = csv
                .lines()
                .find(|l| l.split(',').nth(1) == Some(&c.cycle.to_string()))
                .unwrap();
            assert!(
                row.contains(",ok,fail,false,") && row.contains("dust"),
                "{row}"
            );
        }
    }
}

/// The pins' positions on the connectors' photographs as SPC (issue 16
/// item 3), the model's band per connector, the charts and the Q-DAS file
/// with pins, on a faulty line whose photographs' pins are known:
/// - each pin's height mean and spread equal the painted heights' over the
///   connectors where the pin stands (the side view measures heights to
///   0.01 mm, vision.md), and its count is the number of those connectors;
/// - each connector's band is the overlay's own residual for its cycle
///   (`pinsight overlay --json` on the same log);
/// - an independent AQDEF reader (`aqdefreader`) finds every process and
///   pin characteristic, each pin's values as many as the SPC counted and
///   with the SPC's mean;
/// - one control chart PNG per characteristic.
#[test]
fn pin_positions_spc_band_charts_and_qdas_on_a_faulty_line() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = FaultyLineConfig {
        rig: random_head(77, 50.0),
        rates: FaultRates {
            fault_rate: 0.2,
            ..FaultRates::default()
        },
        recipe: recipe(),
        debris_rate: 0.05,
        images: true,
    };
    let (log, truth) = write_line(dir.path(), "pins", &cfg);
    let r = learned_recipe(dir.path(), &log);
    let out = dir.path().join("out");
    let dfq = dir.path().join("run.dfq");
    let (code, json, err) = pinsight(&[
        "monitor",
        log.to_str().unwrap(),
        "--process",
        r.to_str().unwrap(),
        "-r",
        "fixtures/vision/side-1x6.toml",
        "--band",
        "--json",
        "--out",
        out.to_str().unwrap(),
        "--dfq",
        dfq.to_str().unwrap(),
    ]);
    assert!(code == 0 || code == 1, "{err}");
    let run: Value = serde_json::from_str(&json).unwrap();
    let pin_spc = run["pin_spc"].as_array().unwrap();
    assert!(!pin_spc.is_empty());

    // Heights against the painted truth, pin by pin.
    let mut painted: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for c in &truth.connectors {
        for p in &c.pins {
            if let Some(h) = p.height_mm {
                painted
                    .entry(format!("pin r{}c{} height", p.row, p.col))
                    .or_default()
                    .push(h);
            }
        }
    }
    assert_eq!(painted.len(), 6);
    for (name, hs) in &painted {
        let c = pin_spc
            .iter()
            .find(|c| c["name"] == name.as_str())
            .unwrap_or_else(|| panic!("{name} missing"));
        let k = &c["capability"];
        assert_eq!(k["n"].as_u64().unwrap() as usize, hs.len(), "{name}");
        let mean = hs.iter().sum::<f64>() / hs.len() as f64;
        let sd =
            (hs.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / (hs.len() - 1) as f64).sqrt();
        let got_mean = k["mean"].as_f64().unwrap();
        let got_sd = k["sigma_overall"].as_f64().unwrap();
        assert!(
            (got_mean - mean).abs() < 0.01,
            "{name}: {got_mean} vs {mean}"
        );
        assert!((got_sd - sd).abs() < 0.01, "{name}: σ {got_sd} vs {sd}");
        assert_eq!(c["quantity"], "pin_height_mm");
    }

    // The band of each connector is the overlay's residual for its cycle.
    let (code, ov, err) = pinsight(&["overlay", log.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let ov: Value = serde_json::from_str(&ov).unwrap();
    let residuals: BTreeMap<u64, &Value> = ov["cycles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["index"].as_u64().unwrap(), c))
        .collect();
    let connectors = run["logs"][0]["story"]["connectors"].as_array().unwrap();
    let mut banded = 0;
    for c in connectors {
        let Some(want) = residuals.get(&c["cycle"].as_u64().unwrap()) else {
            continue;
        };
        let b = &c["band"];
        assert_eq!(b["stroke_in_band"], want["stroke_in_band"]);
        assert_eq!(b["force_in_band"], want["force_in_band"]);
        assert_eq!(b["stroke_err_bdc_mm"], want["stroke_err_bdc_mm"]);
        banded += 1;
    }
    assert!(
        banded + 2 >= connectors.len(),
        "{banded} of {}",
        connectors.len()
    );

    // Charts: one per characteristic with a chart.
    let process_spc = run["spc"].as_array().unwrap();
    for c in process_spc.iter().chain(pin_spc) {
        if c["chart"].is_null() {
            continue;
        }
        let slug: String = c["name"]
            .as_str()
            .unwrap()
            .to_lowercase()
            .split(|ch: char| !ch.is_ascii_alphanumeric())
            .filter(|w| !w.is_empty())
            .collect::<Vec<_>>()
            .join("-");
        let png = std::fs::read(out.join(format!("chart-{slug}.png")))
            .unwrap_or_else(|e| panic!("chart of {}: {e}", c["name"]));
        assert_eq!(&png[1..4], b"PNG");
    }

    // Q-DAS with pins, read back independently.
    let py = Command::new("python3")
        .arg(root().join("tests/python/read_dfq.py"))
        .arg(&dfq)
        .output()
        .expect("python3 with aqdefreader");
    assert!(
        py.status.success(),
        "{}",
        String::from_utf8_lossy(&py.stderr)
    );
    let got: Value = serde_json::from_slice(&py.stdout).unwrap();
    let chars = got["parts"][0]["characteristics"].as_array().unwrap();
    assert_eq!(chars.len(), process_spc.len() + pin_spc.len());
    for (c, s) in chars.iter().skip(process_spc.len()).zip(pin_spc) {
        assert_eq!(c["fields"]["K2001"], s["quantity"]);
        assert_eq!(c["fields"]["K2002"], s["name"]);
        let vals: Vec<f64> = c["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| {
                v.as_f64()
                    .or_else(|| v.as_str().and_then(|t| t.replace(',', ".").parse().ok()))
                    .unwrap()
            })
            .collect();
        let k = &s["capability"];
        assert_eq!(vals.len() as u64, k["n"].as_u64().unwrap(), "{}", s["name"]);
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        assert!(
            (mean - k["mean"].as_f64().unwrap()).abs() < 1e-6,
            "{}: {mean} vs {}",
            s["name"],
            k["mean"]
        );
    }
}
