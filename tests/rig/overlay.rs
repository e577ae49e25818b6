//! Overlay and calibration, end to end, against independent truth:
//! - the interop log recorded with a 0.5 mm clearance whose metadata says 0.1;
//! - logs generated from the clearance-joint model by `examples/gen_logs.rs`
//!   whose true clearance and standoff are read from the truth files the
//!   generator wrote from its own inputs;
//! - the CLI's JSON/CSV/PNG outputs, the parameter-file round trip, bad input.

use crate::common;

use pinsight::model::Params;
use pinsight::overlay::calibrate::{CalibrateOptions, CalibrationReport, calibrate};
use pinsight::overlay::compare::model_params;
use pinsight::progress::Progress;
use pinsight::rig::{CycleOptions, LoadOptions, analyse, load};
use std::path::{Path, PathBuf};

fn path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

use common::run as pinsight;

fn calibrate_file(rel: &str) -> CalibrationReport {
    let f = path(rel);
    let log = load(&f, &LoadOptions::default(), &Progress::hidden()).unwrap();
    let cs = analyse(&log, &CycleOptions::default());
    let (base, _) = model_params(&log, None, &[]).unwrap();
    calibrate(
        &log,
        &cs,
        &base,
        &CalibrateOptions::default(),
        &Progress::hidden(),
    )
    .unwrap()
}

fn estimate(r: &CalibrationReport, name: &str) -> (f64, f64) {
    let e = r
        .estimates
        .iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("no estimate {name}"));
    assert!(e.u95.is_finite() && e.u95 > 0.0, "{name}: U95 {}", e.u95);
    (e.value, e.u95)
}

fn truth(rel: &str) -> serde_json::Value {
    let t = path(rel).with_extension("truth.json");
    serde_json::from_str(&std::fs::read_to_string(t).unwrap()).unwrap()
}

#[test]
fn calibrate_finds_the_interop_logs_half_millimetre_clearance() {
    let rel = "fixtures/interop/logs/run-1200-clearance05.mcap";
    let t = truth(rel);
    let true_c = t["true_parameters"]["clearance_mm"].as_f64().unwrap();
    assert_eq!(t["metadata"]["clearance_mm"], "0.1");
    let r = calibrate_file(rel);
    let (c, u) = estimate(&r, "clearance");
    assert_eq!(
        r.estimates[0].nominal,
        Some(0.1),
        "the nominal is the metadata's"
    );
    assert!(
        (c - true_c).abs() <= u,
        "clearance {c} ± {u}, truth {true_c}"
    );
    assert!(
        u < 0.1,
        "the uncertainty must separate 0.5 from 0.1 mm: U95 {u}"
    );
    // The fit explains the log better than the nominal parameters.
    assert!(r.after.stroke_spread_rms_mm < 0.5 * r.before.stroke_spread_rms_mm);
    assert!(r.after.force_rms_n < r.before.force_rms_n);
    let (so, uso) = estimate(&r, "standoff");
    let true_so = t["true_parameters"]["standoff_mm"].as_f64().unwrap();
    assert!((so - true_so).abs() <= uso, "standoff {so} ± {uso}");
}

/// The generator's true clearance and standoff (from the truth file it wrote
/// from its inputs) lie within the calibration's expanded uncertainty.
fn recovers_generator_truth(rel: &str) {
    let t = truth(rel);
    let tp = &t["true_parameters"];
    let true_c = tp["clearance_mm"].as_f64().unwrap();
    let true_so = tp["standoff_mm"].as_f64().unwrap();
    let nominal_c: f64 = t["metadata"]["clearance_mm"]
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (true_c - nominal_c).abs() > 0.05,
        "the fixture must have a true clearance ≠ nominal"
    );
    let r = calibrate_file(rel);
    let (c, uc) = estimate(&r, "clearance");
    let (so, uso) = estimate(&r, "standoff");
    assert!(
        (c - true_c).abs() <= uc,
        "{rel}: clearance {c} ± {uc}, truth {true_c}"
    );
    assert!(
        (so - true_so).abs() <= uso,
        "{rel}: standoff {so} ± {uso}, truth {true_so}"
    );
    // Informative: the interval excludes the wrong nominal values.
    assert!(
        (c - nominal_c).abs() > uc,
        "{rel}: cannot tell from nominal"
    );
    assert!((so - 14.0).abs() > uso, "{rel}: standoff not resolved");
}

