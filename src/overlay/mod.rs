//! Measured against predicted, cycle by cycle, under chaos.
//!
//! - [`predict`]: the predicted ensemble (band over many simulated revolutions).
pub mod calibrate;
pub mod compare;
pub mod outputs;
pub mod predict;
