//! The parameter table: every key a parameter file or `--set` may use,
//! with its meaning, unit, allowed range in words ([`PARAM_SPECS`], what
//! `--set help` and the Model pane list) and in numbers
//! ([`physical_range`], what validation enforces). A test keeps the two in
//! step.

use serde::Serialize;

/// One user-visible parameter key.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ParamSpec {
    pub key: &'static str,
    /// What it is (with the symbol of model.md).
    pub help: &'static str,
    /// Allowed values, in words.
    pub range: &'static str,
    /// Group for listings: geometry, masses, joint, contact, friction, drive, process, environment.
    pub group: &'static str,
}

const fn ps(
    key: &'static str,
    help: &'static str,
    range: &'static str,
    group: &'static str,
) -> ParamSpec {
    ParamSpec {
        key,
        help,
        range,
        group,
    }
}

/// Every parameter key, in listing order.
pub const PARAM_SPECS: &[ParamSpec] = &[
    ps("r_mm", "crank length r", "0.1 … 1000 mm", "geometry"),
    ps(
        "l_mm",
        "connecting rod length l",
        "0.1 … 5000 mm, > r_mm + |offset_mm|",
        "geometry",
    ),
    ps(
        "offset_mm",
        "offset of the pin bar's line of motion",
        "−1000 … 1000 mm, |offset| < l − r",
        "geometry",
    ),
    ps("m2_kg", "crank mass m2", "0 … 1000 kg", "masses"),
    ps(
        "lc2_mm",
        "crank centroid distance Lc2",
        "0 … 1000 mm",
        "masses",
    ),
    ps(
        "i2_kgm2",
        "crank inertia I2 about its centroid",
        "0 … 100 kg m²",
        "masses",
    ),
    ps(
        "m3_kg",
        "connecting rod mass m3",
        "1e-4 … 1000 kg",
        "masses",
    ),
    ps(
        "lc3_mm",
        "rod centroid distance Lc3 from the crank pin",
        "0 … 5000 mm, ≤ l_mm",
        "masses",
    ),
    ps(
        "i3_kgm2",
        "rod inertia I3 about its centroid",
        "0 … 100 kg m²",
        "masses",
    ),
    ps("m4_kg", "pin bar mass m4", "1e-4 … 1000 kg", "masses"),
    ps(
        "rj_mm",
        "journal radius R_J (bearing R_B = R_J + c)",
        "0.1 … 500 mm",
        "joint",
    ),
    ps(
        "clearance_mm",
        "radial clearance c of the rod–pin-bar joint",
        "0 (ideal joint) or 1e-4 … 10 mm",
        "joint",
    ),
    ps(
        "material",
        "material of journal and bearing",
        "alloy_steel, stainless_steel, aluminium, copper, tungsten_carbide",
        "joint",
    ),
    ps(
        "journal_material",
        "journal material",
        "alloy_steel, stainless_steel, aluminium, copper, tungsten_carbide",
        "joint",
    ),
    ps(
        "bearing_material",
        "bearing material",
        "alloy_steel, stainless_steel, aluminium, copper, tungsten_carbide",
        "joint",
    ),
    ps(
        "journal_e_gpa",
        "journal Young's modulus E",
        "0.1 … 1500 GPa",
        "joint",
    ),
    ps(
        "journal_nu",
        "journal Poisson's ratio ν",
        "−0.999 … 0.499",
        "joint",
    ),
    ps(
        "bearing_e_gpa",
        "bearing Young's modulus E",
        "0.1 … 1500 GPa",
        "joint",
    ),
    ps(
        "bearing_nu",
        "bearing Poisson's ratio ν",
        "−0.999 … 0.499",
        "joint",
    ),
    ps(
        "contact_model",
        "contact force model",
        "lankarani_nikravesh, flores, hunt_crossley, hertz",
        "contact",
    ),
    ps(
        "restitution",
        "coefficient of restitution ce",
        "1e-3 … 1",
        "contact",
    ),
    ps(
        "approach_velocity_floor_mps",
        "floor on the onset approach velocity δ̇⁻",
        "1e-9 … 10 m/s",
        "contact",
    ),
    ps("c_f", "joint friction coefficient c_f", "0 … 2", "friction"),
    ps(
        "mu_g",
        "guide friction coefficient μ_g",
        "0 … 0.99",
        "friction",
    ),
    ps(
        "friction_v0_mps",
        "friction smoothing: c_d = 0 below v0",
        "0 … 10 m/s",
        "friction",
    ),
    ps(
        "friction_v1_mps",
        "friction smoothing: c_d = 1 above v1",
        "1e-9 … 10 m/s, > friction_v0_mps",
        "friction",
    ),
    ps("motor_rpm", "motor speed", "1e-9 … 60000 rev/min", "drive"),
    ps(
        "gear_ratio",
        "motor revolutions per crank revolution",
        "1e-3 … 1000",
        "drive",
    ),
    ps("driver", "crank driver", "constant_speed, motor", "drive"),
    ps(
        "motor_curve",
        "motor torque–speed curve: linear T = T_stall (1 − ω/ω0), or the table",
        "linear, table",
        "drive",
    ),
    ps(
        "motor_stall_torque_nm",
        "linear curve: torque at standstill T_stall, at the motor shaft",
        "1e-6 … 1e5 N·m",
        "drive",
    ),
    ps(
        "motor_no_load_rpm",
        "linear curve: no-load speed ω0 of the motor",
        "0 (auto: the head runs at motor_rpm on average) or 1 … 1e5 rev/min",
        "drive",
    ),
    ps(
        "motor_torque_table",
        "table curve: motor torque against motor speed, [[rpm, N·m], …]",
        "speeds 0 … 1e5 rev/min strictly increasing, torques −1e5 … 1e5 N·m",
        "drive",
    ),
    ps(
        "rotor_inertia_kgm2",
        "motor rotor inertia at the motor shaft (referred to the crank × gear_ratio²)",
        "0 … 100 kg m²",
        "drive",
    ),
    ps(
        "flywheel_inertia_kgm2",
        "flywheel inertia on the crank shaft",
        "0 … 1e4 kg m²",
        "drive",
    ),
    ps(
        "gear_efficiency",
        "gear efficiency η (torque × η driving, ÷ η braking)",
        "0.05 … 1",
        "drive",
    ),
    ps(
        "speed_control",
        "motor torque command: none (on its curve) or a PI speed controller within the curve",
        "none, pi",
        "drive",
    ),
    ps(
        "speed_kp_nms",
        "PI speed controller: proportional gain, N·m per rad/s of motor speed error",
        "0 … 1e6 N·m·s",
        "drive",
    ),
    ps(
        "speed_ki_nm",
        "PI speed controller: integral gain, N·m per rad of motor angle error",
        "0 … 1e6 N·m",
        "drive",
    ),
    ps(
        "standoff_mm",
        "stroke at which the pin meets the part",
        "0 … 1000 mm",
        "process",
    ),
    ps(
        "f_ins_table",
        "insertion force against depth, [[mm, N], …]",
        "depths 0 … 1000 mm strictly increasing, forces 0 … 1e6 N",
        "process",
    ),
    ps(
        "f_wd_table",
        "withdrawal force against depth, [[mm, N], …]",
        "depths 0 … 1000 mm strictly increasing, forces 0 … 1e6 N",
        "process",
    ),
    ps(
        "process_law",
        "process load law",
        "regularized, stick",
        "process",
    ),
    ps(
        "gravity_mps2",
        "gravity vector [x, y] (x = insertion direction)",
        "two numbers within ±1000 m/s²",
        "environment",
    ),
];

