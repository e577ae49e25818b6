//! Parquet outputs of `yield` and the merge's refusals, on the real binary.
//!
//! - Shards writing hive-partitioned tables (`--partition-by part,lot`),
//!   merged, give the single run's partitioned folder byte for byte; and
//!   independent readers (pyarrow, DuckDB from PyPI, `.ci/python-
//!   requirements.txt`) read every table and find pinsight's own figures
//!   in them (tests/python/check_parquet.py).
//! - `--items parquet` alone: `yield.json` is the report only, and the
//!   merge still gives the single run's folder.
//! - A merge is refused, naming the file, with nothing written, for: a
//!   missing or corrupt partial, a shard file changed after the shard
//!   wrote it, another recipe, another pinsight version, overlapping
//!   shards.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop")
}

fn pinsight() -> Command {
    common::pinsight_unsharded()
}

/// `pinsight yield` over the interop images, the rig log with camera
/// images and a missing input, recipes from `recipes`.
use common::{assert_same_tree, tree};

fn run_yield(out: &Path, recipes: &Path, extra: &[&str]) -> Output {
    let o = pinsight()
        .arg("yield")
        .arg(fixtures().join("images"))
        .arg(fixtures().join("logs/run-2000-images.mcap"))
        .arg("/no/such/input.png")
        .arg("-r")
        .arg(recipes)
        .args(["--jobs", "1", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.code().is_some_and(|c| c == 0 || c == 3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Every file below `dir` (relative path → bytes).
fn merge(parts: &[PathBuf], out: &Path) -> Output {
    pinsight()
        .arg("merge")
        .args(parts)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn partitioned_shards_merge_to_the_single_run_and_other_readers_agree() {
    let tmp = tempfile::tempdir().unwrap();
    let recipes = fixtures().join("images");
    let whole = tmp.path().join("whole");
    run_yield(&whole, &recipes, &["--items", "json,csv,parquet"]);
    let whole_p = tmp.path().join("whole-partitioned");
    run_yield(&whole_p, &recipes, &["--partition-by", "part,lot"]);
    assert!(
        whole_p
            .join("images/part=HDR-2x10-2.54/lot=L2026-1120-07/data.parquet")
            .is_file(),
        "hive folders of the log's lot"
    );
    assert!(!whole_p.join("images.parquet").exists());
    let n = 4;
    let shards: Vec<PathBuf> = (0..n)
        .map(|k| tmp.path().join(format!("shards/s{k}")))
        .collect();
    for (k, d) in shards.iter().enumerate() {
        run_yield(
            d,
            &recipes,
            &["--partition-by", "part,lot", "--shard", &format!("{k}/{n}")],
        );
    }
    assert!(
        tree(&shards[1])
            .keys()
            .any(|f| f.starts_with("pins/part=") && f.ends_with("/shard-1-of-4.parquet")),
        "a shard names its partition files after itself"
    );
    let merged = tmp.path().join("merged");
    let o = merge(&shards, &merged);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_same_tree(&whole_p, &merged);

    // A second run into the merged folder without Parquet leaves no stale
    // tables; with unpartitioned Parquet, no stale partition folders.
    run_yield(&merged, &recipes, &["--items", "json,csv,parquet"]);
    assert!(merged.join("images.parquet").is_file() && !merged.join("images").exists());

    // pyarrow and DuckDB, independent readers.
    let py = Command::new("python3")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/check_parquet.py"))
        .arg("yield")
        .arg(&whole)
        .arg(format!("{}/shards/s*", tmp.path().display()))
        .output()
        .expect("python3 with duckdb and pyarrow (.ci/python-requirements.txt)");
    let text = String::from_utf8_lossy(&py.stdout);
    assert!(
        py.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&py.stderr)
    );
    assert!(text.contains("ok: DuckDB yield by lot"), "{text}");
}

#[test]
fn parquet_only_items_and_the_refusals_of_merge() {
    let tmp = tempfile::tempdir().unwrap();
    let recipes = fixtures().join("images");
    let whole = tmp.path().join("whole");
    run_yield(&whole, &recipes, &["--items", "parquet"]);
    let y = std::fs::read_to_string(whole.join("yield.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&y).unwrap();
    assert!(
        v.get("items").is_none() && v["report"]["items"] == 51,
        "{y:.200}"
    );
    assert!(!whole.join("items.csv").exists() && whole.join("pins.parquet").is_file());
    let shard = |k: u32| tmp.path().join(format!("s{k}"));
    for k in 0..2 {
        run_yield(
            &shard(k),
            &recipes,
            &["--items", "parquet", "--shard", &format!("{k}/2")],
        );
    }
    let merged = tmp.path().join("merged");
    let o = merge(&[shard(0), shard(1)], &merged);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_same_tree(&whole, &merged);

    // Each refusal: exit 2, the file named, nothing written.
    let refused = |parts: &[PathBuf], want: &str| {
        let out = tmp.path().join("refused");
        let o = merge(parts, &out);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{want}: {err}");
        assert!(err.contains(want), "expected `{want}` in: {err}");
        assert!(!out.exists(), "{want}: nothing may be written");
        // An existing merged folder is left as it was.
        let before = tree(&merged);
        let o = merge(parts, &merged);
        assert_eq!(o.status.code(), Some(2));
        assert!(
            tree(&merged) == before,
            "{want}: the merged folder was touched"
        );
    };
    let copy = |from: &Path, to: &Path| {
        for (rel, bytes) in tree(from) {
            let p = to.join(rel);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, bytes).unwrap();
        }
    };
    // A missing partial.
    refused(
        &[shard(0), tmp.path().join("nowhere")],
        "nowhere: No such file",
    );
    // A corrupt partial.
    let bad = tmp.path().join("bad");
    copy(&shard(1), &bad);
    std::fs::write(bad.join("partial.json"), b"{\"header\": [1, 2").unwrap();
    refused(&[shard(0), bad.clone()], "bad/partial.json");
    // A shard's table changed after it was written.
    copy(&shard(1), &bad);
    let pins = bad.join("pins.parquet");
    let mut b = std::fs::read(&pins).unwrap();
    let mid = b.len() / 2;
    b[mid] ^= 0x55;
    std::fs::write(&pins, b).unwrap();
    refused(&[shard(0), bad.clone()], "bad/pins.parquet");
    // Another pinsight version.
    copy(&shard(1), &bad);
    let p = std::fs::read_to_string(bad.join("partial.json")).unwrap();
    let p = p.replacen(
        &format!("\"pinsight\":\"{}\"", env!("CARGO_PKG_VERSION")),
        "\"pinsight\":\"0.0.9\"",
        1,
    );
    std::fs::write(bad.join("partial.json"), p).unwrap();
    refused(&[shard(0), bad.clone()], "pinsight version 0.0.9");
    // Overlapping shards: a copy of shard 0 claiming to be shard 1.
    let twin = tmp.path().join("twin");
    copy(&shard(0), &twin);
    let p = std::fs::read_to_string(twin.join("partial.json")).unwrap();
    let p = p.replacen(
        "\"shard\":{\"k\":0,\"n\":2}",
        "\"shard\":{\"k\":1,\"n\":2}",
        1,
    );
    std::fs::write(twin.join("partial.json"), p).unwrap();
    refused(&[shard(0), twin], "the partials overlap");
    // The same shard twice.
    refused(&[shard(0), shard(0).join("partial.json")], "given twice");
    // Another recipe: the 2×10 header's position tolerance changed.
    let rec = tmp.path().join("recipes");
    copy(&recipes, &rec);
    for (name, _) in tree(&rec) {
        if !name.ends_with(".toml") {
            std::fs::remove_file(rec.join(name)).unwrap();
        }
    }
    let r = std::fs::read_to_string(rec.join("hdr-2x10.toml")).unwrap();
    std::fs::write(
        rec.join("hdr-2x10.toml"),
        r.replace("position_mm = 0.1", "position_mm = 0.12"),
    )
    .unwrap();
    let other = tmp.path().join("other-recipe");
    run_yield(&other, &rec, &["--items", "parquet", "--shard", "1/2"]);
    refused(&[shard(0), other], "other-recipe/partial.json: settings");
    // A partial of the previous format.
    copy(&shard(1), &bad);
    std::fs::write(
        bad.join("partial.json"),
        b"{\"format\": \"pinsight-yield-partial/1\", \"items\": []}",
    )
    .unwrap();
    refused(&[shard(0), bad], "pinsight-yield-partial/1");
}
