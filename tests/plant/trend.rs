//! `trend --shard k/n` run as the cluster engines would run it (separate
//! processes over the same logs), merged by `pinsight merge`: the merged
//! folder is the single run's, byte for byte (`trend.json`, `history.csv`,
//! `trend.md`, `trend.png`), and a shard run again
//! writes the same bytes (the wall-clock time is kept out of the files).
//!
//! Lean on purpose: a short wear series (`rig::synth::wear_series`, a few
//! cycles per log) calibrated once, on the coarsest grid the command
//! allows (`--revs 8`), into a calibration cache (`--cache`) that the
//! single run and every shard then share, as a plant's nightly job does:
//! each log's calibration is one pure function of its bytes (the cache's
//! key), so what is tested here is the sharding, the partials and the
//! merge; the calibration's accuracy is `tests/plant/wear_trend.rs`'s.

use crate::common;

use pinsight::rig::synth::wear_series::WearSeries;
use std::path::Path;
use std::process::{Command, Output};

fn pinsight() -> Command {
    common::pinsight_unsharded()
}

use common::{exit_in as ok, tree};

fn trend(logs: &Path, cache: &Path, out: &Path, shard: Option<&str>) -> Output {
    let mut c = pinsight();
    c.arg("trend")
        .arg(logs)
        .args(["--limit", "0.8", "--revs", "8", "--cache"])
        .arg(cache)
        .arg("--out")
        .arg(out);
    if let Some(s) = shard {
        c.args(["--shard", s]);
    }
    c.output().unwrap()
}

#[test]
fn trend_shards_merge_to_the_single_run_and_a_rerun_writes_the_same_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    let logs = tmp.path().join("logs");
    std::fs::create_dir(&logs).unwrap();
    WearSeries {
        logs: 3,
        cycles_per_log: 4,
        seed: 11,
        ..WearSeries::default()
    }
    .write(&logs)
    .unwrap();
    // A log that cannot be read: one shard's error, listed in the merge.
    std::fs::write(logs.join("broken.mcap"), b"not an mcap file").unwrap();

    // The first run calibrates the three logs into the cache; the single
    // run compared is the next one, as every shard, from the cache.
    let cache = tmp.path().join("trend-cache.json");
    let first = tmp.path().join("first");
    ok(&trend(&logs, &cache, &first, None), &[3]);
    let whole = tmp.path().join("whole");
    ok(&trend(&logs, &cache, &whole, None), &[3]);
    let shard = |k: u32| tmp.path().join(format!("s{k}"));
    for k in 0..2 {
        ok(
            &trend(&logs, &cache, &shard(k), Some(&format!("{k}/2"))),
            &[0, 3],
        );
    }
    let merged = tmp.path().join("merged");
    let o = pinsight()
        .arg("merge")
        .args([shard(1), shard(0)])
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    ok(&o, &[3]);

    common::assert_same_tree(&whole, &merged);
    let w = tree(&whole);
    assert!(
        w.keys().all(|k| !k.contains(['/', '\\'])),
        "a trend folder holds files only: {:?}",
        w.keys().collect::<Vec<_>>()
    );
    // The report is a real one: three logs in one head, the broken one
    // listed; the cached points are the calibrated ones.
    let j: serde_json::Value = serde_json::from_slice(&w["trend.json"]).unwrap();
    assert_eq!(j["logs"], 4, "{j:.400}");
    assert_eq!(j["cached"], 3, "{j:.400}");
    assert_eq!(j["heads"][0]["points"].as_array().unwrap().len(), 3);
    assert!(
        j["errors"][0]["file"]
            .as_str()
            .unwrap()
            .ends_with("broken.mcap")
    );
    assert!(!String::from_utf8_lossy(&w["trend.json"]).contains("wall_ms"));
    let f: serde_json::Value =
        serde_json::from_slice(&std::fs::read(first.join("trend.json")).unwrap()).unwrap();
    assert_eq!(f["calibrated"], 3, "{f:.400}");
    assert_eq!(f["heads"], j["heads"]);
    assert_eq!(
        std::fs::read(first.join("history.csv")).unwrap(),
        w["history.csv"]
    );

    // A shard run again (into a fresh folder, as a failed pod's retry
    // finds it) writes the same bytes, its partial included.
    for k in 0..2 {
        let again = tmp.path().join(format!("s{k}-again"));
        ok(
            &trend(&logs, &cache, &again, Some(&format!("{k}/2"))),
            &[0, 3],
        );
        assert!(
            tree(&again) == tree(&shard(k)),
            "a re-run of shard {k}/2 differs"
        );
    }
}
