//! Mechanism model: parameters, presets, kinematics, kinetostatics, contact, clearance ODE.
