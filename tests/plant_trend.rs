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
//! merge; the calibration's accuracy is `tests/wear_trend.rs`'s.

mod common;

use pinsight::rig::synth::wear_series::WearSeries;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

fn pinsight() -> Command {
    common::pinsight_unsharded()
}

fn ok(o: &Output, codes: &[i32]) {
    assert!(
        o.status.code().is_some_and(|c| codes.contains(&c)),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Every file below `dir`, by its path relative to `dir`.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        assert!(
            p.is_file(),
            "{}: a trend folder holds files only",
            p.display()
        );
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        out.insert(name, std::fs::read(&p).unwrap());
    }
    out
}

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

    let (w, m) = (tree(&whole), tree(&merged));
    assert_eq!(
        w.keys().collect::<Vec<_>>(),
        m.keys().collect::<Vec<_>>(),
        "the merged folder holds the single run's files"
    );
    for (name, bytes) in &w {
        assert!(
            bytes == &m[name],
            "{name} differs between the single run and the merge"
        );
    }
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
