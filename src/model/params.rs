//! Mechanism parameters: presets, the key registry shared by parameter files,
//! `--set key=value` overrides and the TUI's Model pane, and validation.
//!
//! Values are stored in SI units. Every key a user sees carries its unit in
//! its name (`clearance_mm`, `m4_kg`, `motor_rpm` …); [`PARAM_SPECS`] lists them
//! with their unit, meaning and allowed range, and [`Params::set`] converts and
//! checks one value. A parameter file is a flat TOML table of such keys, with
//! an optional `preset = "paper" | "flores"` as its base.

use super::materials::Material;
pub use super::motor_params::MotorParams;
pub use super::param_table::{PARAM_SPECS, ParamSpec, physical_range, spec, within};
use super::table::Table;
pub use crate::fmt::fmt_num;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub use super::choices::{ContactModel, Driver, MotorCurve, ProcessLaw, SpeedControl};
pub use super::param_error::ParamError;
use super::param_value::pairs;
pub use super::param_value::{ParamValue, parse_value_text};
use crate::fmt::toml_value as show;

/// All parameters of the mechanism, in SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// The preset these parameters started from.
    pub preset: String,
    /// Crank length r, m.
    pub r: f64,
    /// Connecting rod length l, m.
    pub l: f64,
    /// Offset of the pin bar's line of motion (y), m.
    pub offset: f64,
    pub m2: f64,
    pub lc2: f64,
    pub i2: f64,
    pub m3: f64,
    pub lc3: f64,
    pub i3: f64,
    pub m4: f64,
    /// Journal radius R_J, m.
    pub rj: f64,
    /// Radial clearance c = R_B − R_J, m.
    pub clearance: f64,
    pub journal: Material,
    pub bearing: Material,
    pub contact_model: ContactModel,
    /// Restitution coefficient ce.
    pub restitution: f64,
    /// Joint friction coefficient c_f.
    pub c_f: f64,
    /// Guide friction coefficient μ_g.
    pub mu_g: f64,
    /// Friction smoothing: c_d = 0 below v0, 1 above v1 (m/s).
    pub v0: f64,
    pub v1: f64,
    /// Floor on the onset approach velocity δ̇⁻ (m/s).
    pub approach_floor: f64,
    pub motor_rpm: f64,
    pub gear_ratio: f64,
    /// Stroke at which the pin meets the part, m.
    pub standoff: f64,
    pub f_ins: Table,
    pub f_wd: Table,
    pub process_law: ProcessLaw,
    /// Gravity vector in the model frame, m/s².
    pub gravity: [f64; 2],
    pub driver: Driver,
    /// The motor, gear and flywheel (level `motor`).
    pub motor: MotorParams,
}

/// Names of the presets.
pub const PRESETS: [&str; 2] = ["paper", "flores"];

impl Params {
    /// The `paper` preset: a representative pin-insertion head (model.md).
    pub fn paper() -> Self {
        let steel = Material::by_name("alloy_steel").expect("built-in material");
        Self {
            preset: "paper".into(),
            r: 8e-3,
            l: 45e-3,
            offset: 0.0,
            m2: 0.20,
            lc2: 4e-3,
            i2: 2.0e-5,
            m3: 0.06,
            lc3: 22.5e-3,
            i3: 1.2e-5,
            m4: 0.08,
            rj: 3.0e-3,
            clearance: 0.1e-3,
            journal: steel.clone(),
            bearing: steel,
            contact_model: ContactModel::LankaraniNikravesh,
            restitution: 0.9,
            c_f: 0.0,
            mu_g: 0.01,
            v0: 1e-4,
            v1: 1e-3,
            approach_floor: 1e-3,
            motor_rpm: 1200.0,
            gear_ratio: 1.0,
            standoff: 14.0e-3,
            f_ins: Table::from_mm(&[(0.0, 0.0), (0.2, 8.0), (0.5, 21.0), (2.0, 23.0)])
                .expect("built-in table"),
            f_wd: Table::zero(),
            process_law: ProcessLaw::Regularized,
            gravity: [9.81, 0.0],
            driver: Driver::ConstantSpeed,
            motor: MotorParams::default(),
        }
    }

