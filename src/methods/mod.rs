//! The methods lab: speed against accuracy, where methods fail, and the
//! fidelity each scene needs — a product feature (`pinsight methods`, the
//! Methods pane), computed as plain tables and chart descriptions.
//!
//! - [`dynamics`]: work–precision of every integrator against a reference
//!   in the deterministic window, an outside reference (the `ode_solvers`
//!   crate) on the same right-hand side, stability limits of the fixed-step
//!   methods (measured, beside the linear-stability prediction from the
//!   contact frequency), what the long run can promise (prediction horizon
//!   and the convergence of ensemble statistics with the tolerance), where
//!   adaptive methods spend their steps and how methods fail, and the
//!   fidelity chosen across the study grid.
//! - the vision part lives with the vision pipeline (`vision::lab`).

pub mod dynamics;
pub mod stability;

use serde::{Deserialize, Serialize};

/// How much work a lab run does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effort {
    /// Seconds: a couple of scenes and settings (CI, the TUI's first view).
    Quick,
    /// Minutes: every scene and setting (the report).
    Full,
}

impl Effort {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "quick" => Some(Effort::Quick),
            "full" => Some(Effort::Full),
            _ => None,
        }
    }
}
