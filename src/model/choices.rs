//! The named choices of the model (model.md): the contact force law of the
//! clearance joint, how the process load acts around zero speed, and what
//! drives the crank. Each parses from and prints as the word a parameter
//! file uses.

use serde::{Deserialize, Serialize};

/// Contact force model of the clearance joint (model.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactModel {
    LankaraniNikravesh,
    Flores,
    HuntCrossley,
    Hertz,
}

impl ContactModel {
    pub const ALL: [ContactModel; 4] = [
        ContactModel::LankaraniNikravesh,
        ContactModel::Flores,
        ContactModel::HuntCrossley,
        ContactModel::Hertz,
    ];
    pub fn name(self) -> &'static str {
        match self {
            ContactModel::LankaraniNikravesh => "lankarani_nikravesh",
            ContactModel::Flores => "flores",
            ContactModel::HuntCrossley => "hunt_crossley",
            ContactModel::Hertz => "hertz",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == s.trim())
    }
    /// Hysteresis factor D for restitution `ce` (model.md).
    pub fn damping_factor(self, ce: f64) -> f64 {
        match self {
            ContactModel::LankaraniNikravesh => 3.0 * (1.0 - ce * ce) / 4.0,
            ContactModel::Flores => 8.0 * (1.0 - ce) / (5.0 * ce),
            ContactModel::HuntCrossley => 3.0 * (1.0 - ce) / 2.0,
            ContactModel::Hertz => 0.0,
        }
    }
}

/// How the process load acts around v4 = 0 (model.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProcessLaw {
    /// Smoothed like friction with the c_d ramp (default).
    Regularized,
    /// Set-valued stick law (optional refinement; not implemented yet).
    Stick,
}

impl ProcessLaw {
    pub fn name(self) -> &'static str {
        match self {
            ProcessLaw::Regularized => "regularized",
            ProcessLaw::Stick => "stick",
        }
    }
}

/// How the crank is driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Driver {
    /// θ2 = θ0 + ω t (default).
    ConstantSpeed,
    /// A motor with torque–speed curve and flywheel (the `motor` level; not
    /// implemented yet — the driver is a parameter so the level can be added
    /// without changing the file format).
    Motor,
}

impl Driver {
    pub fn name(self) -> &'static str {
        match self {
            Driver::ConstantSpeed => "constant_speed",
            Driver::Motor => "motor",
        }
    }
}
