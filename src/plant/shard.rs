//! `--shard k/n`: which part of a batch this process runs.
//!
//! The partition is by **rank in the sorted list of units**, dealt round
//! robin: unit `i` of the sorted list belongs to shard `i mod n`. A unit is
//! an input file, or a whole rig log (every camera image inside a log goes
//! with its log, so a log is opened by one shard only). Rank rather than a
//! hash of the name because it balances exactly (shard sizes differ by at
//! most one unit) and because every shard of a job sees the same input list
//! (the same mounted folder), so rank is as stable as a hash there; a hash
//! would only help when shards saw different lists, which a merge must
//! refuse anyway. Sorting (byte order of the name) makes the partition
//! independent of the order the inputs were named in.
//!
//! `k` counts from 0, like `JOB_COMPLETION_INDEX` and a Slurm array
//! `--array=0-(n-1)`. Without `--shard` the environment decides:
//! - Kubernetes Indexed Job: `JOB_COMPLETION_INDEX` is the index; Kubernetes
//!   does not export the completions count to the pod, so the manifest sets
//!   `PINSIGHT_SHARDS` to the same number as `spec.completions`.
//! - Slurm array: `SLURM_ARRAY_TASK_ID` minus `SLURM_ARRAY_TASK_MIN` (0 when
//!   unset) is the index, `SLURM_ARRAY_TASK_COUNT` the count.
//! - `PINSIGHT_SHARD=k/n` overrides both (and `--shard` overrides all).
//!
//! With none of them the batch is whole (`0/1`).

use crate::vision::batch::{Item, ItemResult};
use std::collections::{BTreeMap, HashMap};
use std::fmt;

/// Shard `k` of `n` (0 ≤ k < n).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub k: u32,
    pub n: u32,
}

impl Shard {
    /// The whole batch.
    pub const WHOLE: Shard = Shard { k: 0, n: 1 };

    pub fn new(k: u32, n: u32) -> Result<Shard, String> {
        if n == 0 {
            return Err("shard count must be at least 1".into());
        }
        if k >= n {
            return Err(format!(
                "shard index {k} out of range: shards count from 0 to {} for {n} shards",
                n - 1
            ));
        }
        Ok(Shard { k, n })
    }

    /// Parses `k/n`.
    pub fn parse(s: &str) -> Result<Shard, String> {
        let (k, n) = s
            .trim()
            .split_once('/')
            .ok_or_else(|| format!("shard `{s}`: expected k/n, e.g. 0/8"))?;
        let k: u32 = k
            .trim()
            .parse()
            .map_err(|_| format!("shard `{s}`: index `{k}` is not a whole number"))?;
        let n: u32 = n
            .trim()
            .parse()
            .map_err(|_| format!("shard `{s}`: count `{n}` is not a whole number"))?;
        Shard::new(k, n).map_err(|e| format!("shard `{s}`: {e}"))
    }

    /// The shard from the environment (see the module doc), `None` when no
    /// engine variable is set.
    pub fn from_env_vars(get: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, String> {
        if let Some(s) = get("PINSIGHT_SHARD") {
            return Shard::parse(&s)
                .map(Some)
                .map_err(|e| format!("PINSIGHT_SHARD: {e}"));
        }
        let num = |var: &str| -> Result<Option<u32>, String> {
            match get(var) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse::<u32>()
                    .map(Some)
                    .map_err(|_| format!("{var}=`{v}` is not a whole number")),
            }
        };
        if let Some(k) = num("JOB_COMPLETION_INDEX")? {
            let n = num("PINSIGHT_SHARDS")?.ok_or_else(|| {
                "JOB_COMPLETION_INDEX is set but PINSIGHT_SHARDS is not: Kubernetes does not \
                 tell a pod the completions count; set PINSIGHT_SHARDS to spec.completions"
                    .to_string()
            })?;
            return Shard::new(k, n)
                .map(Some)
                .map_err(|e| format!("JOB_COMPLETION_INDEX/PINSIGHT_SHARDS: {e}"));
        }
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let n = num("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
                "SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not".to_string()
            })?;
            let k = id.checked_sub(min).ok_or_else(|| {
                format!("SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}")
            })?;
            return Shard::new(k, n)
                .map(Some)
                .map_err(|e| format!("SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT: {e}"));
        }
        Ok(None)
    }

    /// `--shard` if given, else the environment, else the whole batch.
    pub fn resolve(flag: Option<&str>) -> Result<Shard, String> {
        match flag {
            Some(s) => Shard::parse(s),
            None => Ok(Shard::from_env_vars(|v| std::env::var(v).ok())?.unwrap_or(Shard::WHOLE)),
        }
    }

    pub fn is_whole(&self) -> bool {
        self.n == 1
    }

    /// Which of `units` (keys, any order, repeats allowed) belong to this
    /// shard: `keep[i]` for `units[i]`. Rank in the sorted distinct keys,
    /// round robin (module doc).
    pub fn select<S: AsRef<str>>(&self, units: &[S]) -> Vec<bool> {
        let ranks: BTreeMap<&str, ()> = units.iter().map(|u| (u.as_ref(), ())).collect();
        let rank: HashMap<&str, usize> = ranks.keys().enumerate().map(|(i, k)| (*k, i)).collect();
        units
            .iter()
            .map(|u| rank[u.as_ref()] % self.n as usize == self.k as usize)
            .collect()
    }
}

