//! Integration tests — clearance dynamics: closed forms, convergence, the
//! Flores benchmark, parameters, calibration coverage, the CLI.
//!
//! One test binary per area (each module is one former test file): every
//! integration-test binary links the whole library, so 40 binaries cost
//! CI far more to build than to run (BENCHMARKS.md, "CI's own phases").
//! Run one module with `cargo test --release --test dynamics MODULE::`.

#[path = "../common/mod.rs"]
mod common;

mod calibration_coverage;
mod cli;
mod evidence;
mod flores_benchmark;
mod params_fuzz;
