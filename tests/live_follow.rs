//! The live line end to end: `pinsight rig-sim` writes at 8× real time while
//! `pinsight watch` follows; every cycle and image is seen exactly once, in
//! order, and the figures equal a batch run over the finished files (the
//! rig's cycle analysis, the process monitor with the same learning, the
//! yield over the same images). Bad input: a log that turns corrupt, a
//! deleted log, an image folder that disappears — each a finding, and the
//! following goes on.

use pinsight::rig::cycles::{CycleOptions, analyse};
use pinsight::rig::{LoadOptions, load};
use pinsight::vision::batch::{RecipeBook, collect_items, run_batch};
use pinsight::vision::report::{GroupBy, YieldReport};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_pinsight");

fn events(out: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn of_kind<'a>(ev: &'a [Value], k: &str) -> Vec<&'a Value> {
    ev.iter().filter(|e| e["event"] == k).collect()
}

/// Live and batch run the same analysis on the same samples; the crank
/// angle is unwrapped over a short window live and over the whole file in
/// batch, so figures agree to floating-point round-off (measured: ≤ 2e-8
/// relative on the stroke deviation, the others exactly or to 1e-12).
fn close(a: &Value, b: f64, what: &str) {
    match a.as_f64() {
        Some(x) => assert!(
            (x - b).abs() <= 1e-7 * (1e-3 + b.abs()),
            "{what}: live {x} batch {b}"
        ),
        None => assert!(b.is_nan(), "{what}: live {a} batch {b}"),
    }
}

#[test]
fn rig_sim_at_8x_followed_every_cycle_and_image_once_in_order_and_equal_to_batch() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("run.mcap");
    let img = dir.path().join("img");
    let recipe = dir.path().join("p.toml");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(root.join("fixtures/process/side-1x6.process.toml"), &recipe).unwrap();
    let sim = Command::new(BIN)
        .args([
            "rig-sim",
            "--rpm",
            "1500",
            "--rate",
            "8x",
            "--duration",
            "6s",
        ])
        .args(["--faults", "nok=0.15,debris=0.05", "--seed", "7", "--out"])
        .arg(&log)
        .arg("--images")
        .arg(&img)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let watch = Command::new(BIN)
        .args([
            "watch",
            "--json-lines",
            "--until-finished",
            "--max-time",
            "60s",
            "--learn",
            "20",
        ])
        .arg("--process")
        .arg(&recipe)
        .arg(&log)
        .arg(&img)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let s = sim.wait_with_output().unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let w = watch.wait_with_output().unwrap();
    assert!(w.status.success(), "{}", String::from_utf8_lossy(&w.stderr));
    let ev = events(&w.stdout);
    let summary = ev.last().unwrap();
    assert_eq!(summary["event"], "summary");

    // Batch: the finished log through the loader and the cycle analysis.
    let rl = load(
        &log,
        &LoadOptions::default(),
        &pinsight::progress::Progress::hidden(),
    )
    .unwrap();
    let cs = analyse(&rl, &CycleOptions::default());
    let cycles = of_kind(&ev, "cycle");
    assert!(cs.cycles.len() >= 140, "{}", cs.cycles.len());
    assert_eq!(cycles.len(), cs.cycles.len(), "every cycle once");
    for (k, (e, c)) in cycles.iter().zip(&cs.cycles).enumerate() {
        assert_eq!(
            e["index"].as_u64(),
            Some(k as u64),
            "in order, no gap, no duplicate"
        );
        assert_eq!(c.index, k as u64);
        assert_eq!(e["t_start_ns"].as_i64(), Some(c.t_start_ns));
        close(&e["motor_rpm"], c.motor_rpm_mean, "motor_rpm");
        close(&e["depth_mm"], c.depth_mm, "depth");
        close(&e["peak_force_n"], c.peak_force_n, "peak force");
        close(
            &e["stroke_err_bdc_mm"],
            c.stroke_err_bdc_mm,
            "stroke at BDC",
        );
        close(
            &e["stroke_dev_rms_mm"],
            c.stroke_dev_rms_mm,
            "stroke deviation",
        );
    }
    // The process monitor: the same learning, the same verdicts.
    let r = pinsight::process::ProcessRecipe::load(&recipe).unwrap();
    let (learned, _) = pinsight::process::learn(&r, &cs, 20).unwrap();
    let rep = pinsight::process::monitor(&learned, &cs);
    for (e, v) in cycles.iter().zip(&rep.cycles) {
        assert_eq!(
            e["status"].as_str(),
            Some(v.status.name()),
            "cycle {}",
            v.index
        );
    }
    assert_eq!(summary["process_nok"].as_u64(), Some(rep.nok as u64));
    assert!(rep.nok > 5, "faults were injected: {}", rep.nok);

    // Images: one per complete cycle, each once, in order.
    let images = of_kind(&ev, "image");
    assert_eq!(images.len(), cs.cycles.len());
    for (k, e) in images.iter().enumerate() {
        assert_eq!(e["cycle"].as_u64(), Some(k as u64));
    }
    // The yield equals the batch yield over the finished folder.
    let (items, errors) = collect_items(std::slice::from_ref(&img));
    assert!(errors.is_empty());
    let book = RecipeBook::new(vec![
        pinsight::vision::Recipe::from_toml_str(pinsight::live::sim::RECIPE, "r").unwrap(),
    ]);
    let results = run_batch(
        &items,
        &book,
        &Default::default(),
        &pinsight::progress::Progress::hidden(),
    );
    let batch = YieldReport::build(&results, GroupBy::Lot);
    assert_eq!(summary["yields"], serde_json::to_value(&batch).unwrap());
    assert!(batch.failed > 0 && batch.passed > 0);
    // Nothing was lost on the way.
    for f in of_kind(&ev, "finding") {
        let sev = f["severity"].as_str().unwrap();
        assert!(sev == "info" || sev == "warning", "{f}");
    }
}