    /// The `flores` preset: the literature's slider-crank benchmark
    /// (flores-benchmark.md), c = 0.5 mm.
    pub fn flores() -> Self {
        let steel = Material::by_name("alloy_steel").expect("built-in material");
        Self {
            preset: "flores".into(),
            r: 0.05,
            l: 0.12,
            offset: 0.0,
            m2: 0.30,
            lc2: 0.025,
            i2: 1.0e-4,
            m3: 0.21,
            lc3: 0.06,
            i3: 2.5e-4,
            m4: 0.14,
            rj: 9.5e-3,
            clearance: 0.5e-3,
            journal: steel.clone(),
            bearing: steel,
            contact_model: ContactModel::LankaraniNikravesh,
            restitution: 0.9,
            c_f: 0.0,
            mu_g: 0.0,
            v0: 1e-4,
            v1: 1e-3,
            approach_floor: 1e-3,
            motor_rpm: 5000.0,
            gear_ratio: 1.0,
            standoff: 0.0,
            f_ins: Table::zero(),
            f_wd: Table::zero(),
            process_law: ProcessLaw::Regularized,
            gravity: [0.0, -9.81],
            driver: Driver::ConstantSpeed,
            motor: MotorParams::default(),
        }
    }

    /// A preset by name.
    pub fn preset(name: &str) -> Result<Self, ParamError> {
        match name.trim() {
            "paper" => Ok(Self::paper()),
            "flores" => Ok(Self::flores()),
            other => Err(ParamError::Invalid {
                key: "preset".into(),
                value: other.into(),
                allowed: format!("one of {}", PRESETS.join(", ")),
            }),
        }
    }

    /// Bearing radius R_B = R_J + c, m.
    pub fn rb(&self) -> f64 {
        self.rj + self.clearance
    }

