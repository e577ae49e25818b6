//! The `rig` metadata record (rig-log.md), typed.
//!
//! Every key is optional. Values are kept raw in [`RigMeta::raw`] as well;
//! a value that cannot be understood (e.g. `clearance_mm = "abc"`) is left
//! `None` and reported as a finding rather than guessed. A session can
//! override any key ([`RigMeta::apply_overrides`]); overridden keys are listed.

use super::report::{Finding, FindingCode, Severity};
use crate::fmt::fmt_num;
use crate::model::params::{physical_range, within};
use serde::Serialize;
use std::collections::BTreeMap;

/// Materials the model knows (model.md).
pub const MATERIALS: [&str; 5] = [
    "alloy_steel",
    "stainless_steel",
    "aluminium",
    "copper",
    "tungsten_carbide",
];

/// The keys of rig-log.md's `rig` record.
pub const KNOWN_KEYS: [&str; 11] = [
    "rig_id",
    "clearance_mm",
    "material",
    "motor_rpm",
    "gear_ratio",
    "standoff_mm",
    "laser_zero_mm",
    "force_tare_n",
    "angle_offset_rad",
    "part_number",
    "lot",
];

/// The run's metadata: the `rig` record's keys, typed.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RigMeta {
    pub rig_id: Option<String>,
    /// Radial clearance of the rod–pin-bar joint fitted for the run (mm).
    pub clearance_mm: Option<f64>,
    pub material: Option<String>,
    /// Motor speed set-point (rev/min).
    pub motor_rpm: Option<f64>,
    /// Motor revolutions per crank revolution.
    pub gear_ratio: Option<f64>,
    /// Stroke (from TDC) at which the pin tip meets the part (mm).
    pub standoff_mm: Option<f64>,
    /// Stroke at which the displacement sensor reads 0 (mm).
    pub laser_zero_mm: Option<f64>,
    /// Load-cell reading with no load (N), to subtract.
    pub force_tare_n: Option<f64>,
    /// Angle to add to the logged crank angle to get θ2 (rad).
    pub angle_offset_rad: Option<f64>,
    pub part_number: Option<String>,
    pub lot: Option<String>,
    /// The record exactly as written (plus overrides), key → value.
    pub raw: BTreeMap<String, String>,
    /// Whether the file had a `rig` record at all.
    pub present: bool,
    /// Keys whose value came from a session override rather than the file.
    pub overridden: Vec<String>,
}

/// A metadata value as a message quotes it: numbers read as numbers (no
/// 300-digit expansions), anything else cut at 40 characters.
fn short(v: &str) -> String {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => fmt_num(x),
        _ if v.chars().count() > 40 => format!("{}…", v.chars().take(40).collect::<String>()),
        _ => v.to_string(),
    }
}

/// A warning about a value of the log's `rig` metadata record.
fn metadata_warning(file: &str, text: String) -> Finding {
    Finding::new(
        Severity::Warning,
        FindingCode::Metadata,
        file,
        None,
        None,
        format!("metadata 'rig': {text}"),
    )
}

fn num(
    raw: &BTreeMap<String, String>,
    key: &str,
    file: &str,
    findings: &mut Vec<Finding>,
    check: impl Fn(f64) -> bool,
    what: &str,
) -> Option<f64> {
    let v = raw.get(key)?;
    let not = match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && check(x) => return Some(x),
        Ok(_) => what,
        Err(_) => "a number",
    };
    findings.push(metadata_warning(
        file,
        format!("{key} = '{}' is not {not}; ignored", short(v)),
    ));
    None
}

