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
    /// Set-valued stick law: the pin bar is held at rest while the other
    /// forces stay within −F_wd … F_ins (stick/slip located as events).
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
    /// A motor with torque–speed curve, gear and flywheel: θ2 is free
    /// (the `motor` level; the lower levels run at its operating speed).
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

/// The motor's torque–speed curve (`motor_curve`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotorCurve {
    /// T = T_stall (1 − ω/ω0) (default).
    Linear,
    /// Piecewise linear in motor speed (`motor_torque_table`).
    Table,
}

impl MotorCurve {
    pub fn name(self) -> &'static str {
        match self {
            MotorCurve::Linear => "linear",
            MotorCurve::Table => "table",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim() {
            "linear" => Some(MotorCurve::Linear),
            "table" => Some(MotorCurve::Table),
            _ => None,
        }
    }
}

/// How the motor's torque is commanded (`speed_control`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedControl {
    /// The motor runs on its curve (an induction motor on a fixed
    /// frequency, a DC motor on a fixed voltage) (default).
    None,
    /// A PI speed controller (a servo drive) commands the torque within
    /// the curve's envelope, with back-calculation anti-windup.
    Pi,
}

impl SpeedControl {
    pub fn name(self) -> &'static str {
        match self {
            SpeedControl::None => "none",
            SpeedControl::Pi => "pi",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim() {
            "none" => Some(SpeedControl::None),
            "pi" => Some(SpeedControl::Pi),
            _ => None,
        }
    }
}