#[test]
fn calibrate_recovers_the_generators_truth_at_1200_rpm() {
    recovers_generator_truth("fixtures/logs/synth-1200-model-c030.mcap");
}

#[test]
fn calibrate_recovers_the_generators_truth_at_1500_rpm_with_an_encoder_offset() {
    recovers_generator_truth("fixtures/logs/synth-1500-model-c020.mcap");
}

#[test]
fn overlay_writes_the_promised_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ov");
    let log = path("fixtures/logs/synth-1200-model-c030.mcap");
    let (code, stdout, stderr) = pinsight(&[
        "overlay",
        log.to_str().unwrap(),
        "--set",
        "clearance_mm=0.3",
        "--set",
        "standoff_mm=13.8",
        "--cycles",
        "2..20",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let file_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("overlay.json")).unwrap()).unwrap();
    assert_eq!(v["run"], file_json["run"]);
    for k in [
        "stroke_mean_rms_mm",
        "stroke_mean_max_mm",
        "force_mean_rms_n",
        "stroke_rms_err_mm",
        "force_rms_err_n",
        "stroke_in_band",
        "stroke_in_2sigma",
        "force_in_band",
    ] {
        assert!(v["run"][k].as_f64().is_some(), "run.{k}");
    }
    let cycles = v["cycles"].as_array().unwrap();
    assert_eq!(cycles.len(), 18, "--cycles 2..20");
    assert!(
        cycles
            .iter()
            .all(|c| (2..20).contains(&c["index"].as_u64().unwrap()))
    );
    for k in [
        "stroke_rms_err_mm",
        "stroke_max_err_mm",
        "stroke_err_tdc_mm",
        "stroke_err_bdc_mm",
        "force_rms_err_n",
    ] {
        assert!(cycles[0][k].as_f64().is_some(), "cycle.{k}");
    }
    for k in [
        "depth_mm",
        "peak_force_n",
        "disp_dev_mean_mm",
        "disp_dev_max_mm",
        "vel_dev_mean_mps",
        "vel_dev_max_mps",
    ] {
        assert!(cycles[0]["measured"][k].as_f64().is_some(), "measured.{k}");
    }
    // With the true clearance and standoff, the measured cycles lie in the predicted band.
    assert!(v["run"]["stroke_in_band"].as_f64().unwrap() > 0.8);
    assert_eq!(v["groups"].as_array().unwrap().len(), 1);
    let csv = std::fs::read_to_string(out.join("cycles.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for k in [
        "index",
        "stroke_rms_err_mm",
        "stroke_err_tdc_mm",
        "stroke_err_bdc_mm",
        "depth_mm",
        "peak_force_n",
        "force_rms_err_n",
        "disp_dev_max_mm",
        "vel_dev_max_mps",
    ] {
        assert!(header.split(',').any(|h| h == k), "cycles.csv lacks {k}");
    }
    assert_eq!(csv.lines().count(), 19);
    let run = std::fs::read_to_string(out.join("run.csv")).unwrap();
    assert!(run.starts_with("key,value,unit\n") && run.contains("\nstroke_in_band,"));
    let curves = std::fs::read_to_string(out.join("curves.csv")).unwrap();
    assert_eq!(curves.lines().count(), 721);
    let figs = std::fs::read_to_string(out.join("figures.csv")).unwrap();
    assert!(figs.contains("\npeak_force_n,N,18,"));
    for png in ["overlay_stroke.png", "overlay_force.png"] {
        let img = image::open(out.join(png)).unwrap();
        assert_eq!((img.width(), img.height()), (1200, 1000), "{png}");
    }
}

