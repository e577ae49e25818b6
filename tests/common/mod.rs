//! Shared helpers of the TUI and batch tests.
#![allow(dead_code)]

use pinsight::panes::Session;
use pinsight::sim::sweep::SweepGrid;

/// The demo session with every result the panes show computed in line:
/// the model (paper preset, clearance level), a small study (2 × 2 × 2
/// cases, 1 + 1 revolutions), the first image's inspection, the batch
/// yield, the overlay of the demo log (and, with methods, the quick
/// methods lab).
pub fn full_session() -> Session {
    let mut s = Session::demo();
    s.display = Some("test display".into());
    s.run_model_now();
    assert!(s.model_error.is_none(), "{:?}", s.model_error);
    s.study_setup.grid = SweepGrid {
        clearances_mm: vec![0.1, 0.5],
        speeds_rpm: vec![1200.0, 1800.0],
        materials: vec!["alloy_steel".into(), "aluminium".into()],
    };
    s.study_setup.warmup = 1.0;
    s.study_setup.revs = 1.0;
    s.run_study_now();
    s.inspect_now(0);
    s.run_yield_now();
    s.run_overlay_now(0);
    s
}

/// `full_session` plus the methods lab (seconds).
pub fn full_session_with_methods() -> Session {
    let mut s = full_session();
    s.run_methods_now();
    s
}
