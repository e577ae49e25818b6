//! `pinsight batch` and `pinsight render` through the real binary: the CI
//! script over the fixture data, failing checks and exit codes, every
//! render format, and `pinsight` without a terminal.

use std::path::Path;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pinsight"))
}

fn repo(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

#[test]
fn ci_script_passes_and_writes_every_export() {
    let out = tempfile::tempdir().unwrap();
    let report = out.path().join("report.json");
    let o = bin()
        .arg("batch")
        .arg(repo("fixtures/ci.toml"))
        .arg("--out")
        .arg(out.path())
        .arg("--json")
        .arg(&report)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("0 failed; step errors: 0 — OK"), "{stdout}");
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let steps = r["steps"].as_array().unwrap();
    let checks = steps.iter().filter(|s| s["kind"] == "check").count();
    assert!(checks >= 8, "{checks} checks");
    assert_eq!(r["checks_passed"].as_u64().unwrap() as usize, checks);
    // Exports.
    let model: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("model.json")).unwrap()).unwrap();
    assert!(model["rows"].as_array().unwrap().len() > 30);
    let png = image::open(out.path().join("overlay.png")).unwrap();
    assert!(png.width() >= 500);
    let text = std::fs::read_to_string(out.path().join("signals.txt")).unwrap();
    assert_eq!(text.lines().count(), 24);
    // The tab bar (at 80 columns ten tabs show as `2 Sig`, see tui::draw).
    assert!(text.lines().next().unwrap().contains("2 Sig"));
    let csv = std::fs::read_to_string(out.path().join("study-by-speed.csv")).unwrap();
    assert!(csv.starts_with("case,clearance_mm,motor_rpm"));
    assert_eq!(csv.lines().count(), 3, "{csv}"); // header + 2 speeds
    assert!(image::open(out.path().join("study.png")).is_ok());
    // The data panes' exports: one CSV row per compared cycle (20 in the
    // log's truth file), per inspected image (40), and the annotated image.
    let cycles = std::fs::read_to_string(out.path().join("overlay-cycles.csv")).unwrap();
    assert_eq!(cycles.lines().count(), 21, "{cycles}");
    let items = std::fs::read_to_string(out.path().join("yield-items.csv")).unwrap();
    assert_eq!(items.lines().count(), 41, "{items}");
    assert!(image::open(out.path().join("yield.png")).is_ok());
    let v = image::open(out.path().join("vision-h2x10-00.png")).unwrap();
    assert_eq!((v.width(), v.height()), (1024, 768));
    assert!(image::open(out.path().join("overlay-measured.png")).is_ok());
}

#[test]
fn failing_checks_give_exit_code_1_and_every_step_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("s.toml");
    std::fs::write(
        &script,
        r#"
[[step]]
kind = "set"
level = "kinematic"
[[step]]
kind = "check"
name = "impossible"
pane = "model"
figure = "summary.stroke_max_mm"
op = ">"
value = 100
[[step]]
kind = "load"
path = "nothing-here.png"
[[step]]
kind = "check"
pane = "model"
figure = "summary.stroke_max_mm"
op = "<"
value = 100
"#,
    )
    .unwrap();
    let o = bin()
        .arg("batch")
        .arg(&script)
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("FAIL"), "{stdout}");
    assert!(stdout.contains("ERROR"), "{stdout}");
    assert!(stdout.contains("nothing-here.png"), "{stdout}");
    assert!(
        stdout.contains("checks: 1 passed, 1 failed; step errors: 1"),
        "{stdout}"
    );
    // A script that is not one: exit 2 with a message.
    std::fs::write(&script, "[[step]\n").unwrap();
    let o = bin().arg("batch").arg(&script).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not valid TOML"));
}

#[test]
fn render_prints_the_screen_and_writes_view_models() {
    let o = bin()
        .args([
            "render",
            "model",
            "--size",
            "80x24",
            "--set",
            "clearance_mm=0.2",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(text.lines().count(), 24);
    // The row of clearance_mm holds the value set (the columns are sized
    // from their content, so the spacing between them is not fixed).
    assert!(
        text.lines().any(|l| {
            let mut w = l.trim_start_matches('│').split_whitespace();
            w.next() == Some("clearance_mm") && w.next() == Some("0.2")
        }),
        "{text}"
    );
    // JSON: the same view model the checks read.
    let o = bin()
        .args(["render", "model", "--format", "json", "--level", "ideal"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["level"], "ideal");
    assert_eq!(v["summary"]["disp_dev_max_mm"], 0.0);
    // CSV.
    let o = bin()
        .args(["render", "signals", "--format", "csv"])
        .output()
        .unwrap();
    let csv = String::from_utf8_lossy(&o.stdout);
    assert!(csv.starts_with("channel,unit,visible"), "{csv}");
    assert_eq!(csv.lines().count(), 5, "{csv}");
    // PNG of a chart pane; a pane without charts says so.
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("signals.png");
    let o = bin()
        .args(["render", "signals", "--format", "png", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(image::open(&png).is_ok());
    let o = bin()
        .args(["render", "session", "--format", "png", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no chart"));
    // Bad arguments are errors, not panics.
    for args in [
        vec!["render", "nosuchpane"],
        vec!["render", "model", "--size", "5x5"],
        vec!["render", "model", "--set", "clearance_mm=-1"],
        vec!["render", "study", "--ui", "study.factor=colour"],
    ] {
        let o = bin().args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(!String::from_utf8_lossy(&o.stderr).contains("panicked"));
    }
}

#[test]
fn render_opens_files_and_reports_bad_ones() {
    let o = bin()
        .arg("render")
        .arg("session")
        .arg(repo("fixtures/batch/corrupt.mcap"))
        .arg(repo("fixtures/batch/worn-joint.toml"))
        .args(["--format", "json"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["errors"].as_array().unwrap().len(), 1);
    assert!(
        v["params_source"]
            .as_str()
            .unwrap()
            .ends_with("worn-joint.toml")
    );
}

#[test]
fn without_a_terminal_pinsight_prints_the_demo_summary() {
    let o = bin().output().unwrap();
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("pinsight demo"), "{s}");
    assert!(s.contains("impacts"), "{s}");
    let o = bin().arg("tui").output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("pinsight render"));
}
