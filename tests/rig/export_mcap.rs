//! `--mcap FILE` (issue 17) read back by the official Python readers
//! (`mcap`, `mcap-protobuf-support`; installed by `.ci/run` from
//! `.ci/python-requirements.txt`) through `tests/python/read_results_mcap.py`:
//! schema names and fields as Foxglove documents them, message counts and
//! times against the JSON reports of the same runs.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn pinsight(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pinsight"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    assert!(
        code == 0 || code == 1 || code == 3,
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (code, String::from_utf8_lossy(&out.stdout).into_owned())
}

/// What the Python readers see in an MCAP file.
fn read_back(file: &Path) -> Value {
    let out = Command::new("python3")
        .arg(root().join("tests/python/read_results_mcap.py"))
        .arg(file)
        .output()
        .expect("python3 with the mcap packages (.ci/python-requirements.txt)");
    assert!(
        out.status.success(),
        "{}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn topic<'a>(v: &'a Value, name: &str) -> &'a Value {
    let t = &v["topics"][name];
    assert!(!t.is_null(), "no topic {name} in {}", v["topics"]);
    t
}

fn fields(t: &Value) -> Vec<&str> {
    t["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect()
}

fn tmp(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

#[test]
fn overlay_mcap_has_measured_against_predicted_and_the_logs_signals() {
    let dir = tempfile::tempdir().unwrap();
    let file = tmp(&dir, "ov.mcap");
    let log = "fixtures/interop/logs/run-1200-zstd.mcap";
    let (_, json) = pinsight(&[
        "overlay",
        log,
        "--json",
        "--mcap",
        file.to_str().unwrap(),
        "--mcap-signals",
    ]);
    let report: Value = serde_json::from_str(&json).unwrap();
    let v = read_back(&file);
    let source = read_back(&root().join(log));
    // The log's own messages, unchanged.
    for (name, t) in source["topics"].as_object().unwrap() {
        let copy = topic(&v, name);
        assert_eq!(copy["count"], t["count"], "{name}");
        assert_eq!(copy["schema"], t["schema"], "{name}");
        assert_eq!(copy["first_ns"], t["first_ns"], "{name}");
    }
    let cycles = report["cycles"].as_array().unwrap();
    let stroke = topic(&v, "/pinsight/overlay/stroke");
    assert_eq!(stroke["schema"], "pinsight.StrokeSample");
    assert_eq!(stroke["schema_encoding"], "jsonschema");
    // One sample per grid angle per compared cycle (the interop log has full coverage).
    let grid = report["grid_deg"].as_array().unwrap().len();
    assert_eq!(
        stroke["count"].as_u64().unwrap() as usize,
        grid * cycles.len()
    );
    assert_eq!(stroke["first_ns"], cycles[0]["t_start_ns"]);
    for f in [
        "measured_mm",
        "predicted_mean_mm",
        "predicted_lo_2sigma_mm",
        "residual_mm",
    ] {
        assert!(fields(stroke).contains(&f), "{f}");
    }
    assert_eq!(
        topic(&v, "/pinsight/overlay/force")["count"],
        stroke["count"]
    );
    let per_cycle = topic(&v, "/pinsight/overlay/cycle");
    assert_eq!(per_cycle["count"].as_u64().unwrap() as usize, cycles.len());
    assert!(fields(per_cycle).contains(&"stroke_err_bdc_mm"));
}

#[test]
fn yield_and_inspect_mcap_have_images_with_foxglove_annotations() {
    let dir = tempfile::tempdir().unwrap();
    let file = tmp(&dir, "y.mcap");
    let recipe = "fixtures/interop/images/hdr-2x10.toml";
    // The ROS 2 twin: images in, annotated images out.
    let (_, json) = pinsight(&[
        "yield",
        "-r",
        recipe,
        "fixtures/twins/run-2000-images.ros2.mcap",
        "--json",
        "--mcap",
        file.to_str().unwrap(),
    ]);
    let rep: Value = serde_json::from_str(&json).unwrap();
    let v = read_back(&file);
    let images = topic(&v, "/camera/connector");
    assert_eq!(images["schema"], "foxglove.CompressedImage");
    assert_eq!(images["message_encoding"], "protobuf");
    assert_eq!(images["count"], 10);
    let ann = topic(&v, "/camera/connector/annotations");
    assert_eq!(ann["schema"], "foxglove.ImageAnnotations");
    assert_eq!(ann["count"], 10);
    // The log's own clock: the first image at its log_time.
    let source = read_back(&root().join("fixtures/interop/logs/run-2000-images.mcap"));
    assert_eq!(
        images["first_ns"],
        source["topics"]["/camera/connector"]["first_ns"]
    );
    for a in v["annotations"].as_array().unwrap() {
        assert!(
            a["circles"].as_u64().unwrap() >= 20,
            "a circle per pin: {a}"
        );
        assert_eq!(
            a["circle_fields"],
            serde_json::json!([
                "diameter",
                "fill_color",
                "outline_color",
                "position",
                "thickness",
                "timestamp"
            ])
        );
        // Points (measured centres) and a line list (the fitted grid).
        assert_eq!(a["point_types"], serde_json::json!([1, 4]));
    }
    let statuses = v["statuses"].as_array().unwrap();
    let passed = statuses.iter().filter(|s| *s == "pass").count();
    assert_eq!(passed as u64, rep["passed"].as_u64().unwrap());
    assert_eq!(v["images"][0]["format"], "png");

    // inspect: an unreadable file is an inspection message without an image.
    let file = tmp(&dir, "i.mcap");
    let (code, _) = pinsight(&[
        "inspect",
        "-r",
        recipe,
        "fixtures/interop/images/h2x10-00.png",
        "fixtures/interop/images/no-such-image.png",
        "--mcap",
        file.to_str().unwrap(),
    ]);
    assert_eq!(code, 3);
    let v = read_back(&file);
    assert_eq!(topic(&v, "/pinsight/inspection")["count"], 2);
    assert_eq!(topic(&v, "/camera/connector")["count"], 1);
    assert_eq!(v["statuses"], serde_json::json!(["error", "fail"]));
}

#[test]
fn simulate_mcap_has_every_output_step() {
    let dir = tempfile::tempdir().unwrap();
    let file = tmp(&dir, "s.mcap");
    let csv = tmp(&dir, "s.csv");
    pinsight(&[
        "simulate",
        "--revs",
        "1",
        "--warmup",
        "1",
        "--csv",
        csv.to_str().unwrap(),
        "--mcap",
        file.to_str().unwrap(),
    ]);
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count() - 1;
    let v = read_back(&file);
    let state = topic(&v, "/pinsight/sim/state");
    assert_eq!(state["count"].as_u64().unwrap() as usize, rows);
    assert_eq!(state["first_ns"], 0);
    assert!(fields(state).contains(&"contact_force_n"));
    assert_eq!(topic(&v, "/pinsight/sim/summary")["count"], 1);
    assert!(
        topic(&v, "/pinsight/sim/contact")["count"]
            .as_u64()
            .unwrap()
            > 0
    );
}
