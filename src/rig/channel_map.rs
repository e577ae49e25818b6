//! Channel maps: which topic and JSON field hold each signal, and how to
//! convert the raw value (`value = scale · raw + offset`, then the unit to
//! pinsight's canonical unit).
//!
//! The default map is rig-log.md's convention. A rig that names things
//! differently gets a TOML map — in its own file or as the `[channels]`
//! table of a session/config file — with one table per signal:
//!
//! ```toml
//! [force]
//! topic = "/daq/ai0"
//! field = "v"
//! unit = "N"
//! scale = 10.0     # N per V
//! offset = 0.0
//! ```
//!
//! Signals: `angle` (crank angle), `speed` (motor speed), `force`,
//! `displacement`, `cycle` (cycle index at TDC), and `images` (camera topic,
//! `topic` only). A map given by the user lists the signals the rig logs:
//! a signal it leaves out is *not expected* (speed is then derived from the
//! angle, cycles from the angle) and is not reported missing. With
//! `inherit = "default"` at the top level, signals left out keep the default
//! convention instead. A table with `topic = ""` says explicitly that the
//! rig does not log that signal. Unknown tables or keys are errors (a typo
//! must not silently drop a signal).
//!
//! Canonical units: angle rad, speed rev/min (motor), force N,
//! displacement mm, cycle index (dimensionless). Accepted `unit`s: angle
//! `rad`, `deg`; speed `rpm`, `rev/min`, `rad/s`, `Hz` (rev/s); force `N`,
//! `kN`; displacement `mm`, `um`/`µm`, `m`. `unit` names the unit of
//! `scale · raw + offset`.

use super::error::LogError;

/// The camera topic of rig-log.md (the default channel map's `images`).
pub const CAMERA_TOPIC: &str = "/camera/connector";
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A signal pinsight reads from a rig log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SignalKind {
    /// Crank angle (rad).
    Angle,
    /// Motor speed (rev/min).
    Speed,
    /// Load-cell force (N, + = pin pushed into the part).
    Force,
    /// Laser displacement of the pin bar (mm, + = down, 0 at the zero mark).
    Displacement,
    /// Cycle index, emitted at top dead centre.
    Cycle,
}

impl SignalKind {
    pub const ALL: [SignalKind; 5] = [
        SignalKind::Angle,
        SignalKind::Speed,
        SignalKind::Force,
        SignalKind::Displacement,
        SignalKind::Cycle,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SignalKind::Angle => "angle",
            SignalKind::Speed => "speed",
            SignalKind::Force => "force",
            SignalKind::Displacement => "displacement",
            SignalKind::Cycle => "cycle",
        }
    }

    /// Canonical unit.
    pub fn unit(self) -> &'static str {
        match self {
            SignalKind::Angle => "rad",
            SignalKind::Speed => "rpm",
            SignalKind::Force => "N",
            SignalKind::Displacement => "mm",
            SignalKind::Cycle => "",
        }
    }

    fn from_name(s: &str) -> Option<Self> {
        SignalKind::ALL.into_iter().find(|k| k.name() == s)
    }

    /// Factor from `unit` to the canonical unit.
    fn unit_factor(self, unit: &str) -> Option<f64> {
        let u = unit.trim();
        match self {
            SignalKind::Angle => match u {
                "rad" => Some(1.0),
                "deg" | "°" => Some(PI / 180.0),
                _ => None,
            },
            SignalKind::Speed => match u {
                "rpm" | "rev/min" | "1/min" => Some(1.0),
                "rad/s" => Some(60.0 / (2.0 * PI)),
                "Hz" | "rev/s" => Some(60.0),
                _ => None,
            },
            SignalKind::Force => match u {
                "N" => Some(1.0),
                "kN" => Some(1000.0),
                _ => None,
            },
            SignalKind::Displacement => match u {
                "mm" => Some(1.0),
                "um" | "µm" => Some(1e-3),
                "m" => Some(1e3),
                _ => None,
            },
            SignalKind::Cycle => match u {
                "" | "-" | "index" | "count" => Some(1.0),
                _ => None,
            },
        }
    }
}

/// Where one signal lives and how to convert it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignalSource {
    pub topic: String,
    /// JSON field; for block topics, the schema `title` naming the field.
    pub field: String,
    /// Unit of `scale · raw + offset` as written in the map.
    pub unit: String,
    pub scale: f64,
    pub offset: f64,
    /// Factor from `unit` to the canonical unit.
    pub unit_factor: f64,
}

