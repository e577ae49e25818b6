//! Plant scale: one batch split across the machines of a cluster, and its
//! parts merged back exactly (issue 19, docs/scale.md).
//!
//! - `shard`: the `--shard k/n` partition of a batch's inputs (defaults
//!   from Kubernetes Indexed Jobs and Slurm arrays). It knows nothing of
//!   the terminal; the commands and engine jobs call it on the list they
//!   already collected.
//! - `partial`: what every shard's `partial.json` says about its job (the
//!   header a merge checks) and the checks of the files it refers to.
//! - `yields`: a yield folder's files (report, per-item outputs, Parquet)
//!   for a run, a shard and a merge alike, and the yield merge.
//! - `monitor`: the same for `monitor` (its partial: every log's verdicts
//!   and values, as the SPC's charts need them in order).
//! - `sweep`: the same for `sweep` (the grid's cases dealt round robin).
//! - `trend`: the same for `trend` (its partial: the calibrated history
//!   points; the merge fits them).
//! - `log_batch`: many logs through a one-log job (`overlay`,
//!   `calibrate`), sharded; nothing to merge (no aggregate over logs).
//! - `merge`: `pinsight merge` — reads and checks a job's partials and
//!   calls that job's merge.

pub mod log_batch;
pub mod merge;
pub mod monitor;
pub mod partial;
pub mod shard;
pub mod sweep;
pub mod trend;
pub mod yields;