/// The spec of a key.
pub fn spec(key: &str) -> Option<&'static ParamSpec> {
    PARAM_SPECS.iter().find(|s| s.key == key)
}

/// Whether `x` lies in [lo, hi], allowing for the rounding of a unit
/// conversion (a bound met in metres may come back a few ulps outside it
/// in millimetres).
pub fn within(x: f64, lo: f64, hi: f64) -> bool {
    let slack = 1e-12;
    x >= lo - slack * lo.abs() && x <= hi + slack * hi.abs()
}

/// The physical range of a numeric key in its user units (inclusive), for
/// every key that is a number. Values outside are refused with the range
/// named: they describe no pin-insertion head, and some (a clearance of
/// 1e-300 mm, a speed of 1e308 rpm) would only make the integrator spin.
/// A positive clearance below 0.1 µm is indistinguishable from the ideal
/// joint (use 0) and would make every free-flight step vanish.
pub fn physical_range(key: &str) -> Option<(f64, f64)> {
    Some(match key {
        "r_mm" => (0.1, 1000.0),
        "l_mm" => (0.1, 5000.0),
        "offset_mm" => (-1000.0, 1000.0),
        "m2_kg" | "m3_kg" | "m4_kg" => (if key == "m2_kg" { 0.0 } else { 1e-4 }, 1000.0),
        "lc2_mm" => (0.0, 1000.0),
        "lc3_mm" => (0.0, 5000.0),
        "i2_kgm2" | "i3_kgm2" => (0.0, 100.0),
        "rj_mm" => (0.1, 500.0),
        "clearance_mm" => (1e-4, 10.0),
        "journal_e_gpa" | "bearing_e_gpa" => (0.1, 1500.0),
        "journal_nu" | "bearing_nu" => (-0.999, 0.499),
        "restitution" => (1e-3, 1.0),
        "approach_velocity_floor_mps" => (1e-9, 10.0),
        "c_f" => (0.0, 2.0),
        "mu_g" => (0.0, 0.99),
        "friction_v0_mps" => (0.0, 10.0),
        "friction_v1_mps" => (1e-9, 10.0),
        "motor_rpm" => (1e-9, 60000.0),
        "gear_ratio" => (1e-3, 1000.0),
        "standoff_mm" => (0.0, 1000.0),
        "motor_stall_torque_nm" => (1e-6, 1e5),
        "motor_no_load_rpm" => (1.0, 1e5),
        "rotor_inertia_kgm2" => (0.0, 100.0),
        "flywheel_inertia_kgm2" => (0.0, 1e4),
        "gear_efficiency" => (0.05, 1.0),
        "speed_kp_nms" | "speed_ki_nm" => (0.0, 1e6),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmt::fmt_num;

    /// The words of every numeric key's range name its numeric bounds.
    #[test]
    fn range_words_and_numbers_agree() {
        let mut numeric = 0;
        for s in PARAM_SPECS {
            if let Some((lo, hi)) = physical_range(s.key) {
                numeric += 1;
                for b in [lo, hi] {
                    // Written as a person writes it: 1e-4 for 0.0001, − for -.
                    let sci = format!("{b:e}");
                    let forms = [
                        fmt_num(b),
                        fmt_num(b).replace('-', "−"),
                        sci.replace('-', "−"),
                        sci,
                    ];
                    assert!(
                        forms.iter().any(|f| s.range.contains(f.as_str())),
                        "{}: range text `{}` does not name {}",
                        s.key,
                        s.range,
                        fmt_num(b)
                    );
                }
            }
        }
        assert!(numeric >= 20, "{numeric} numeric keys");
    }
}