/// The unit a collected item belongs to: its rig log, else its own name.
pub fn unit_of_item(item: &Item) -> &str {
    item.meta.log.as_deref().unwrap_or(&item.name)
}

/// The unit of an input that failed to be collected (a missing path, a log
/// that cannot be opened): its log if known, else its name.
pub fn unit_of_result(r: &ItemResult) -> &str {
    r.meta.log.as_deref().unwrap_or(&r.name)
}

/// Keeps this shard's part of what `vision::batch::collect_items` returned
/// (images and inputs that failed), each list in its own order. The units
/// of both lists are ranked together, so a failed input counts in exactly
/// one shard like any other.
pub fn split_collected(
    shard: Shard,
    items: Vec<Item>,
    errors: Vec<ItemResult>,
) -> (Vec<Item>, Vec<ItemResult>) {
    let p = split_collected_part(shard, items, errors);
    (p.items, p.errors)
}

/// A shard's part of a collected batch, and what a merge must know of the
/// whole batch.
#[derive(Debug)]
pub struct ShardPart {
    pub items: Vec<Item>,
    pub errors: Vec<ItemResult>,
    /// Where each kept input stands in the whole batch's order — the order
    /// a single run inspects them in: the inputs that failed first, then
    /// the images (`errors` first, then `items`).
    pub orders: Vec<u64>,
    /// Distinct units of the whole batch.
    pub units: u64,
    /// SHA-256 (hex) of the whole batch's sorted distinct unit names, one
    /// per line: the identity of the input list every shard of a job saw.
    pub digest: String,
}

/// [`split_collected`] with the positions and the batch's identity.
pub fn split_collected_part(shard: Shard, items: Vec<Item>, errors: Vec<ItemResult>) -> ShardPart {
    let units: Vec<String> = errors
        .iter()
        .map(unit_of_result)
        .chain(items.iter().map(unit_of_item))
        .map(str::to_string)
        .collect();
    let (n_units, digest) = units_digest(&units);
    let keep = shard.select(&units);
    let (ke, ki) = keep.split_at(errors.len());
    let e0 = errors.len();
    let mut orders: Vec<u64> = (0..e0).filter(|&i| ke[i]).map(|i| i as u64).collect();
    orders.extend((0..items.len()).filter(|&i| ki[i]).map(|i| (e0 + i) as u64));
    let items = items
        .into_iter()
        .zip(ki)
        .filter_map(|(i, &k)| k.then_some(i))
        .collect();
    let errors = errors
        .into_iter()
        .zip(ke)
        .filter_map(|(e, &k)| k.then_some(e))
        .collect();
    ShardPart {
        items,
        errors,
        orders,
        units: n_units,
        digest,
    }
}

/// The identity of a list of units: their number and the SHA-256 (hex) of
/// the sorted distinct names, one per line.
pub fn units_digest<S: AsRef<str>>(units: &[S]) -> (u64, String) {
    use sha2::Digest;
    let distinct: std::collections::BTreeSet<&str> = units.iter().map(|u| u.as_ref()).collect();
    let mut h = sha2::Sha256::new();
    for u in &distinct {
        h.update(u.as_bytes());
        h.update(b"\n");
    }
    let digest = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
    (distinct.len() as u64, digest)
}