#[test]
fn overlay_speed_groups_follow_the_threshold() {
    // The 1800 rpm fixture has a 2 % speed ripple within each cycle but a
    // steady mean speed: one group at the default 1 % threshold; a threshold
    // below the cycle-to-cycle spread splits it.
    let log = path("fixtures/logs/synth-1800-ripple-dropouts-blocks.mcap");
    let (code, out, err) = pinsight(&[
        "overlay",
        log.to_str().unwrap(),
        "--level",
        "ideal",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["groups"].as_array().unwrap().len(), 1);
    let speeds: Vec<f64> = v["cycles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["motor_rpm"].as_f64().unwrap())
        .collect();
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let thr = format!("{}", 0.4 * (hi - lo) / hi);
    let (code, out, err) = pinsight(&[
        "overlay",
        log.to_str().unwrap(),
        "--level",
        "ideal",
        "--speed-threshold",
        &thr,
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        v["groups"].as_array().unwrap().len() >= 2,
        "threshold {thr}"
    );
}

#[test]
fn calibrated_parameter_file_round_trips_through_simulate_and_overlay() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("cal.toml");
    let log = path("fixtures/logs/synth-1500-model-c020.mcap");
    let (code, out, err) = pinsight(&[
        "calibrate",
        log.to_str().unwrap(),
        "--revs",
        "16",
        "--out",
        toml.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in ["estimates", "before", "after", "f_ins_table", "params_toml"] {
        assert!(!v[k].is_null(), "calibrate JSON lacks {k}");
    }
    let e = &v["estimates"][0];
    assert_eq!(e["name"], "clearance");
    let c = e["value"].as_f64().unwrap();
    let p = Params::from_toml_file(&toml).unwrap();
    assert!((p.clearance * 1e3 - c).abs() < 1e-9);
    let so = v["estimates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == "standoff")
        .unwrap()["value"]
        .as_f64()
        .unwrap();
    assert!((p.standoff * 1e3 - so).abs() < 1e-9);
    let (code, out, err) = pinsight(&[
        "simulate",
        "--params",
        toml.to_str().unwrap(),
        "--warmup",
        "0",
        "--revs",
        "0.5",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"clearance"), "{out}");
    let (code, out, err) = pinsight(&[
        "overlay",
        log.to_str().unwrap(),
        "--params",
        toml.to_str().unwrap(),
        "--revs",
        "16",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let ov: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!((ov["clearance_mm"].as_f64().unwrap() - c).abs() < 1e-9);
    assert!((ov["standoff_mm"].as_f64().unwrap() - so).abs() < 1e-9);
}

#[test]
fn bad_input_gives_a_clear_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // A corrupt log: the magic is right, the rest garbage.
    let bad = dir.path().join("corrupt.mcap");
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    bytes.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    std::fs::write(&bad, &bytes).unwrap();
    for cmd in ["overlay", "calibrate"] {
        let (code, _, err) = pinsight(&[cmd, bad.to_str().unwrap()]);
        assert_ne!(code, 0, "{cmd}");
        assert!(
            err.contains("corrupt.mcap") && err.starts_with("error:"),
            "{cmd}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    // A missing file.
    let missing = dir.path().join("nope.mcap");
    let (code, _, err) = pinsight(&["overlay", missing.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("nope.mcap"), "{err}");
    // A log without the displacement channel (renamed topics, no channel map).
    let renamed = path("fixtures/interop/logs/run-1200-renamed.mcap");
    for cmd in ["overlay", "calibrate"] {
        let (code, _, err) = pinsight(&[cmd, renamed.to_str().unwrap()]);
        assert_ne!(code, 0, "{cmd}");
        assert!(
            err.contains("run-1200-renamed.mcap") && err.contains("displacement"),
            "{cmd}: {err}"
        );
    }
    // Bad arguments.
    let good = path("fixtures/logs/synth-1200-offsets.mcap");
    let (code, _, err) = pinsight(&["overlay", good.to_str().unwrap(), "--cycles", "9..3"]);
    assert_ne!(code, 0);
    assert!(err.contains("--cycles"), "{err}");
    let (code, _, err) = pinsight(&["overlay", good.to_str().unwrap(), "--level", "fast"]);
    assert_ne!(code, 0);
    assert!(err.contains("--level"), "{err}");
    // A log without force still overlays the stroke, and says so.
    let noforce = path("fixtures/interop/logs/run-1800-noforce.mcap");
    let (code, out, err) = pinsight(&["overlay", noforce.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        v["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("no force channel"))
    );
}
