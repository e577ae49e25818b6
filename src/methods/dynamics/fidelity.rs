//! Fidelity chosen across the study grid (`sim::fidelity`), and for
//! motor-driven heads with and without a flywheel (the fourth rung).

use crate::methods::Effort;
use crate::model::params::{Driver, Params};
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
    /// A motor-driven head (driver = motor): its flywheel, kg m², and the
    /// crank speed's first harmonic the ladder weighed, %.
    #[serde(default)]
    pub flywheel_kgm2: Option<f64>,
    #[serde(default)]
    pub speed_ripple_pct: Option<f64>,
}

pub fn fidelity_map(effort: Effort) -> Vec<FidelityCell> {
    let (cs, speeds): (Vec<f64>, Vec<f64>) = match effort {
        Effort::Quick => (vec![0.0005, 0.1], vec![1200.0]),
        Effort::Full => (
            vec![0.0001, 0.001, 0.01, 0.1, 0.3, 0.8],
            vec![1000.0, 1500.0, 2000.0],
        ),
    };
    // Motor-driven heads: the default motor without a flywheel, and with
    // one that holds the speed below what the spindle resolves.
    let motors: Vec<(f64, f64, f64)> = match effort {
        Effort::Quick => vec![(0.1, 1200.0, 0.0), (0.1, 1200.0, 0.05)],
        Effort::Full => vec![
            (0.0, 1200.0, 0.0),
            (0.1, 1200.0, 0.0),
            (0.1, 1200.0, 1e-3),
            (0.1, 1200.0, 0.05),
            (0.1, 2000.0, 0.0),
        ],
    };
    let cases = cs
        .iter()
        .flat_map(|&c| speeds.iter().map(move |&rpm| (c, rpm, None)))
        .chain(motors.into_iter().map(|(c, rpm, j)| (c, rpm, Some(j))));
    let mut out = Vec::new();
    for (c, rpm, fly) in cases {
        let mut p = Params::paper();
        p.clearance = c * 1e-3;
        p.motor_rpm = rpm;
        if let Some(j) = fly {
            p.driver = Driver::Motor;
            p.motor.flywheel_inertia = j;
        }
        if let Ok(r) = assess(&p, SceneResolution::default(), Method::Dop853) {
            out.push(FidelityCell {
                clearance_mm: c,
                motor_rpm: rpm,
                chosen: r.chosen,
                stroke_diff_mm: r.steps.get(1).and_then(|s| s.stroke_diff_mm),
                force_diff_n: r.steps.get(1).and_then(|s| s.force_diff_n),
                // The pane's row is (clearance, speed, level, reason): a
                // motor-driven head says so in its reason.
                reason: match fly {
                    Some(j) => format!("motor-driven, flywheel {j} kg m²: {}", r.reason),
                    None => r.reason,
                },
                flywheel_kgm2: fly,
                speed_ripple_pct: r.steps.get(2).and_then(|s| s.speed_ripple_pct),
            });
        }
    }
    out
}
