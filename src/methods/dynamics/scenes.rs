//! Scenes of the dynamics lab: the built-in sets (quick and full) and
//! scenes read from a TOML file.

use crate::methods::Effort;
use crate::model::params::Params;
use serde::Serialize;

/// A named parameter set.
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    pub name: String,
    #[serde(skip)]
    pub params: Params,
}

pub(super) fn paper_scene(c_mm: f64, rpm: f64, material: &str) -> Scene {
    let mut p = Params::paper();
    p.clearance = c_mm * 1e-3;
    p.motor_rpm = rpm;
    let _ = p.set_str("material", material);
    Scene {
        name: format!("paper c={c_mm} mm {rpm} rpm {material}"),
        params: p,
    }
}

/// The scenes of the issue: the paper preset at c = 0.1 and 0.8 mm, 1000
/// and 2000 rpm, alloy steel and tungsten carbide, and the flores preset.
pub fn scenes(effort: Effort) -> Vec<Scene> {
    let flores = Scene {
        name: "flores c=0.5 mm 5000 rpm".into(),
        params: Params::flores(),
    };
    match effort {
        Effort::Quick => vec![paper_scene(0.1, 1000.0, "alloy_steel"), flores],
        Effort::Full => {
            let mut v = Vec::new();
            for c in [0.1, 0.8] {
                for rpm in [1000.0, 2000.0] {
                    for m in ["alloy_steel", "tungsten_carbide"] {
                        v.push(paper_scene(c, rpm, m));
                    }
                }
            }
            v.push(flores);
            v
        }
    }
}

/// Reads scenes from TOML: `[[scene]]` tables with `name`, an optional
/// `preset` and an optional `set = ["key=value", …]` list.
pub fn scenes_from_toml(text: &str) -> Result<Vec<Scene>, String> {
    let t: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
    let list = t
        .get("scene")
        .and_then(|v| v.as_array())
        .ok_or("expected [[scene]] tables")?;
    let mut out = Vec::new();
    for (i, v) in list.iter().enumerate() {
        let tab = v.as_table().ok_or(format!("scene {i} is not a table"))?;
        let name = tab
            .get("name")
            .and_then(|x| x.as_str())
            .map(str::to_string)
            .unwrap_or_else(|| format!("scene {i}"));
        let preset = tab
            .get("preset")
            .and_then(|x| x.as_str())
            .unwrap_or("paper");
        let mut p = Params::preset(preset).map_err(|e| format!("scene `{name}`: {e}"))?;
        let sets: Vec<String> = tab
            .get("set")
            .and_then(|x| x.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        p.apply_overrides(&sets)
            .map_err(|e| format!("scene `{name}`: {e}"))?;
        out.push(Scene { name, params: p });
    }
    if out.is_empty() {
        return Err("no scenes".into());
    }
    Ok(out)
}