impl SignalSource {
    fn new(topic: &str, field: &str, unit: &str) -> Self {
        SignalSource {
            topic: topic.into(),
            field: field.into(),
            unit: unit.into(),
            scale: 1.0,
            offset: 0.0,
            unit_factor: 1.0,
        }
    }

    /// Raw value → canonical unit.
    #[inline]
    pub fn convert(&self, raw: f64) -> f64 {
        (self.scale * raw + self.offset) * self.unit_factor
    }
}

/// The mapping from signals to topics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelMap {
    /// Where the map came from ("default (rig-log.md)" or a file name).
    pub source: String,
    pub angle: Option<SignalSource>,
    pub speed: Option<SignalSource>,
    pub force: Option<SignalSource>,
    pub displacement: Option<SignalSource>,
    pub cycle: Option<SignalSource>,
    /// Camera topic (foxglove.CompressedImage).
    pub images: Option<String>,
}

impl Default for ChannelMap {
    /// rig-log.md's convention.
    fn default() -> Self {
        ChannelMap {
            source: "default (rig-log.md)".into(),
            angle: Some(SignalSource::new("/rig/spindle", "angle_rad", "rad")),
            speed: Some(SignalSource::new("/rig/spindle", "speed_rpm", "rpm")),
            force: Some(SignalSource::new("/rig/force", "force_n", "N")),
            displacement: Some(SignalSource::new(
                "/rig/displacement",
                "displacement_mm",
                "mm",
            )),
            cycle: Some(SignalSource::new("/rig/cycle", "index", "")),
            images: Some(CAMERA_TOPIC.into()),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EntryToml {
    topic: String,
    field: Option<String>,
    unit: Option<String>,
    scale: Option<f64>,
    offset: Option<f64>,
}

impl ChannelMap {
    pub fn get(&self, kind: SignalKind) -> Option<&SignalSource> {
        match kind {
            SignalKind::Angle => self.angle.as_ref(),
            SignalKind::Speed => self.speed.as_ref(),
            SignalKind::Force => self.force.as_ref(),
            SignalKind::Displacement => self.displacement.as_ref(),
            SignalKind::Cycle => self.cycle.as_ref(),
        }
    }

    fn slot(&mut self, kind: SignalKind) -> &mut Option<SignalSource> {
        match kind {
            SignalKind::Angle => &mut self.angle,
            SignalKind::Speed => &mut self.speed,
            SignalKind::Force => &mut self.force,
            SignalKind::Displacement => &mut self.displacement,
            SignalKind::Cycle => &mut self.cycle,
        }
    }

    /// Whether this is the built-in convention (missing default topics are then warnings).
    pub fn is_default(&self) -> bool {
        *self == ChannelMap::default()
    }

    /// Reads a map from a TOML file (a map file or a session file with `[channels]`).
    pub fn from_file(path: &std::path::Path) -> Result<Self, LogError> {
        let name = path.display().to_string();
        let text = crate::input::read_text(path).map_err(|e| LogError::ChannelMap {
            source_name: name.clone(),
            message: format!("cannot read: {e}"),
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses a map from TOML text; `source_name` names it in messages.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Self, LogError> {
        let err = |message: String| LogError::ChannelMap {
            source_name: source_name.to_string(),
            message,
        };
        let doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| err(e.to_string()))?;
        let table = match doc.get("channels") {
            Some(toml::Value::Table(t)) => t.clone(),
            Some(_) => return Err(err("`channels` must be a table".into())),
            None => doc,
        };
        let mut map = ChannelMap {
            source: source_name.to_string(),
            angle: None,
            speed: None,
            force: None,
            displacement: None,
            cycle: None,
            images: None,
        };
        if let Some(inherit) = table.get("inherit") {
            match inherit.as_str() {
                Some("default") => {
                    let d = ChannelMap::default();
                    map = ChannelMap {
                        source: source_name.to_string(),
                        ..d
                    };
                }
                Some("none") => {}
                _ => return Err(err("`inherit` must be \"default\" or \"none\"".into())),
            }
        }
        for (key, value) in &table {
            if key == "inherit" {
                continue;
            }
            if key == "images" {
                let topic = value
                    .as_table()
                    .and_then(|t| t.get("topic"))
                    .and_then(|t| t.as_str())
                    .ok_or_else(|| err("[images] needs `topic = \"...\"`".into()))?;
                map.images = (!topic.is_empty()).then(|| topic.to_string());
                continue;
            }
            let Some(kind) = SignalKind::from_name(key) else {
                return Err(err(format!(
                    "unknown signal '{key}' (known: angle, speed, force, displacement, cycle, images, inherit)"
                )));
            };
            let entry: EntryToml = value
                .clone()
                .try_into()
                .map_err(|e: toml::de::Error| err(format!("[{key}]: {}", e.message())))?;
            if entry.topic.is_empty() {
                *map.slot(kind) = None;
                continue;
            }
            let unit = entry.unit.unwrap_or_else(|| kind.unit().to_string());
            let unit_factor = kind.unit_factor(&unit).ok_or_else(|| {
                err(format!(
                    "[{key}]: unit '{unit}' is not a {} unit pinsight knows",
                    key
                ))
            })?;
            let default_field = ChannelMap::default()
                .get(kind)
                .map(|s| s.field.clone())
                .unwrap_or_default();
            let field = entry.field.unwrap_or(default_field);
            if field.is_empty() {
                return Err(err(format!("[{key}]: `field` is empty")));
            }
            let scale = entry.scale.unwrap_or(1.0);
            let offset = entry.offset.unwrap_or(0.0);
            if !scale.is_finite() || scale == 0.0 || !offset.is_finite() {
                return Err(err(format!(
                    "[{key}]: scale must be finite and non-zero and offset finite (scale = {scale}, offset = {offset})"
                )));
            }
            *map.slot(kind) = Some(SignalSource {
                topic: entry.topic,
                field,
                unit,
                scale,
                offset,
                unit_factor,
            });
        }
        Ok(map)
    }

    /// The signals mapped to `topic`.
    pub fn signals_on(&self, topic: &str) -> Vec<(SignalKind, &SignalSource)> {
        SignalKind::ALL
            .into_iter()
            .filter_map(|k| self.get(k).filter(|s| s.topic == topic).map(|s| (k, s)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renamed_map_loads() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/interop/logs/run-1200-renamed.channels.toml"
        ))
        .unwrap();
        let m = ChannelMap::from_toml_str(&text, "renamed").unwrap();
        let f = m.force.as_ref().unwrap();
        assert_eq!(
            (f.topic.as_str(), f.field.as_str(), f.scale),
            ("/daq/ai0", "v", 10.0)
        );
        assert_eq!(f.convert(1.5), 15.0);
        let a = m.angle.as_ref().unwrap();
        assert_eq!(a.topic, "/enc/pos");
        assert!((a.convert(4096.0) - 2.0 * PI).abs() < 1e-12);
        assert!(m.speed.is_none() && m.cycle.is_none() && m.images.is_none());
        assert!(!m.is_default());
    }

    #[test]
    fn session_table_inherit_and_units() {
        let m = ChannelMap::from_toml_str(
            "[channels]\ninherit = \"default\"\n[channels.force]\ntopic = \"/lc\"\nfield = \"kn\"\nunit = \"kN\"\n",
            "session.toml",
        )
        .unwrap();
        assert_eq!(m.force.as_ref().unwrap().convert(0.002), 2.0);
        assert_eq!(m.angle, ChannelMap::default().angle);
        assert!(ChannelMap::default().is_default());
    }

    #[test]
    fn errors_name_the_problem() {
        let e = ChannelMap::from_toml_str("[forse]\ntopic = \"/x\"\n", "m.toml").unwrap_err();
        assert!(e.to_string().contains("unknown signal 'forse'"), "{e}");
        let e = ChannelMap::from_toml_str("[force]\ntopic = \"/x\"\nunit = \"lbf\"\n", "m.toml")
            .unwrap_err();
        assert!(e.to_string().contains("unit 'lbf'"), "{e}");
        let e = ChannelMap::from_toml_str("[force]\ntopic = \"/x\"\nscael = 2\n", "m.toml")
            .unwrap_err();
        assert!(e.to_string().contains("m.toml"), "{e}");
        let e = ChannelMap::from_toml_str("[force]\ntopic = \"/x\"\nscale = 0\n", "m.toml")
            .unwrap_err();
        assert!(e.to_string().contains("non-zero"), "{e}");
        assert!(ChannelMap::from_toml_str("not toml [", "m.toml").is_err());
    }
}