#[test]
fn a_log_turning_corrupt_a_deleted_log_and_a_vanished_folder_are_findings_and_following_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("run.mcap");
    let img = dir.path().join("img");
    let sim = Command::new(BIN)
        .args([
            "rig-sim",
            "--rpm",
            "1500",
            "--rate",
            "4x",
            "--duration",
            "10s",
        ])
        .args(["--faults", "corrupt@3s", "--out"])
        .arg(&log)
        .arg("--images")
        .arg(&img)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let watch = Command::new(BIN)
        .args([
            "watch",
            "--json-lines",
            "--until-finished",
            "--max-time",
            "60s",
        ])
        .arg(&log)
        .arg(&img)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // After ~1.5 s of wall time (6 s of log): the log is deleted (the rig
    // goes on writing the unlinked file) and the image folder removed.
    std::thread::sleep(Duration::from_millis(1500));
    std::fs::remove_file(&log).unwrap();
    // The rig may be writing an image into the folder while it is being
    // removed (then removal reports "directory not empty"): try again, as an
    // operator would, until the folder is gone.
    let mut tries = 0;
    while let Err(e) = std::fs::remove_dir_all(&img) {
        tries += 1;
        assert!(tries < 50, "cannot remove {}: {e}", img.display());
        std::thread::sleep(Duration::from_millis(10));
    }
    let s = sim.wait_with_output().unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let w = watch.wait_with_output().unwrap();
    assert!(w.status.success(), "{}", String::from_utf8_lossy(&w.stderr));
    let ev = events(&w.stdout);
    let findings: Vec<String> = of_kind(&ev, "finding")
        .iter()
        .map(|f| f["message"].as_str().unwrap().to_string())
        .collect();
    let has = |what: &str| findings.iter().any(|m| m.contains(what));
    assert!(
        of_kind(&ev, "finding")
            .iter()
            .any(|f| f["severity"] == "data_loss"
                && f["message"].as_str().unwrap().contains("chunk")),
        "{findings:#?}"
    );
    assert!(has("was deleted while being followed"), "{findings:#?}");
    assert!(has("is not there (any more)"), "{findings:#?}");
    // Following went on: cycles after the corruption and after the deletion.
    let cycles = of_kind(&ev, "cycle");
    let last = cycles.last().unwrap()["index"].as_u64().unwrap();
    assert!(last >= 240, "last cycle {last}");
    let idx: Vec<u64> = cycles
        .iter()
        .map(|c| c["index"].as_u64().unwrap())
        .collect();
    assert!(
        idx.windows(2).all(|w| w[1] > w[0]),
        "in order, no duplicate"
    );
    let lost = 250 - idx.len();
    assert!(
        lost > 0 && lost < 10,
        "the corrupt chunk's cycles only: {lost} lost"
    );
    let files = of_kind(&ev, "file");
    assert!(files.iter().any(|f| f["state"] == "deleted"), "{files:?}");
}

/// `demo --live` makes its line in a temporary folder and leaves nothing
/// behind: not after a normal run, and not when an argument is bad (the
/// folder used to be made, and kept, before `--for` was read).
#[test]
fn the_live_demo_leaves_no_temporary_folder_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let left = || std::fs::read_dir(tmp.path()).unwrap().count();
    let run = |extra: &[&str]| {
        Command::new(BIN)
            .args(["demo", "--live"])
            .args(extra)
            .env("TMPDIR", tmp.path())
            .stdin(Stdio::null())
            .output()
            .unwrap()
    };
    let ok = run(&["--for", "1s"]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(
        !events(&ok.stdout).is_empty(),
        "the demo's line printed no event"
    );
    assert_eq!(left(), 0, "a normal run left its folder");
    for bad in [["--for", "soon"], ["--faults", "nok=lots"]] {
        let out = run(&bad);
        assert!(!out.status.success(), "{bad:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(bad[0]),
            "{bad:?}: the error does not name the option: {err}"
        );
        assert_eq!(left(), 0, "{bad:?} left a folder behind");
    }
}
