//! Integration tests — connector vision: the pipeline on our generator's
//! images, the envelope sets of both renderers, the interop images, the CLI and
//! bad input.
//!
//! One test binary per area (each module is one former test file): every
//! integration-test binary links the whole library, so 40 binaries cost
//! CI far more to build than to run (BENCHMARKS.md, "CI's own phases").
//! Run one module with `cargo test --release --test vision MODULE::`.

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod blurred_tip_areas;
mod blurred_tip_centres;
mod cli;
mod envelope;
mod extras;
mod faint_and_clipped;
mod fixtures;
mod grid_on_the_tips;
mod housing_edges;
mod interop;
mod one_tip;
mod python_envelope;
mod side;
mod synth;
mod tips_beside_structure;