    /// Crank angular speed ω = 2π · motor_rpm / 60 / gear_ratio, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.motor_rpm / 60.0 / self.gear_ratio
    }

    /// Crank period, s.
    pub fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.omega()
    }

    /// Name of the material pair (`custom` or `a/b` when they differ).
    pub fn material_name(&self) -> String {
        if self.journal.name == self.bearing.name {
            self.journal.name.clone()
        } else {
            format!("{}/{}", self.journal.name, self.bearing.name)
        }
    }

    /// Loads a parameter file: its `preset` (default `paper`) is the base,
    /// then every other key in the file applies (material before E/ν).
    pub fn from_toml_file(path: &Path) -> Result<Self, ParamError> {
        let text = crate::input::read_text(path).map_err(|e| ParamError::File {
            file: path.display().to_string(),
            msg: e.to_string(),
        })?;
        Self::from_toml_str(&text).map_err(|e| e.in_file(path))
    }

    /// Parses parameter-file text (see [`Params::from_toml_file`]).
    pub fn from_toml_str(text: &str) -> Result<Self, ParamError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ParamError::File {
                file: String::new(),
                msg: e.to_string(),
            })?;
        let base = match table.get("preset") {
            Some(toml::Value::String(s)) => Self::preset(s)?,
            Some(v) => {
                return Err(ParamError::Invalid {
                    key: "preset".into(),
                    value: show(v),
                    allowed: format!("a string, one of {}", PRESETS.join(", ")),
                });
            }
            None => Self::paper(),
        };
        let mut p = base;
        p.apply_table(&table)?;
        p.validate()?;
        Ok(p)
    }

    /// Applies every key of a TOML table except `preset` (materials first, so
    /// that explicit E/ν keys override them).
    pub fn apply_table(&mut self, table: &toml::Table) -> Result<(), ParamError> {
        let rank = |k: &str| match k {
            "material" => 0,
            "journal_material" | "bearing_material" => 1,
            _ => 2,
        };
        let mut entries: Vec<(&String, &toml::Value)> = table
            .iter()
            .filter(|(k, _)| k.as_str() != "preset")
            .collect();
        entries.sort_by_key(|(k, _)| rank(k));
        for (k, v) in entries {
            self.set(k, v)?;
        }
        Ok(())
    }

    /// Applies `key=value` overrides in order (value in TOML syntax, bare
    /// words taken as strings), then validates the whole set.
    pub fn apply_overrides<S: AsRef<str>>(&mut self, sets: &[S]) -> Result<(), ParamError> {
        for s in sets {
            let s = s.as_ref();
            let (k, v) = s.split_once('=').ok_or_else(|| ParamError::Syntax {
                text: s.to_string(),
            })?;
            self.set_str(k.trim(), v.trim())?;
        }
        self.validate()
    }

    /// Sets one key from its text form (TOML value syntax; a bare word is a string).
    pub fn set_str(&mut self, key: &str, text: &str) -> Result<(), ParamError> {
        let value = parse_value_text(text);
        self.set(key, &value)
    }

    /// Sets one key, converting units and checking its range.
    pub fn set(&mut self, key: &str, value: &toml::Value) -> Result<(), ParamError> {
        let spec = spec(key).ok_or_else(|| ParamError::unknown(key))?;
        let invalid = |v: String| ParamError::Invalid {
            key: key.to_string(),
            value: v,
            allowed: spec.range.to_string(),
        };
        let num = || -> Result<f64, ParamError> {
            let x = match value {
                toml::Value::Float(f) => *f,
                toml::Value::Integer(i) => *i as f64,
                toml::Value::String(s) => {
                    s.trim().parse::<f64>().map_err(|_| invalid(show(value)))?
                }
                other => return Err(invalid(show(other))),
            };
            if !x.is_finite() {
                return Err(invalid(x.to_string()));
            }
            // The physical range (a clearance of 0 is the ideal joint, a
            // no-load speed of 0 is `auto`).
            if let Some((lo, hi)) = physical_range(key)
                && !within(x, lo, hi)
                && !(matches!(key, "clearance_mm" | "motor_no_load_rpm") && x == 0.0)
            {
                return Err(invalid(fmt_num(x)));
            }
            Ok(x)
        };
        let text = || -> Result<String, ParamError> {
            match value {
                toml::Value::String(s) => Ok(s.trim().to_string()),
                other => Err(invalid(show(other))),
            }
        };
        let check = |x: f64, ok: bool| -> Result<f64, ParamError> {
            if ok { Ok(x) } else { Err(invalid(fmt_num(x))) }
        };
        match key {
            "r_mm" => {
                let x = num()?;
                self.r = check(x, x > 0.0)? / 1e3
            }
            "l_mm" => {
                let x = num()?;
                self.l = check(x, x > 0.0)? / 1e3
            }
            "offset_mm" => self.offset = num()? / 1e3,
            "m2_kg" => {
                let x = num()?;
                self.m2 = check(x, x >= 0.0)?
            }
            "lc2_mm" => {
                let x = num()?;
                self.lc2 = check(x, x >= 0.0)? / 1e3
            }
            "i2_kgm2" => {
                let x = num()?;
                self.i2 = check(x, x >= 0.0)?
            }
            "m3_kg" => {
                let x = num()?;
                self.m3 = check(x, x > 0.0)?
            }
            "lc3_mm" => {
                let x = num()?;
                self.lc3 = check(x, x >= 0.0)? / 1e3
            }
            "i3_kgm2" => {
                let x = num()?;
                self.i3 = check(x, x >= 0.0)?
            }
            "m4_kg" => {
                let x = num()?;
                self.m4 = check(x, x > 0.0)?
            }
            "rj_mm" => {
                let x = num()?;
                self.rj = check(x, x > 0.0)? / 1e3
            }
            "clearance_mm" => {
                let x = num()?;
                self.clearance = check(x, x >= 0.0)? / 1e3
            }
            "material" => {
                let m = Material::by_name(&text()?).ok_or_else(|| invalid(show(value)))?;
                self.journal = m.clone();
                self.bearing = m;
            }
            "journal_material" => {
                self.journal = Material::by_name(&text()?).ok_or_else(|| invalid(show(value)))?
            }
            "bearing_material" => {
                self.bearing = Material::by_name(&text()?).ok_or_else(|| invalid(show(value)))?
            }
            "journal_e_gpa" => {
                let x = num()?;
                self.journal.e_pa = check(x, x > 0.0)? * 1e9;
                self.journal.name = "custom".into();
            }
            "bearing_e_gpa" => {
                let x = num()?;
                self.bearing.e_pa = check(x, x > 0.0)? * 1e9;
                self.bearing.name = "custom".into();
            }
            "journal_nu" => {
                let x = num()?;
                self.journal.nu = check(x, x > -1.0 && x < 0.5)?;
                self.journal.name = "custom".into();
            }
            "bearing_nu" => {
                let x = num()?;
                self.bearing.nu = check(x, x > -1.0 && x < 0.5)?;
                self.bearing.name = "custom".into();
            }
            "contact_model" => {
                self.contact_model =
                    ContactModel::parse(&text()?).ok_or_else(|| invalid(show(value)))?
            }
            "restitution" => {
                let x = num()?;
                self.restitution = check(x, x > 0.0 && x <= 1.0)?
            }
            "c_f" => {
                let x = num()?;
                self.c_f = check(x, x >= 0.0)?
            }
            "mu_g" => {
                let x = num()?;
                self.mu_g = check(x, (0.0..1.0).contains(&x))?
            }
            "friction_v0_mps" => {
                let x = num()?;
                self.v0 = check(x, x >= 0.0)?
            }
            "friction_v1_mps" => {
                let x = num()?;
                self.v1 = check(x, x > 0.0)?
            }
            "approach_velocity_floor_mps" => {
                let x = num()?;
                self.approach_floor = check(x, x > 0.0)?
            }
            "motor_rpm" => {
                let x = num()?;
                self.motor_rpm = check(x, x > 0.0)?
            }
            "gear_ratio" => {
                let x = num()?;
                self.gear_ratio = check(x, x > 0.0)?
            }
            "standoff_mm" => {
                let x = num()?;
                self.standoff = check(x, x >= 0.0)? / 1e3
            }
            "f_ins_table" | "f_wd_table" => {
                let pts = pairs(value).ok_or_else(|| invalid(show(value)))?;
                // Physical range: depths within 1000 mm, forces within 1 MN.
                if let Some(&(d, f)) = pts
                    .iter()
                    .find(|(d, f)| !(d.abs() <= 1000.0 && f.abs() <= 1e6))
                {
                    return Err(invalid(format!("[{}, {}]", fmt_num(d), fmt_num(f))));
                }
                let t = Table::from_mm(&pts).map_err(|msg| ParamError::Invalid {
                    key: key.to_string(),
                    value: format!("{} ({msg})", show(value)),
                    allowed: spec.range.to_string(),
                })?;
                if key == "f_ins_table" {
                    self.f_ins = t
                } else {
                    self.f_wd = t
                }
            }
            "process_law" => {
                self.process_law = match text()?.as_str() {
                    "regularized" => ProcessLaw::Regularized,
                    "stick" => ProcessLaw::Stick,
                    _ => return Err(invalid(show(value))),
                }
            }
            "gravity_mps2" => {
                let v = match value {
                    toml::Value::Array(a) if a.len() == 2 => {
                        let mut g = [0.0; 2];
                        for (i, x) in a.iter().enumerate() {
                            g[i] = match x {
                                toml::Value::Float(f) if f.abs() <= 1000.0 => *f,
                                toml::Value::Integer(n) if n.abs() <= 1000 => *n as f64,
                                _ => return Err(invalid(show(value))),
                            };
                        }
                        g
                    }
                    _ => return Err(invalid(show(value))),
                };
                self.gravity = v
            }
            "driver" => {
                self.driver = match text()?.as_str() {
                    "constant_speed" => Driver::ConstantSpeed,
                    "motor" => Driver::Motor,
                    _ => return Err(invalid(show(value))),
                }
            }
            "motor_curve" => {
                self.motor.curve =
                    MotorCurve::parse(&text()?).ok_or_else(|| invalid(show(value)))?
            }
            "speed_control" => {
                self.motor.control =
                    SpeedControl::parse(&text()?).ok_or_else(|| invalid(show(value)))?
            }
            "motor_stall_torque_nm" => self.motor.stall_torque = num()?,
            "motor_no_load_rpm" => self.motor.no_load_rpm = num()?,
            "rotor_inertia_kgm2" => self.motor.rotor_inertia = num()?,
            "flywheel_inertia_kgm2" => self.motor.flywheel_inertia = num()?,
            "gear_efficiency" => self.motor.efficiency = num()?,
            "speed_kp_nms" => self.motor.kp = num()?,
            "speed_ki_nm" => self.motor.ki = num()?,
            "motor_torque_table" => {
                let pts = pairs(value).ok_or_else(|| invalid(show(value)))?;
                let bad = |i: usize, why: &str| ParamError::Invalid {
                    key: key.to_string(),
                    value: format!("{} (point {i}: {why})", show(value)),
                    allowed: spec.range.to_string(),
                };
                for (i, &(w, t)) in pts.iter().enumerate() {
                    if !(w.is_finite() && (0.0..=1e5).contains(&w)) {
                        return Err(bad(i, "speed outside 0 … 1e5 rev/min"));
                    }
                    if !(t.is_finite() && t.abs() <= 1e5) {
                        return Err(bad(i, "torque outside −1e5 … 1e5 N·m"));
                    }
                    if i > 0 && w <= pts[i - 1].0 {
                        return Err(bad(i, "speeds must increase strictly"));
                    }
                }
                self.motor.torque_table = Table { points: pts };
            }
            _ => return Err(ParamError::unknown(key)),
        }
        Ok(())
    }

    /// The value of a key in its user units.
    pub fn get(&self, key: &str) -> Option<ParamValue> {
        use ParamValue::*;
        Some(match key {
            "r_mm" => Number(self.r * 1e3),
            "l_mm" => Number(self.l * 1e3),
            "offset_mm" => Number(self.offset * 1e3),
            "m2_kg" => Number(self.m2),
            "lc2_mm" => Number(self.lc2 * 1e3),
            "i2_kgm2" => Number(self.i2),
            "m3_kg" => Number(self.m3),
            "lc3_mm" => Number(self.lc3 * 1e3),
            "i3_kgm2" => Number(self.i3),
            "m4_kg" => Number(self.m4),
            "rj_mm" => Number(self.rj * 1e3),
            "clearance_mm" => Number(self.clearance * 1e3),
            "material" => Text(self.material_name()),
            "journal_material" => Text(self.journal.name.clone()),
            "bearing_material" => Text(self.bearing.name.clone()),
            "journal_e_gpa" => Number(self.journal.e_pa / 1e9),
            "bearing_e_gpa" => Number(self.bearing.e_pa / 1e9),
            "journal_nu" => Number(self.journal.nu),
            "bearing_nu" => Number(self.bearing.nu),
            "contact_model" => Text(self.contact_model.name().into()),
            "restitution" => Number(self.restitution),
            "c_f" => Number(self.c_f),
            "mu_g" => Number(self.mu_g),
            "friction_v0_mps" => Number(self.v0),
            "friction_v1_mps" => Number(self.v1),
            "approach_velocity_floor_mps" => Number(self.approach_floor),
            "motor_rpm" => Number(self.motor_rpm),
            "gear_ratio" => Number(self.gear_ratio),
            "standoff_mm" => Number(self.standoff * 1e3),
            "f_ins_table" => Pairs(self.f_ins.to_mm()),
            "f_wd_table" => Pairs(self.f_wd.to_mm()),
            "process_law" => Text(self.process_law.name().into()),
            "gravity_mps2" => Vector(self.gravity.to_vec()),
            "driver" => Text(self.driver.name().into()),
            "motor_curve" => Text(self.motor.curve.name().into()),
            "motor_stall_torque_nm" => Number(self.motor.stall_torque),
            "motor_no_load_rpm" => Number(self.motor.no_load_rpm),
            "motor_torque_table" => Pairs(self.motor.torque_table.points.clone()),
            "rotor_inertia_kgm2" => Number(self.motor.rotor_inertia),
            "flywheel_inertia_kgm2" => Number(self.motor.flywheel_inertia),
            "gear_efficiency" => Number(self.motor.efficiency),
            "speed_control" => Text(self.motor.control.name().into()),
            "speed_kp_nms" => Number(self.motor.kp),
            "speed_ki_nm" => Number(self.motor.ki),
            _ => return None,
        })
    }

    /// Checks the relations between parameters (each key's own range is
    /// checked when it is set).
    pub fn validate(&self) -> Result<(), ParamError> {
        // Re-check every key's range (a struct may be built in code).
        for s in PARAM_SPECS {
            if matches!(s.key, "material" | "journal_material" | "bearing_material") {
                continue; // names, possibly `custom`; E and ν are checked below
            }
            if let Some(v) = self.get(s.key) {
                let mut copy = self.clone();
                copy.set(s.key, &v.to_toml())?;
            }
        }
        if self.l <= self.r + self.offset.abs() {
            return Err(ParamError::Relation {
                keys: "l_mm, r_mm, offset_mm".into(),
                msg: format!(
                    "l_mm = {} must exceed r_mm + |offset_mm| = {} (the crank could not turn a full revolution)",
                    fmt_num(self.l * 1e3),
                    fmt_num((self.r + self.offset.abs()) * 1e3)
                ),
            });
        }
        if self.lc3 > self.l {
            return Err(ParamError::Relation {
                keys: "lc3_mm, l_mm".into(),
                msg: format!(
                    "lc3_mm = {} must lie on the rod (0 … l_mm = {})",
                    fmt_num(self.lc3 * 1e3),
                    fmt_num(self.l * 1e3)
                ),
            });
        }
        if self.i3 + self.m3 * self.lc3 * self.lc3 <= 0.0 {
            return Err(ParamError::Relation {
                keys: "i3_kgm2, m3_kg, lc3_mm".into(),
                msg: "the rod's inertia about the crank pin, i3 + m3·lc3², must be positive".into(),
            });
        }
        if self.motor.curve == MotorCurve::Table && self.motor.torque_table.points.len() < 2 {
            return Err(ParamError::Relation {
                keys: "motor_curve, motor_torque_table".into(),
                msg: "motor_curve = \"table\" needs motor_torque_table with at least two points [[rpm, N·m], …]".into(),
            });
        }
        if self.motor.control == SpeedControl::Pi && self.motor.kp <= 0.0 {
            return Err(ParamError::Relation {
                keys: "speed_control, speed_kp_nms".into(),
                msg:
                    "speed_control = \"pi\" needs speed_kp_nms > 0 (its anti-windup runs at ki/kp)"
                        .into(),
            });
        }
        if self.v1 <= self.v0 {
            return Err(ParamError::Relation {
                keys: "friction_v0_mps, friction_v1_mps".into(),
                msg: format!(
                    "friction_v1_mps = {} must exceed friction_v0_mps = {}",
                    fmt_num(self.v1),
                    fmt_num(self.v0)
                ),
            });
        }
        Ok(())
    }

    /// The whole parameter set as a parameter file (loadable by
    /// [`Params::from_toml_str`]).
    pub fn to_toml(&self) -> String {
        let mut out = String::new();
        out.push_str(&format!("preset = \"{}\"\n", self.preset));
        for s in PARAM_SPECS {
            // Materials by name; E and ν only for a body whose material is custom.
            let skip = match s.key {
                "material" => {
                    self.journal.name != self.bearing.name || self.journal.name == "custom"
                }
                "journal_material" => {
                    self.journal.name == self.bearing.name || self.journal.name == "custom"
                }
                "bearing_material" => {
                    self.journal.name == self.bearing.name || self.bearing.name == "custom"
                }
                "journal_e_gpa" | "journal_nu" => self.journal.name != "custom",
                "bearing_e_gpa" | "bearing_nu" => self.bearing.name != "custom",
                _ => false,
            };
            if skip {
                continue;
            }
            if let Some(v) = self.get(s.key) {
                out.push_str(&format!("{} = {}\n", s.key, v.to_toml()));
            }
        }
        out
    }

    /// Every key with its current value, for listings and the Model pane.
    pub fn listing(&self) -> Vec<(&'static ParamSpec, ParamValue)> {
        PARAM_SPECS
            .iter()
            .filter_map(|s| self.get(s.key).map(|v| (s, v)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_roundtrip_through_toml() {
        for name in PRESETS {
            let p = Params::preset(name).unwrap();
            p.validate().unwrap();
            let text = p.to_toml();
            let q = Params::from_toml_str(&text).unwrap();
            assert_eq!(p, q, "{name}:\n{text}");
        }
    }

    #[test]
    fn flores_stiffness_inputs() {
        let p = Params::flores();
        assert!((p.rb() - 10.0e-3).abs() < 1e-15);
        assert!((p.omega() - 523.598_775_598).abs() < 1e-6);
        assert!((p.contact_model.damping_factor(p.restitution) - 0.1425).abs() < 1e-15);
    }

    #[test]
    fn overrides_apply_in_units() {
        let mut p = Params::paper();
        p.apply_overrides(&[
            "clearance_mm=0.3",
            "motor_rpm = 1500",
            "material=copper",
            "m4_kg=0.1",
        ])
        .unwrap();
        assert!((p.clearance - 0.3e-3).abs() < 1e-15);
        assert_eq!(p.motor_rpm, 1500.0);
        assert_eq!(p.journal.name, "copper");
        assert_eq!(p.bearing.e_pa, 117e9);
        p.apply_overrides(&["f_ins_table=[[0,0],[1,10]]", "gravity_mps2=[0, -9.81]"])
            .unwrap();
        assert_eq!(p.f_ins.eval(0.5e-3), 5.0);
        assert_eq!(p.gravity, [0.0, -9.81]);
    }

    #[test]
    fn invalid_values_name_key_and_range() {
        let cases: &[(&str, &str)] = &[
            ("clearance_mm=-0.1", "clearance_mm"),
            ("m4_kg=-1", "m4_kg"),
            ("m3_kg=0", "m3_kg"),
            ("rj_mm=0", "rj_mm"),
            ("journal_e_gpa=0", "journal_e_gpa"),
            ("bearing_nu=0.5", "bearing_nu"),
            ("journal_nu=-1", "journal_nu"),
            ("motor_rpm=0", "motor_rpm"),
            ("motor_rpm=-5", "motor_rpm"),
            ("material=unobtainium", "material"),
            ("f_ins_table=[[0,0],[0.5,3],[0.4,5]]", "f_ins_table"),
            ("contact_model=magic", "contact_model"),
            ("restitution=0", "restitution"),
            ("motor_rpm=fast", "motor_rpm"),
        ];
        for (set, key) in cases {
            let mut p = Params::paper();
            let err = p.apply_overrides(&[*set]).unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains(key), "{set}: {msg}");
            assert!(msg.contains("allowed"), "{set}: {msg}");
        }
    }

    #[test]
    fn relations_and_unknown_keys() {
        let mut p = Params::paper();
        let err = p.apply_overrides(&["l_mm=7"]).unwrap_err().to_string();
        assert!(err.contains("l_mm") && err.contains("r_mm"), "{err}");
        let mut p = Params::paper();
        let err = p
            .apply_overrides(&["offset_mm=40"])
            .unwrap_err()
            .to_string();
        assert!(err.contains("offset_mm"), "{err}");
        let mut p = Params::paper();
        let err = p
            .apply_overrides(&["clearance=0.2"])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("unknown parameter `clearance`") && err.contains("clearance_mm"),
            "{err}"
        );
        let mut p = Params::paper();
        assert!(p.apply_overrides(&["clearance_mm"]).is_err());
    }

    #[test]
    fn file_with_preset_and_explicit_moduli() {
        let text = "preset = \"flores\"\njournal_e_gpa = 100\nmaterial = \"copper\"\nclearance_mm = 0.25\n";
        let p = Params::from_toml_str(text).unwrap();
        assert_eq!(p.preset, "flores");
        // material applies first, then the explicit modulus
        assert_eq!(p.journal.e_pa, 100e9);
        assert_eq!(p.journal.name, "custom");
        assert_eq!(p.bearing.name, "copper");
        assert!((p.rb() - 9.75e-3).abs() < 1e-15);
        let err = Params::from_toml_str("preset = \"nope\"")
            .unwrap_err()
            .to_string();
        assert!(err.contains("preset"), "{err}");
        let err = Params::from_toml_str("m4_kg = \n").unwrap_err().to_string();
        assert!(err.contains("parameter file"), "{err}");
        // A custom material survives a round trip.
        let q = Params::from_toml_str(&p.to_toml()).unwrap();
        assert_eq!(p, q);
    }
}
