//! Shared helpers of the integration tests: the demo session with its
//! results (TUI and batch tests), a replayable random generator (fuzz tests).
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

/// A small deterministic generator (xorshift64*) for the fuzz tests, so a
/// failing random run is replayed from its seed (seed ≠ 0).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in 0..n (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The environment variables by which a job array's engines name a shard
/// (pinsight's own, Kubernetes Indexed Jobs, Slurm arrays).
pub const SHARD_ENV: [&str; 6] = [
    "PINSIGHT_SHARD",
    "PINSIGHT_SHARDS",
    "JOB_COMPLETION_INDEX",
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
];

/// The binary without [`SHARD_ENV`]: a test run inside a CI job array must
/// not shard itself.
pub fn pinsight_unsharded() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_pinsight"));
    for v in SHARD_ENV {
        c.env_remove(v);
    }
    c
}
