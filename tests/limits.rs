//! Issue 14's reproductions through the real binary: no value hangs the
//! solver, no option asks for unbounded memory, nonsense is refused with
//! its range, and help is not an error. Every command runs under a time
//! limit: a hang fails the test instead of the suite.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(p)
        .to_str()
        .unwrap()
        .to_string()
}

/// Runs pinsight with `args`, killed after `secs` (then the test fails).
fn run(args: &[&str], dir: &Path, secs: u64) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pinsight"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > Duration::from_secs(secs) {
            let _ = child.kill();
            panic!("pinsight {args:?} did not finish within {secs} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn a_vanishing_clearance_is_refused_everywhere_and_never_hangs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = repo("fixtures/interop/logs/run-1200-zstd.mcap");
    for c in ["1e-300", "1e-40", "0x10", "", "nan", "1e300"] {
        let set = format!("clearance_mm={c}");
        let o = run(
            &["simulate", "--set", &set, "--warmup", "0", "--revs", "0.5"],
            d,
            20,
        );
        assert_eq!(o.status.code(), Some(2), "{c}: {}", text(&o));
        let t = text(&o);
        assert!(
            t.contains("clearance_mm") && t.contains("1e-4 … 10 mm"),
            "{c}: {t}"
        );
        assert!(t.len() < 400, "{c}: message too long: {t}");
    }
    // Through a log's metadata: `log` reports it, `overlay` finishes with a
    // note instead of integrating a 1e-300 mm clearance.
    let o = run(&["log", &log, "--meta", "clearance_mm=1e-300"], d, 30);
    let t = text(&o);
    assert!(
        t.contains("clearance_mm = '1e-300' is not 0 or a clearance within"),
        "{t}"
    );
    let o = run(&["overlay", &log, "--meta", "clearance_mm=1e-300"], d, 60);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("metadata clearance_mm = '1e-300' not used"));
    // The sweep records the failing case and writes the others.
    let out = d.join("sw");
    let o = run(
        &[
            "sweep",
            "--clearances",
            "1e-300,0.1",
            "--speeds",
            "1200",
            "--materials",
            "alloy_steel",
            "--warmup",
            "0",
            "--revs",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
        d,
        60,
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("sweep.json")).unwrap()).unwrap();
    let cases = json["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    assert!(cases[0]["error"].as_str().unwrap().contains("clearance_mm"));
    assert!(cases[1]["error"].is_null(), "{}", cases[1]);
}

#[test]
fn size_options_are_bounded_and_nonsense_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = repo("fixtures/interop/logs/run-1200-zstd.mcap");
    for args in [
        vec!["log", &log, "--points", "10000000"],
        vec!["log", &log, "--points", "100000000"],
        vec!["log", &log, "--points", "0"],
        vec!["overlay", &log, "--points", "1000000"],
    ] {
        let o = run(&args, d, 20);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains("8 … 7200"), "{args:?}: {}", text(&o));
    }
    let o = run(&["overlay", &log, "--revs", "0"], d, 20);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("2 … 10000"), "{}", text(&o));
    let o = run(&["simulate", "--set", "motor_rpm=1e308"], d, 20);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("motor_rpm"), "{}", text(&o));
    let o = run(&["render", "session", "--size", "100000x100000"], d, 20);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("allowed 20–1000 columns"), "{}", text(&o));
}

#[test]
fn help_for_the_parameter_keys_is_not_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(&["simulate", "--set", "help"], dir.path(), 20);
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("clearance_mm") && out.contains("0 (ideal joint) or 1e-4 … 10 mm"));
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
