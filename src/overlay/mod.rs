//! Measured against predicted, cycle by cycle, under chaos.
//!
//! - [`predict`]: the predicted ensemble (band over many simulated revolutions).
pub mod predict;
pub mod compare;
pub mod calibrate;
