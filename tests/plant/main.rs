//! Integration tests — line and plant: jobs, shards, Parquet, monitors, trends,
//! process faults and wear.
//!
//! One test binary per area (each module is one former test file): every
//! integration-test binary links the whole library, so 40 binaries cost
//! CI far more to build than to run (BENCHMARKS.md, "CI's own phases").
//! Run one module with `cargo test --release --test plant MODULE::`.

#[path = "../common/mod.rs"]
mod common;

mod jobs;
mod monitor;
mod parquet;
mod process_faults;
mod process_monitor;
mod shard;
mod trend;
mod wear_trend;
