//! Integration tests — the application's one engine under three faces:
//! architecture rules, batch and CI reports, atomic outputs, the TUI's state
//! machine.
//!
//! One test binary per area (each module is one former test file): every
//! integration-test binary links the whole library, so 40 binaries cost
//! CI far more to build than to run (BENCHMARKS.md, "CI's own phases").
//! Run one module with `cargo test --release --test app MODULE::`.

mod architecture;
mod batch_ci;
mod one_path;
mod output_atomic;
mod output_atomic_all;
mod tui_app;
