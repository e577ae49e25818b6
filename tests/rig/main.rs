//! Integration tests — rig logs: readers of every encoding, interop logs from
//! other tools' writers, bad input, overlays, export, the CLI.
//!
//! One test binary per area (each module is one former test file): every
//! integration-test binary links the whole library, so 40 binaries cost
//! CI far more to build than to run (BENCHMARKS.md, "CI's own phases").
//! Run one module with `cargo test --release --test rig MODULE::`.

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod cli;
mod export_mcap;
mod fuzz_readers;
mod images;
mod interop;
mod overlay;
mod synth;
mod twins;
