//! Plant scale: one batch split across the machines of a cluster.
//!
//! `shard` holds the partition of a batch's inputs (`--shard k/n` and its
//! defaults from Kubernetes Indexed Jobs and Slurm arrays). It knows nothing
//! of the terminal; the commands call it on the list they already collected.
//! `merge` holds a shard's partial result (`partial.json`) and the exact
//! merge of a job's partials (`pinsight merge`).

pub mod merge;
pub mod shard;
