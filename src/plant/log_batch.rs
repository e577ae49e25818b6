//! Many rig logs through a one-log job (`overlay`, `calibrate`), sharded:
//! the logs named (files, and folders' `*.mcap` files, sorted) and the
//! inputs that are not there, this shard's part of them, and a folder
//! name for each log that does not depend on the shard (its file stem;
//! `stem-<place>` when two logs of the job share a stem).
//!
//! These jobs have no aggregate over logs, so nothing is merged: each
//! shard writes its logs' folders, and the shards' folders together hold
//! every log once.

use super::shard::{Shard, split_list};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// One input of the batch: a log, or a named input that is not there.
#[derive(Debug, Clone)]
pub struct BatchLog {
    pub path: PathBuf,
    /// Its folder name in `--out`.
    pub name: String,
    /// Why it cannot be read, when it is not there.
    pub missing: Option<String>,
}

/// This shard's logs, in the job's order.
pub fn log_batch(shard: Shard, inputs: &[PathBuf]) -> Vec<BatchLog> {
    let (files, errors) = crate::engine::trend::collect_logs(inputs);
    let stem = |p: &PathBuf| {
        p.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "log".into())
    };
    let mut all: Vec<BatchLog> = files
        .iter()
        .map(|f| BatchLog {
            path: f.clone(),
            name: stem(f),
            missing: None,
        })
        .chain(errors.into_iter().map(|e| BatchLog {
            path: PathBuf::from(&e.file),
            name: stem(&PathBuf::from(&e.file)),
            missing: Some(e.error),
        }))
        .collect();
    let mut count: BTreeMap<String, usize> = BTreeMap::new();
    for l in &all {
        *count.entry(l.name.clone()).or_default() += 1;
    }
    for (i, l) in all.iter_mut().enumerate() {
        if count[&l.name] > 1 {
            l.name = format!("{}-{i}", l.name);
        }
    }
    split_list(shard, all, |l| l.path.display().to_string()).kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_do_not_depend_on_the_shard() {
        let d = tempfile::tempdir().unwrap();
        for sub in ["a", "b"] {
            std::fs::create_dir_all(d.path().join(sub)).unwrap();
            for f in ["run.mcap", &format!("{sub}-only.mcap")] {
                std::fs::write(d.path().join(sub).join(f), b"x").unwrap();
            }
        }
        let inputs = vec![
            d.path().join("a"),
            d.path().join("b"),
            d.path().join("gone.mcap"),
        ];
        let whole = log_batch(Shard::WHOLE, &inputs);
        let names: Vec<&str> = whole.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, vec!["a-only", "run-1", "b-only", "run-3", "gone"]);
        assert!(whole[4].missing.is_some());
        let mut from_shards: Vec<(PathBuf, String)> = (0..2)
            .flat_map(|k| log_batch(Shard::new(k, 2).unwrap(), &inputs))
            .map(|l| (l.path, l.name))
            .collect();
        let mut want: Vec<(PathBuf, String)> =
            whole.into_iter().map(|l| (l.path, l.name)).collect();
        from_shards.sort();
        want.sort();
        assert_eq!(
            from_shards, want,
            "each log once, named as in the whole run"
        );
    }
}
