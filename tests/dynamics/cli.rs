//! The dynamics commands end to end: the real binary, its outputs and its
//! error messages.

use crate::common;

use std::process::Command;

use common::run as pinsight;

#[test]
fn simulate_json_has_every_required_field() {
    let (code, out, err) = pinsight(&["simulate", "--warmup", "0", "--revs", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("one JSON object");
    for key in [
        "preset",
        "motor_rpm",
        "clearance_mm",
        "material",
        "contact_model",
        "level",
        "method",
        "rtol",
        "steps",
        "rhs_evals",
        "wall_ms",
        "n_impacts",
        "peak_accel_mps2",
        "peak_contact_force_n",
        "disp_dev_mean_mm",
        "disp_dev_max_mm",
        "vel_dev_mean_mps",
        "vel_dev_max_mps",
        "peak_torque_nm",
        "torque_dev_rms_nm",
        "stroke_min_mm",
        "stroke_max_mm",
        "peak_process_force_n",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}` in {out}");
    }
    assert_eq!(v["preset"], "paper");
    assert_eq!(v["level"], "clearance");
    // The pin reaches the part: the load cell sees the insertion force.
    let f = v["peak_process_force_n"].as_f64().unwrap();
    assert!(f > 20.0 && f <= 23.0 + 1e-9, "{f}");
}

#[test]
fn simulate_csv_grid_and_ensemble() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("run.csv");
    let (code, out, err) = pinsight(&[
        "simulate",
        "--set",
        "clearance_mm=0.3",
        "--warmup",
        "0",
        "--revs",
        "0.5",
        "--csv",
        csv.to_str().unwrap(),
        "--ensemble",
        "3",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,crank_deg,stroke_mm,vel_mps,acc_mps2,torque_nm,contact_force_n,ecc_x_mm,ecc_y_mm,ideal_stroke_mm,ideal_vel_mps,ideal_acc_mps2,ideal_torque_nm,process_force_n"
    );
    // Half a revolution on a 0.5° grid: 360 intervals, 361 rows.
    assert_eq!(lines.count(), 361);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let figures = v["ensemble"]["figures"].as_array().unwrap();
    assert!(
        figures
            .iter()
            .any(|f| f["figure"] == "disp_dev_mean_mm" && f["std"].is_number())
    );
    assert_eq!(v["ensemble"]["realisations"], 3);
}

#[test]
fn invalid_input_is_a_clear_error() {
    for (args, needle) in [
        (
            vec!["simulate", "--set", "clearance_mm=-0.1"],
            "clearance_mm",
        ),
        (vec!["simulate", "--set", "l_mm=7"], "l_mm"),
        (vec!["simulate", "--set", "material=cheese"], "material"),
        (vec!["simulate", "--set", "colour=red"], "colour"),
        (vec!["simulate", "--method", "euler"], "--method"),
        (vec!["simulate", "--rtol", "0"], "rtol"),
        (vec!["simulate", "--revs=-1"], "revs"),
        (
            vec!["simulate", "--params", "/no/such/file.toml"],
            "/no/such/file.toml",
        ),
        (vec!["sweep", "--materials", "gold"], "gold"),
    ] {
        let (code, _, err) = pinsight(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn parameter_file_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("head.toml");
    std::fs::write(
        &f,
        "preset = \"paper\"\nclearance_mm = 0.25\nmotor_rpm = 1500\nmaterial = \"copper\"\n",
    )
    .unwrap();
    let (code, out, err) = pinsight(&[
        "simulate",
        "--params",
        f.to_str().unwrap(),
        "--level",
        "ideal",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["clearance_mm"], 0.25);
    assert_eq!(v["motor_rpm"], 1500.0);
    assert_eq!(v["material"], "copper");
    // --set overrides the file.
    let (_, out, _) = pinsight(&[
        "simulate",
        "--params",
        f.to_str().unwrap(),
        "--set",
        "motor_rpm=1000",
        "--level",
        "kinematic",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["motor_rpm"], 1000.0);
    assert!(
        v["peak_torque_nm"].is_null(),
        "kinematic level has no forces"
    );
}

#[test]
fn small_sweep_writes_tables_and_charts() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("sweep");
    let (code, out, err) = pinsight(&[
        "sweep",
        "--clearances",
        "0.1,0.5",
        "--speeds",
        "1200",
        "--materials",
        "alloy_steel,copper",
        "--warmup",
        "0.5",
        "--revs",
        "0.5",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}\n{out}");
    let csv = std::fs::read_to_string(out_dir.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4);
    assert!(csv.lines().skip(1).all(|l| l.contains(",ok,")));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("sweep.json")).unwrap())
            .unwrap();
    assert_eq!(json["cases"].as_array().unwrap().len(), 4);
    for f in [
        "curves_clearance",
        "bars_clearance",
        "curves_speed",
        "bars_speed",
        "curves_material",
        "bars_material",
    ] {
        let png = std::fs::read(out_dir.join(format!("{f}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG", "{f}");
        assert!(png.len() > 10_000, "{f} looks empty");
    }
}

#[test]
fn methods_quick_lab_writes_its_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("methods");
    let (code, out, err) = pinsight(&["methods", "dynamics", "--out", out_dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("work–precision"), "{out}");
    for f in [
        "dynamics.json",
        "work_precision.csv",
        "stability.csv",
        "outside_reference.csv",
        "long_run.csv",
        "fidelity.csv",
        "work_precision.png",
        "stability.png",
        "long_run.png",
        "step_budget.png",
    ] {
        assert!(out_dir.join(f).exists(), "missing {f}");
    }
}

/// Runs the command with its stdout a pipe whose read end is closed before
/// the command has printed anything (`| head` having had enough).
fn run_with_stdout_closed(mut cmd: Command) -> std::process::Output {
    use std::process::Stdio;
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

/// `pinsight simulate --json | head -1`: the reader closing the pipe early
/// is not a failure, and never a panic trace.
#[test]
fn closed_stdout_pipe_is_not_a_panic() {
    for args in [
        &["simulate", "--json"][..],
        &["simulate", "--revs", "0.5", "--warmup", "0"][..],
    ] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_pinsight"));
        cmd.args(args);
        let out = run_with_stdout_closed(cmd);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    }
}

/// `pinsight inspect … --out DIR | head`: the closed pipe loses only the
/// text; every annotated overlay is still written.
#[test]
fn closed_stdout_pipe_still_writes_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let fx = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/interop/images");
    let imgs: Vec<String> = (0..4).map(|i| format!("{fx}/h2x10-0{i}.png")).collect();
    let imgs: Vec<&String> = imgs
        .iter()
        .filter(|p| std::path::Path::new(p).exists())
        .collect();
    assert!(imgs.len() >= 2);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pinsight"));
    cmd.args([
        "inspect",
        "--recipe",
        &format!("{fx}/hdr-2x10.toml"),
        "--out",
    ])
    .arg(dir.path())
    .args(&imgs);
    let out = run_with_stdout_closed(cmd);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    // docs/vision.md: 0 all passed, 1 some failed (h2x10-00 has a bent pin).
    assert_eq!(out.status.code(), Some(1), "{err}");
    let written = std::fs::read_dir(dir.path()).unwrap().count();
    assert!(
        written >= imgs.len(),
        "{written} files for {} images",
        imgs.len()
    );
}
