//! Fidelity chosen across the study grid (`sim::fidelity`).

use crate::methods::Effort;
use crate::model::params::Params;
use crate::sim::Level;
use crate::sim::fidelity::{SceneResolution, assess};
use crate::solver::Method;
use serde::{Deserialize, Serialize};

/// Fidelity chosen across a clearance × speed grid (nominal material).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FidelityCell {
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub chosen: Level,
    pub stroke_diff_mm: Option<f64>,
    pub force_diff_n: Option<f64>,
    pub reason: String,
}

pub fn fidelity_map(effort: Effort) -> Vec<FidelityCell> {
    let (cs, speeds): (Vec<f64>, Vec<f64>) = match effort {
        Effort::Quick => (vec![0.0005, 0.1], vec![1200.0]),
        Effort::Full => (
            vec![0.0001, 0.001, 0.01, 0.1, 0.3, 0.8],
            vec![1000.0, 1500.0, 2000.0],
        ),
    };
    let mut out = Vec::new();
    for &c in &cs {
        for &rpm in &speeds {
            let mut p = Params::paper();
            p.clearance = c * 1e-3;
            p.motor_rpm = rpm;
            if let Ok(r) = assess(&p, SceneResolution::default(), Method::Dop853) {
                out.push(FidelityCell {
                    clearance_mm: c,
                    motor_rpm: rpm,
                    chosen: r.chosen,
                    stroke_diff_mm: r.steps.get(1).and_then(|s| s.stroke_diff_mm),
                    force_diff_n: r.steps.get(1).and_then(|s| s.force_diff_n),
                    reason: r.reason,
                });
            }
        }
    }
    out
}