/// A shard's part of any list of inputs (logs, grid cases …): the kept
/// entries in the list's order, each one's place in the whole list, and
/// the whole list's identity.
#[derive(Debug)]
pub struct Part<T> {
    pub kept: Vec<T>,
    pub orders: Vec<u64>,
    pub units: u64,
    pub digest: String,
}

/// Keeps this shard's entries of `list`; `unit` names an entry's unit
/// (entries with one name go to one shard).
pub fn split_list<T>(shard: Shard, list: Vec<T>, unit: impl Fn(&T) -> String) -> Part<T> {
    let units: Vec<String> = list.iter().map(&unit).collect();
    let (n, digest) = units_digest(&units);
    let keep = shard.select(&units);
    let mut kept = Vec::new();
    let mut orders = Vec::new();
    for (i, (t, k)) in list.into_iter().zip(keep).enumerate() {
        if k {
            kept.push(t);
            orders.push(i as u64);
        }
    }
    Part {
        kept,
        orders,
        units: n,
        digest,
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn parse_and_refuse() {
        assert_eq!(Shard::parse("3/8").unwrap(), Shard { k: 3, n: 8 });
        assert_eq!(Shard::parse(" 0 / 1 ").unwrap(), Shard::WHOLE);
        for bad in ["8/8", "1/0", "a/2", "3", "-1/4", "1/x"] {
            let e = Shard::parse(bad).unwrap_err();
            assert!(e.contains(bad), "{bad}: {e}");
        }
    }

    #[test]
    fn environment_of_kubernetes_and_slurm() {
        assert_eq!(Shard::from_env_vars(env(&[])).unwrap(), None);
        let k8s = [("JOB_COMPLETION_INDEX", "5"), ("PINSIGHT_SHARDS", "8")];
        assert_eq!(
            Shard::from_env_vars(env(&k8s)).unwrap(),
            Some(Shard { k: 5, n: 8 })
        );
        let e = Shard::from_env_vars(env(&[("JOB_COMPLETION_INDEX", "5")])).unwrap_err();
        assert!(e.contains("PINSIGHT_SHARDS"), "{e}");
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "12"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(
            Shard::from_env_vars(env(&slurm)).unwrap(),
            Some(Shard { k: 2, n: 4 })
        );
        let over = [("PINSIGHT_SHARD", "1/2"), ("SLURM_ARRAY_TASK_ID", "3")];
        assert_eq!(
            Shard::from_env_vars(env(&over)).unwrap(),
            Some(Shard { k: 1, n: 2 })
        );
        let e = Shard::from_env_vars(env(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]))
        .unwrap_err();
        assert!(e.contains("out of range"), "{e}");
    }

    #[test]
    fn shards_cover_every_unit_once_and_balance() {
        // Units named out of order, a log's images repeated under one key.
        let units: Vec<String> = (0..23)
            .rev()
            .map(|i| format!("img-{i:02}.png"))
            .chain(std::iter::repeat_n("run.mcap".to_string(), 5))
            .collect();
        let n = 4;
        let mut owner = vec![None; units.len()];
        let mut sizes = vec![0usize; n];
        for k in 0..n as u32 {
            let keep = Shard::new(k, n as u32).unwrap().select(&units);
            for (i, &kp) in keep.iter().enumerate() {
                if kp {
                    assert_eq!(owner[i], None, "unit {i} in two shards");
                    owner[i] = Some(k);
                    if units[i] != "run.mcap" {
                        sizes[k as usize] += 1;
                    }
                }
            }
        }
        assert!(owner.iter().all(Option::is_some));
        // The log's five images all went to one shard.
        let log: Vec<_> = (23..28).map(|i| owner[i]).collect();
        assert!(log.iter().all(|o| *o == log[0]));
        // 24 distinct units over 4 shards: 6 each (23 files + the log).
        let units_per_shard: Vec<usize> = (0..n)
            .map(|k| sizes[k] + usize::from(log[0] == Some(k as u32)))
            .collect();
        assert_eq!(units_per_shard, vec![6; 4]);
        // Sorted rank, not input order: img-00 (rank 0) is shard 0.
        assert_eq!(owner[22], Some(0));
        // Same answer for a reordered list.
        let mut rev = units.clone();
        rev.reverse();
        let a = Shard::new(1, 4).unwrap().select(&units);
        let b = Shard::new(1, 4).unwrap().select(&rev);
        let mut b_back = b.clone();
        b_back.reverse();
        assert_eq!(a, b_back);
    }
}
