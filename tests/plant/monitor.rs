//! `pinsight monitor --shard k/n` over the interop logs, run as the cluster
//! engines would (separate processes), merged by `pinsight merge`: the
//! merged folder is the single run's byte for byte (monitor.json with its
//! SPC over all logs, by lot and by speed, the pins' SPC from the
//! photographs, cycles.csv, spc.csv, connectors.csv, every control chart,
//! cycles.parquet); a re-run shard writes the same bytes; pyarrow and
//! DuckDB read the cycles table and find monitor.json's cycles in it; a
//! merge refuses partials of two jobs.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn pinsight() -> Command {
    let mut c = common::pinsight_unsharded();
    c.current_dir(root());
    c
}

fn logs() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("fixtures/interop/logs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    // A log that cannot be read, and one named twice (counted twice,
    // as a single run does, both by one shard).
    v.push(root().join("fixtures/batch/corrupt.mcap"));
    v.push(root().join("fixtures/interop/logs/run-1500-lz4.mcap"));
    // Named in reverse: the partition must not depend on the order given.
    v.sort();
    v.reverse();
    v
}

use common::tree;

fn monitor(recipe: &Path, out: &Path, extra: &[&str]) -> Output {
    let o = pinsight()
        .arg("monitor")
        .args(logs())
        .arg("--process")
        .arg(recipe)
        .args(["-r", "fixtures/interop/images", "--parquet", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0 | 1 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn monitor_shards_merge_to_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    // The process recipe with its envelope learned on the zstd log.
    let recipe = tmp.path().join("r.toml");
    std::fs::copy(
        root().join("fixtures/process/hdr-2x10.process.toml"),
        &recipe,
    )
    .unwrap();
    let o = pinsight()
        .args([
            "monitor",
            "fixtures/interop/logs/run-1200-zstd.mcap",
            "--process",
        ])
        .arg(&recipe)
        .args(["--learn", "10"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );

    let whole = tmp.path().join("whole");
    let single = monitor(&recipe, &whole, &[]);
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(whole.join("monitor.json")).unwrap()).unwrap();
    assert!(run["logs"].as_array().unwrap().len() >= 10);
    assert!(
        run["logs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l["report"]["Err"].is_string()),
        "a log that cannot be monitored is part of the test"
    );
    assert!(
        !run["pin_spc"].as_array().unwrap().is_empty(),
        "the pins' SPC"
    );
    assert!(whole.join("connectors.csv").is_file());

    let n = 3;
    let shard = |k: u32| tmp.path().join(format!("s{k}"));
    for k in 0..n {
        monitor(&recipe, &shard(k), &["--shard", &format!("{k}/{n}")]);
    }
    let merged = tmp.path().join("merged");
    let o = pinsight()
        .arg("merge")
        .args((0..n).rev().map(shard))
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        single.status.code(),
        "the merge's exit status is the single run's: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    common::assert_same_tree(&whole, &merged);

    // A re-run shard writes the same bytes.
    let again = tmp.path().join("again");
    monitor(&recipe, &again, &["--shard", "1/3"]);
    assert!(
        tree(&again) == tree(&shard(1)),
        "shard 1/3 run twice differs"
    );

    // Partials of two jobs are refused.
    let y = tmp.path().join("yield-shard");
    let o = pinsight()
        .args([
            "yield",
            "fixtures/interop/images",
            "-r",
            "fixtures/interop/images",
        ])
        .args(["--shard", "1/3", "--out"])
        .arg(&y)
        .output()
        .unwrap();
    assert!(matches!(o.status.code(), Some(0 | 3)));
    let o = pinsight()
        .arg("merge")
        .args([shard(0), y, shard(2)])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("job yield differs") && err.contains("yield-shard"),
        "{err}"
    );

    // --learn with --shard is refused (each shard would learn its own).
    let o = pinsight()
        .arg("monitor")
        .args(logs())
        .arg("--process")
        .arg(&recipe)
        .args(["--learn", "5", "--shard", "0/2"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));

    // pyarrow and DuckDB read the cycles table.
    let py = Command::new("python3")
        .arg(root().join("tests/python/check_parquet.py"))
        .arg("monitor")
        .arg(&whole)
        .output()
        .expect("python3 with duckdb and pyarrow (.ci/python-requirements.txt)");
    assert!(
        py.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&py.stdout),
        String::from_utf8_lossy(&py.stderr)
    );
}