impl RigMeta {
    /// Types a raw `rig` record; problems go to `findings`.
    pub fn from_raw(
        raw: BTreeMap<String, String>,
        file: &str,
        findings: &mut Vec<Finding>,
    ) -> Self {
        let s = |k: &str| {
            raw.get(k)
                .map(|v| v.trim().to_string())
                .filter(|v| !v.is_empty())
        };
        let mut m = RigMeta {
            rig_id: s("rig_id"),
            material: s("material"),
            part_number: s("part_number"),
            lot: s("lot"),
            ..Default::default()
        };
        // The model's physical ranges (a log cannot make the solver spin
        // with a clearance of 1e-300 mm): outside them the value is ignored
        // with a finding.
        let mut ranged = |key: &str, what: &str, unit: &str| {
            let (lo, hi) = physical_range(key).unwrap_or((f64::MIN, f64::MAX));
            let zero_ok = key == "clearance_mm";
            let allowed = format!("{what} within {} … {}{unit}", fmt_num(lo), fmt_num(hi));
            num(
                &raw,
                key,
                file,
                findings,
                |x| within(x, lo, hi) || (zero_ok && x == 0.0),
                &allowed,
            )
        };
        m.clearance_mm = ranged("clearance_mm", "0 or a clearance", " mm");
        m.motor_rpm = ranged("motor_rpm", "a speed", " rpm");
        m.gear_ratio = ranged("gear_ratio", "a ratio", "");
        m.standoff_mm = ranged("standoff_mm", "a length", " mm");
        let mut bounded = |key: &str, limit: f64, what: &str| {
            num(&raw, key, file, findings, |x| x.abs() <= limit, what)
        };
        m.laser_zero_mm = bounded("laser_zero_mm", 1000.0, "a length within ±1000 mm");
        m.force_tare_n = bounded("force_tare_n", 1e6, "a force within ±1e6 N");
        m.angle_offset_rad = bounded("angle_offset_rad", 100.0, "an angle within ±100 rad");
        if let Some(mat) = &m.material
            && !MATERIALS.contains(&mat.as_str())
        {
            findings.push(metadata_warning(
                file,
                format!(
                    "material '{mat}' is not one the model knows ({})",
                    MATERIALS.join(", ")
                ),
            ));
        }
        m.raw = raw;
        m
    }

    /// Applies session overrides (key → value as in the record) and re-types.
    pub fn apply_overrides(
        &self,
        overrides: &BTreeMap<String, String>,
        file: &str,
        findings: &mut Vec<Finding>,
    ) -> Self {
        if overrides.is_empty() {
            return self.clone();
        }
        let mut raw = self.raw.clone();
        for (k, v) in overrides {
            raw.insert(k.clone(), v.clone());
        }
        let mut m = RigMeta::from_raw(raw, file, findings);
        m.present = self.present;
        m.overridden = overrides.keys().cloned().collect();
        m
    }

    /// Crank speed set-point (rev/min) = motor speed / gear ratio.
    pub fn crank_rpm(&self) -> Option<f64> {
        Some(self.motor_rpm? / self.gear_ratio.unwrap_or(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_known_keys_and_reports_bad_values() {
        let mut raw = BTreeMap::new();
        raw.insert("clearance_mm".to_string(), "0.1".to_string());
        raw.insert("motor_rpm".to_string(), "fast".to_string());
        raw.insert("gear_ratio".to_string(), "2".to_string());
        raw.insert("material".to_string(), "cheese".to_string());
        let mut f = Vec::new();
        let m = RigMeta::from_raw(raw, "x.mcap", &mut f);
        assert_eq!(m.clearance_mm, Some(0.1));
        assert_eq!(m.motor_rpm, None);
        assert_eq!(m.gear_ratio, Some(2.0));
        assert_eq!(f.len(), 2);
        assert!(f[0].message.contains("motor_rpm = 'fast'"));
        assert!(f[1].message.contains("cheese"));
        let mut o = BTreeMap::new();
        o.insert("motor_rpm".to_string(), "1200".to_string());
        let m2 = m.apply_overrides(&o, "x.mcap", &mut f);
        assert_eq!(m2.motor_rpm, Some(1200.0));
        assert_eq!(m2.crank_rpm(), Some(600.0));
        assert_eq!(m2.overridden, vec!["motor_rpm".to_string()]);
    }
}
