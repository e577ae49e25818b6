//! `pinsight monitor` (issue 16) on the interop logs: learning the envelope,
//! verdicts, the reasons and amounts of a NOK against the log's own cycle
//! figures (`pinsight log --json`), cycles without force never OK, bad
//! recipes named, the report files and the MCAP read back by Python.

use crate::common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

use common::run as pinsight;

const LOG: &str = "fixtures/interop/logs/run-1200-zstd.mcap";

/// The fixture recipe, learned on the first 10 good cycles of LOG, in a temp folder.
fn learned(dir: &tempfile::TempDir) -> PathBuf {
    let r = dir.path().join("r.toml");
    std::fs::copy(root().join("fixtures/process/hdr-2x10.process.toml"), &r).unwrap();
    let (code, out, err) = pinsight(&[
        "monitor",
        LOG,
        "--process",
        r.to_str().unwrap(),
        "--learn",
        "10",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("learned 1 envelope(s) from 10 good cycles"),
        "{out}"
    );
    let text = std::fs::read_to_string(&r).unwrap();
    assert!(text.contains("learned_from = 10"), "{text}");
    r
}

#[test]
fn a_good_run_is_ok_and_a_tightened_limit_names_every_cycle_by_its_amount() {
    let dir = tempfile::tempdir().unwrap();
    let r = learned(&dir);
    let (code, json, err) = pinsight(&["monitor", LOG, "--process", r.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let run: Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        (run["ok"].as_u64(), run["nok"].as_u64()),
        (Some(20), Some(0))
    );
    // The cycles' own figures, from the loader's summary.
    let (_, log_json, _) = pinsight(&["log", LOG, "--json", "--all-cycles"]);
    let log: Value = serde_json::from_str(&log_json).unwrap();
    let figures = log["cycles"]["cycles"].as_array().unwrap();
    let peak: Vec<f64> = figures
        .iter()
        .map(|c| c["peak_force_n"].as_f64().unwrap())
        .collect();
    let lowest = peak.iter().copied().fold(f64::INFINITY, f64::min);
    // A maximum just under the lowest peak: every cycle NOK by peak − max.
    let text = std::fs::read_to_string(&r)
        .unwrap()
        .replace("max = 30.0", &format!("max = {}", lowest - 0.01));
    let tight = dir.path().join("tight.toml");
    std::fs::write(&tight, text).unwrap();
    let (code, json, _) = pinsight(&[
        "monitor",
        LOG,
        "--process",
        tight.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 1);
    let run: Value = serde_json::from_str(&json).unwrap();
    let cycles = run["logs"][0]["report"]["Ok"]["cycles"].as_array().unwrap();
    assert_eq!(cycles.len(), 20);
    for (c, p) in cycles.iter().zip(&peak) {
        assert_eq!(c["status"], "nok");
        let f = &c["failed"][0];
        assert_eq!(f["name"], "peak force");
        assert!((f["value"].as_f64().unwrap() - p).abs() < 1e-12);
        assert!((f["by"].as_f64().unwrap() - (p - (lowest - 0.01))).abs() < 1e-9);
        assert!(f["reason"].as_str().unwrap().contains("above the maximum"));
    }
    // SPC of the peak force: the mean of the loader's peaks.
    let spc = &run["spc"][0];
    assert_eq!(spc["name"], "peak force");
    let mean = peak.iter().sum::<f64>() / peak.len() as f64;
    assert!((spc["capability"]["mean"].as_f64().unwrap() - mean).abs() < 1e-9);
}

#[test]
fn cycles_without_force_are_never_ok() {
    let dir = tempfile::tempdir().unwrap();
    let r = learned(&dir);
    let (code, csv, _) = pinsight(&[
        "monitor",
        "fixtures/interop/logs/run-1800-noforce.mcap",
        "--process",
        r.to_str().unwrap(),
        "--csv",
    ]);
    assert_eq!(code, 1);
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 20);
    assert!(
        rows.iter()
            .all(|r| r.contains(",not_evaluated,no force data")),
        "{csv}"
    );
}

#[test]
fn bad_recipes_name_the_key_and_the_allowed_values() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(root().join("fixtures/process/hdr-2x10.process.toml")).unwrap();
    for (from, to, expect) in [
        ("\"rising\"", "\"upward\"", ["upward", "rising", "falling"]),
        (
            "\"peak_force_n\"",
            "\"peak\"",
            ["peak", "peak_force_n", "impact_noise_um"],
        ),
        (
            "subgroup = 5",
            "subgroup = 40",
            ["spc.subgroup = 40", "1", "10"],
        ),
    ] {
        let p = dir.path().join("bad.toml");
        std::fs::write(&p, text.replace(from, to)).unwrap();
        let (code, _, err) = pinsight(&["monitor", LOG, "--process", p.to_str().unwrap()]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("bad.toml"), "{err}");
        for e in expect {
            assert!(err.contains(e), "{e} not in {err}");
        }
    }
}

#[test]
fn out_folder_and_mcap() {
    let dir = tempfile::tempdir().unwrap();
    let r = learned(&dir);
    let out = dir.path().join("mon");
    let mcap = dir.path().join("mon.mcap");
    let (code, _, err) = pinsight(&[
        "monitor",
        LOG,
        "--process",
        r.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--mcap",
        mcap.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let cycles = std::fs::read_to_string(out.join("cycles.csv")).unwrap();
    assert_eq!(cycles.lines().count(), 21);
    let spc = std::fs::read_to_string(out.join("spc.csv")).unwrap();
    assert!(
        spc.lines()
            .any(|l| l.starts_with("all,peak force,peak_force_n,N,20,5,")),
        "{spc}"
    );
    let _: Value =
        serde_json::from_slice(&std::fs::read(out.join("monitor.json")).unwrap()).unwrap();
    let py = Command::new("python3")
        .arg(root().join("tests/python/read_results_mcap.py"))
        .arg(&mcap)
        .output()
        .expect("python3 with the mcap packages");
    assert!(
        py.status.success(),
        "{}",
        String::from_utf8_lossy(&py.stderr)
    );
    let v: Value = serde_json::from_slice(&py.stdout).unwrap();
    let t = &v["topics"]["/pinsight/monitor/cycle"];
    assert_eq!(t["schema"], "pinsight.CycleVerdict");
    assert_eq!(t["count"], 20);
    // The log's own signals are there too.
    assert!(v["topics"]["/rig/force"]["count"].as_u64().unwrap() > 10_000);
}

/// The Q-DAS export read back by an independent reader (PyPI
/// `aqdefreader`): the part, every value check as a characteristic with its
/// limits and unit, and every cycle's value and date, against the run's
/// own JSON.
#[test]
fn the_dfq_export_reads_back_with_an_independent_aqdef_reader() {
    let dir = tempfile::tempdir().unwrap();
    let r = learned(&dir);
    let dfq = dir.path().join("run.dfq");
    let (code, json, err) = pinsight(&[
        "monitor",
        LOG,
        "--process",
        r.to_str().unwrap(),
        "--json",
        "--dfq",
        dfq.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let run: Value = serde_json::from_str(&json).unwrap();
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
    let parts = got["parts"].as_array().unwrap();
    assert_eq!(parts.len(), 1);
    assert_eq!(parts[0]["part"], "HDR-2x10-2.54");
    let chars = parts[0]["characteristics"].as_array().unwrap();
    let spc = run["spc"].as_array().unwrap();
    assert_eq!(chars.len(), spc.len());
    let cycles = run["logs"][0]["report"]["Ok"]["cycles"].as_array().unwrap();
    for (c, s) in chars.iter().zip(spc) {
        let f = &c["fields"];
        assert_eq!(f["K2001"], s["quantity"]);
        assert_eq!(f["K2002"], s["name"]);
        let unit = s["unit"].as_str().unwrap();
        if unit.is_ascii() {
            assert_eq!(f["K2142"], unit);
        } else {
            // Latin-1 in the file (µ = 0xB5); the reader guesses the code
            // page from the bytes (chardet) and may read 0xB5 as another
            // letter, so the bytes are checked here.
            let bytes = std::fs::read(&dfq).unwrap();
            let latin1: Vec<u8> = unit.chars().map(|c| c as u32 as u8).collect();
            assert!(
                bytes
                    .windows(latin1.len() + 2)
                    .any(|w| w[1..w.len() - 1] == latin1[..]
                        && w[0] == b' '
                        && w[w.len() - 1] == b'\r'),
                "unit {unit} not in Latin-1"
            );
            assert_eq!(
                f["K2142"].as_str().unwrap().chars().count(),
                unit.chars().count()
            );
        }
        let lim = |k: &str, j: &str| {
            let want = &s["capability"][j];
            if want.is_null() {
                assert!(f.get(k).is_none(), "{k}: {f}");
            } else {
                let v: f64 = f[k].as_str().unwrap().replace(',', ".").parse().unwrap();
                assert_eq!(v, want.as_f64().unwrap(), "{k}");
            }
        };
        lim("K2110", "lsl");
        lim("K2111", "usl");
        let name = s["name"].as_str().unwrap();
        let want: Vec<f64> = cycles
            .iter()
            .filter_map(|cy| cy["values"][name].as_f64())
            .collect();
        let vals = c["values"].as_array().unwrap();
        assert_eq!(vals.len(), want.len(), "{name}");
        for (v, w) in vals.iter().zip(&want) {
            assert!(
                (v.as_f64().unwrap() - w).abs() <= 5e-7,
                "{name}: {v} vs {w}"
            );
        }
        // Dates: the cycle's start, to the second (UTC; the fixture's days
        // are past the 12th, so the reader's month-first guess is moot).
        let dates = c["dates"].as_array().unwrap();
        let starts: Vec<i64> = cycles
            .iter()
            .filter(|cy| cy["values"][name].is_number())
            .map(|cy| cy["t_start_ns"].as_i64().unwrap())
            .collect();
        for (d, t) in dates.iter().zip(starts) {
            let secs = t.div_euclid(1_000_000_000);
            let (days, sod) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
            let want_time = format!("T{:02}:{:02}:{:02}", sod / 3600, (sod / 60) % 60, sod % 60);
            let d = d.as_str().unwrap();
            assert!(d.ends_with(&want_time), "{d} vs {want_time}");
            // The fixture runs on 2026-11-20 (UTC): day 20 777 after the epoch.
            assert_eq!(days, 20_777);
            assert!(d.starts_with("2026-11-20"), "{d}");
        }
    }
}
