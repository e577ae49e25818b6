//! The motor keys of a parameter set (level `motor`, docs/motor.md): the
//! curve, the gear's efficiency, the rotor and flywheel inertia, the speed
//! controller. Plain data below `params` (which holds them) and `motor`
//! (which resolves them into a drive), so neither imports the other.

use super::choices::{MotorCurve, SpeedControl};
use super::table::Table;
use serde::{Deserialize, Serialize};

/// The motor keys of a parameter set (user units where the key has them:
/// rev/min for speeds; SI otherwise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorParams {
    pub curve: MotorCurve,
    /// Linear curve: torque at standstill (N·m, motor shaft) …
    pub stall_torque: f64,
    /// … and no-load speed (rev/min of the motor; 0 = auto: chosen so the
    /// head runs at `motor_rpm` on average).
    pub no_load_rpm: f64,
    /// Table curve: (motor rev/min, N·m), speeds strictly increasing; the
    /// torque holds its end values outside.
    pub torque_table: Table,
    /// Rotor inertia at the motor shaft, kg m².
    pub rotor_inertia: f64,
    /// Flywheel inertia on the crank shaft, kg m².
    pub flywheel_inertia: f64,
    /// Gear efficiency η.
    pub efficiency: f64,
    pub control: SpeedControl,
    /// PI gains at the motor shaft: N·m per rad/s, N·m per rad.
    pub kp: f64,
    pub ki: f64,
}

impl Default for MotorParams {
    /// A small induction-type motor on its linear curve (the no-load speed
    /// set so the head runs at `motor_rpm` on average), direct drive, no
    /// flywheel, no speed control (docs/motor.md).
    fn default() -> Self {
        Self {
            curve: MotorCurve::Linear,
            stall_torque: 2.0,
            no_load_rpm: 0.0,
            torque_table: Table::zero(),
            rotor_inertia: 2.0e-5,
            flywheel_inertia: 0.0,
            efficiency: 1.0,
            control: SpeedControl::None,
            kp: 0.02,
            ki: 0.5,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::params::Params;

    /// The motor keys: each bad value names its key and range; the
    /// relations (a table curve needs a table, PI needs kp > 0) name both
    /// keys; `auto` is 0; a table round-trips.
    #[test]
    fn motor_keys_name_key_and_range() {
        let cases: &[(&str, &str)] = &[
            ("gear_efficiency=0", "gear_efficiency"),
            ("gear_efficiency=1.2", "gear_efficiency"),
            ("motor_stall_torque_nm=-1", "motor_stall_torque_nm"),
            ("motor_stall_torque_nm=0", "motor_stall_torque_nm"),
            ("motor_no_load_rpm=0.5", "motor_no_load_rpm"),
            ("motor_no_load_rpm=-3", "motor_no_load_rpm"),
            ("flywheel_inertia_kgm2=1e5", "flywheel_inertia_kgm2"),
            ("rotor_inertia_kgm2=-1e-6", "rotor_inertia_kgm2"),
            ("speed_kp_nms=-1", "speed_kp_nms"),
            ("speed_ki_nm=nan", "speed_ki_nm"),
            ("motor_curve=cubic", "motor_curve"),
            ("speed_control=pid", "speed_control"),
            ("motor_torque_table=[[0,1],[0,2]]", "motor_torque_table"),
            ("motor_torque_table=[[0,1],[-5,2]]", "motor_torque_table"),
            ("motor_torque_table=[[0,1e6]]", "motor_torque_table"),
        ];
        for (set, key) in cases {
            let mut p = Params::paper();
            let msg = p.apply_overrides(&[*set]).unwrap_err().to_string();
            assert!(msg.contains(key) && msg.contains("allowed"), "{set}: {msg}");
        }
        let mut p = Params::paper();
        let msg = p
            .apply_overrides(&["motor_curve=table"])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("motor_torque_table"), "{msg}");
        let mut p = Params::paper();
        let msg = p
            .apply_overrides(&["speed_control=pi", "speed_kp_nms=0"])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("speed_kp_nms"), "{msg}");
        let mut p = Params::paper();
        p.apply_overrides(&[
            "driver=motor",
            "motor_no_load_rpm=0",
            "motor_curve=table",
            "motor_torque_table=[[0, 2.5], [1000, 1.0], [1500, 0]]",
            "flywheel_inertia_kgm2=0.01",
        ])
        .unwrap();
        let q = Params::from_toml_str(&p.to_toml()).unwrap();
        assert_eq!(p, q);
    }
}
