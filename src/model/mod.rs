//! Mechanism model: parameters, presets, kinematics, kinetostatics, contact, clearance ODE.

pub mod choices;
pub mod clearance;

pub mod contact;
pub mod joint_model;
pub mod kinematics;
pub mod kinetostatics;
pub mod materials;
pub mod motor;
pub mod motor_clearance;
pub mod motor_params;
pub mod motor_rigid;
pub mod param_error;
pub mod param_table;
pub mod param_value;
pub mod params;
pub mod sincos;
pub mod table;

pub use params::{ContactModel, ParamError, Params};
