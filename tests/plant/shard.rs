//! `--shard k/n` on the real binary, run as the cluster engines would run
//! it: N separate processes over the same inputs. Every input lands in
//! exactly one shard, a log's images stay together, each item's result is
//! the one a single run gives, a re-run shard writes the same bytes, and
//! `pinsight merge` of the shards' partials writes the single run's folder
//! byte for byte (its Parquet tables included).

use crate::common;

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop")
}

/// `pinsight yield` over the interop images (several recipes), a rig log
/// with camera images and a missing path, into `out`; environment cleared
/// of cluster variables so only `--shard` decides.
fn run_yield(out: &Path, shard: Option<&str>, env: &[(&str, &str)]) -> std::process::ExitStatus {
    let imgs = fixtures().join("images");
    let mut c = Command::new(env!("CARGO_BIN_EXE_pinsight"));
    c.arg("yield")
        .arg(&imgs)
        .arg(fixtures().join("logs/run-2000-images.mcap"))
        .arg("/no/such/input.png")
        .arg("-r")
        .arg(&imgs)
        .arg("--jobs")
        .arg("1")
        .args(["--items", "json,csv,parquet"])
        .arg("--out")
        .arg(out);
    for v in common::SHARD_ENV {
        c.env_remove(v);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    if let Some(s) = shard {
        c.arg("--shard").arg(s);
    }
    let o = c.output().expect("run pinsight");
    assert!(
        o.status.code().is_some_and(|c| c == 0 || c == 3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o.status
}

fn items(dir: &Path) -> (Vec<Value>, Value) {
    let v: Value = serde_json::from_slice(&std::fs::read(dir.join("yield.json")).unwrap()).unwrap();
    (v["items"].as_array().unwrap().clone(), v["report"].clone())
}

#[test]
fn eight_shards_partition_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    run_yield(&whole, None, &[]);
    let (all, all_rep) = items(&whole);
    assert!(all.len() > 40, "{}", all.len());
    let by_name: BTreeMap<String, &Value> = all
        .iter()
        .map(|i| (i["name"].as_str().unwrap().to_string(), i))
        .collect();
    assert_eq!(by_name.len(), all.len(), "names are unique");

    let n = 8;
    let mut seen: BTreeMap<String, u32> = BTreeMap::new();
    let (mut passed, mut failed, mut errors) = (0, 0, 0);
    let mut log_shards = std::collections::BTreeSet::new();
    for k in 0..n {
        let dir = tmp.path().join(format!("shard-{k}"));
        // Shard 3 from the Kubernetes environment, the others by flag.
        if k == 3 {
            run_yield(
                &dir,
                None,
                &[("JOB_COMPLETION_INDEX", "3"), ("PINSIGHT_SHARDS", "8")],
            );
        } else {
            run_yield(&dir, Some(&format!("{k}/{n}")), &[]);
        }
        let (part, rep) = items(&dir);
        assert!(!part.is_empty(), "shard {k} is empty");
        for it in &part {
            let name = it["name"].as_str().unwrap().to_string();
            assert_eq!(
                Some(&it),
                by_name.get(&name),
                "shard {k}: {name} differs from the single run"
            );
            assert!(
                seen.insert(name.clone(), k).is_none(),
                "{name} in two shards"
            );
            if it["meta"]["log"].is_string() {
                log_shards.insert(k);
            }
        }
        passed += rep["passed"].as_u64().unwrap();
        failed += rep["failed"].as_u64().unwrap();
        errors += rep["errors"].as_u64().unwrap();
    }
    assert_eq!(seen.len(), all.len(), "every item in some shard");
    assert_eq!(log_shards.len(), 1, "the log's images stay in one shard");
    assert_eq!(passed, all_rep["passed"].as_u64().unwrap());
    assert_eq!(failed, all_rep["failed"].as_u64().unwrap());
    assert_eq!(errors, all_rep["errors"].as_u64().unwrap());

    // The shards' partial results merged (as `pinsight merge` would be run
    // after the job) are the single run's folder, byte for byte: the same
    // files, the same JSON numbers, Markdown, CSV and charts.
    let merged = tmp.path().join("merged");
    let mut m = Command::new(env!("CARGO_BIN_EXE_pinsight"));
    m.arg("merge");
    // Any order of the partials; files or folders.
    for k in (0..n).rev() {
        let d = tmp.path().join(format!("shard-{k}"));
        m.arg(if k % 2 == 0 {
            d.join("partial.json")
        } else {
            d
        });
    }
    let o = m.arg("--out").arg(&merged).output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    common::assert_same_tree(&whole, &merged);
    // A merge that lacks a shard, or mixes two jobs, is refused.
    let o = Command::new(env!("CARGO_BIN_EXE_pinsight"))
        .args(["merge"])
        .args((0..n - 1).map(|k| tmp.path().join(format!("shard-{k}"))))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("7/8 missing"));

    // A failed shard re-run gives the same bytes (Slurm environment this
    // time: task 12 of an array 10-17 is shard 2/8).
    let again = tmp.path().join("again");
    run_yield(
        &again,
        None,
        &[
            ("SLURM_ARRAY_TASK_ID", "12"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ],
    );
    for f in [
        "yield.json",
        "items.csv",
        "pins.csv",
        "yield.md",
        "images.parquet",
        "pins.parquet",
        "partial.json",
    ] {
        assert_eq!(
            std::fs::read(tmp.path().join("shard-2").join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f} differs between two runs of shard 2/8"
        );
    }
}

#[test]
fn bad_shard_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    for (flag, env, want) in [
        (Some("8/8"), vec![], "out of range"),
        (Some("x/2"), vec![], "x/2"),
        (None, vec![("JOB_COMPLETION_INDEX", "1")], "PINSIGHT_SHARDS"),
    ] {
        let mut c = Command::new(env!("CARGO_BIN_EXE_pinsight"));
        c.arg("yield")
            .arg(fixtures().join("images"))
            .arg("-r")
            .arg(fixtures().join("images"))
            .arg("--out")
            .arg(tmp.path().join("o"))
            .env_remove("PINSIGHT_SHARD")
            .env_remove("SLURM_ARRAY_TASK_ID");
        for (k, v) in &env {
            c.env(k, v);
        }
        if let Some(f) = flag {
            c.arg("--shard").arg(f);
        }
        let o = c.output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag:?} {env:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want), "{flag:?}: {err}");
        assert!(!tmp.path().join("o").exists(), "nothing written");
    }
}
