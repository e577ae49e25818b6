//! `--shard k/n` on the jobs besides `yield` and `monitor`, run as the
//! cluster engines would run them (separate processes over the same
//! inputs): `sweep`'s shards merged by `pinsight merge` give the single
//! run's study byte for byte, and `overlay` over several logs puts each
//! log in exactly one shard, in the folder a single run gives it, with the
//! same bytes. The wall-clock times (`wall_ms`) stay out of the files
//! (`output::json`), so a shard run again writes the same bytes (tested
//! for both).

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pinsight() -> Command {
    common::pinsight_unsharded()
}

use common::{exit_in as ok, tree};

fn sweep(out: &Path, shard: Option<&str>) -> Output {
    let mut c = pinsight();
    c.args(["sweep", "--clearances", "0.1,0.5", "--speeds", "1200"])
        .args(["--materials", "alloy_steel,copper"])
        .args(["--warmup", "0.5", "--revs", "0.5", "--out"])
        .arg(out);
    if let Some(s) = shard {
        c.args(["--shard", s]);
    }
    c.output().unwrap()
}

#[test]
fn sweep_shards_merge_to_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    ok(&sweep(&whole, None), &[0]);
    // Three shards of four cases: 0/3 runs cases 0 and 3.
    let shard = |k: u32| tmp.path().join(format!("s{k}"));
    for k in 0..3 {
        ok(&sweep(&shard(k), Some(&format!("{k}/3"))), &[0]);
        let j: serde_json::Value =
            serde_json::from_slice(&std::fs::read(shard(k).join("sweep.json")).unwrap()).unwrap();
        let ran = j["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| !c["summary"].is_null())
            .count();
        assert_eq!(ran, if k == 0 { 2 } else { 1 }, "shard {k}: {j:.300}");
    }
    let merged = tmp.path().join("merged");
    let o = pinsight()
        .arg("merge")
        .args([shard(2), shard(0), shard(1)])
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    ok(&o, &[0]);

    common::assert_same_tree(&whole, &merged);
    let w = tree(&whole);
    // No wall-clock time in any file.
    for name in ["sweep.json", "sweep.csv"] {
        let text = String::from_utf8(w[name].clone()).unwrap();
        assert!(!text.contains("wall_ms"), "{name}: {text:.400}");
    }
    // A shard run again (a failed pod retried) writes the same bytes.
    let again = tmp.path().join("s1-again");
    ok(&sweep(&again, Some("1/3")), &[0]);
    assert!(
        tree(&again) == tree(&shard(1)),
        "a re-run of shard 1/3 differs"
    );

    // A missing shard is refused, naming it, and nothing is written.
    let refused = tmp.path().join("refused");
    let o = pinsight()
        .arg("merge")
        .args([shard(0), shard(1)])
        .arg("--out")
        .arg(&refused)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2/3 missing"), "{err}");
    assert!(!refused.exists());
}

fn logs() -> Vec<PathBuf> {
    let f = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/logs");
    vec![
        f.join("synth-1800-ripple-dropouts-blocks.mcap"),
        f.join("synth-1200-model-c030.mcap"),
        f.join("synth-1500-nomarks-lz4.mcap"),
    ]
}

fn overlay(out: &Path, shard: Option<&str>) -> Output {
    let mut c = pinsight();
    c.arg("overlay")
        .args(logs())
        .arg("/no/such/log.mcap")
        .args(["--revs", "2", "--warmup", "0", "--points", "90", "--out"])
        .arg(out);
    if let Some(s) = shard {
        c.args(["--shard", s]);
    }
    c.output().unwrap()
}

#[test]
fn overlay_shards_hold_every_log_once_as_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    // The missing log is listed and the others done: exit 3.
    let o = overlay(&whole, None);
    ok(&o, &[3]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("/no/such/log.mcap"));
    let w = tree(&whole);
    let folders: std::collections::BTreeSet<&str> =
        w.keys().map(|k| k.split('/').next().unwrap()).collect();
    assert_eq!(folders.len(), 3, "{folders:?}");

    let mut union = BTreeMap::new();
    let mut missing_in = Vec::new();
    for k in 0..2 {
        let d = tmp.path().join(format!("s{k}"));
        let o = overlay(&d, Some(&format!("{k}/2")));
        ok(&o, &[0, 3]);
        if String::from_utf8_lossy(&o.stderr).contains("/no/such/log.mcap") {
            missing_in.push(k);
        }
        if d.exists() {
            for (name, bytes) in tree(&d) {
                assert!(
                    union.insert(name.clone(), bytes).is_none(),
                    "{name} written by two shards"
                );
            }
        }
    }
    assert_eq!(missing_in.len(), 1, "the missing log is one shard's error");
    assert_eq!(
        w.keys().collect::<Vec<_>>(),
        union.keys().collect::<Vec<_>>(),
        "the shards' folders together are the single run's"
    );
    // Every file the same bytes, `overlay.json` too (its prediction's
    // wall-clock time is not written).
    for (name, bytes) in &w {
        assert!(
            bytes == &union[name],
            "{name} differs between the single run and its shard"
        );
        if name.ends_with(".json") {
            assert!(
                !String::from_utf8_lossy(bytes).contains("wall_ms"),
                "{name}"
            );
        }
    }
    // A shard run again writes the same bytes.
    let again = tmp.path().join("s0-again");
    ok(&overlay(&again, Some("0/2")), &[0, 3]);
    let first = tmp.path().join("s0");
    assert_eq!(again.exists(), first.exists());
    if first.exists() {
        assert!(
            tree(&again) == tree(&first),
            "a re-run of shard 0/2 differs"
        );
    }
}
