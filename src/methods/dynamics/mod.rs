//! The dynamics part of the methods lab.
//!
//! Everything here is measured on the real clearance model:
//! - **work–precision** in the deterministic window (model.md: figures
//!   converge with the tolerance there), every method over tolerances
//!   (fixed-step methods: step sizes), against a reference — DOP853 at
//!   rtol 1e-13, the best method at the tightest tolerance it reaches;
//! - **an outside reference**: the `ode_solvers` crate's DOP853 and DOPRI5
//!   on the same right-hand side, on a smooth free-flight scene (pure
//!   integrator comparison) and on a Hertz-contact scene run without event
//!   location (what events buy);
//! - **stability** of the fixed-step explicit methods: the largest step
//!   that stays stable and the largest that stays accurate as the contact
//!   stiffness and speed vary, beside the linear-stability prediction
//!   (the method's imaginary-axis limit / the contact frequency);
//! - **the long run**: prediction horizon against tolerance, and how the
//!   ensemble statistics converge with tolerance compared with their spread
//!   (the cheapest tolerance as good as the tightest is what sweeps use);
//! - **where the steps go** (contact vs free flight) and **how methods
//!   fail** (step underflow, too many steps, blow-up), reported, never hung;
//! - **fidelity** across the study grid (`sim::fidelity`).

mod budgets;
mod charts;
mod fidelity;
mod long_run;
mod outside;
mod scenes;
mod step_stability;
mod work_precision;

pub use budgets::*;
pub use fidelity::*;
pub use long_run::*;
pub use outside::*;
pub use scenes::*;
pub use step_stability::*;
pub use work_precision::*;

use crate::methods::Effort;
use crate::methods::stability::imaginary_axis_limit;
use crate::progress::Progress;
use crate::sim::ensemble::FIGURES;
use crate::solver::Method;
use serde::Serialize;
use std::time::Instant;

/// The whole dynamics lab.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicsLab {
    pub effort: Effort,
    pub references: Vec<Reference>,
    pub work_precision: Vec<WpPoint>,
    pub outside_reference: Vec<OutsidePoint>,
    pub stability: Vec<StabilityRow>,
    /// Imaginary-axis stability limits h·ω of the fixed-step formulas.
    pub imaginary_axis_limits: Vec<(String, Option<f64>)>,
    pub long_run: LongRun,
    pub step_budgets: Vec<StepBudget>,
    pub failures: Vec<FailureCase>,
    pub fidelity: Vec<FidelityCell>,
    pub wall_ms: f64,
}

/// Runs the whole lab; `custom` scenes replace the default ones in the
/// work–precision and step-budget studies.
pub fn run_dynamics_lab(
    effort: Effort,
    custom: Option<Vec<Scene>>,
    progress: &Progress,
) -> DynamicsLab {
    let start = Instant::now();
    let scene_list = custom.unwrap_or_else(|| scenes(effort));
    let n_scenes = scene_list.len() as u64;
    progress.set_total(n_scenes + if effort == Effort::Quick { 2 } else { 11 } + 8 + 3);
    progress.set_done(0);
    let (references, work_precision) = work_precision(effort, &scene_list, progress);
    progress.set_message("outside reference (ode_solvers)");
    let outside_reference = outside_reference(effort);
    progress.inc(1);
    let stability = stability_study(effort, progress);
    let long_run = long_run(effort, progress);
    progress.set_message("step budgets and failure modes");
    let (step_budgets, failures) = budgets_and_failures(&scene_list);
    progress.inc(1);
    progress.set_message("fidelity map");
    let fidelity = fidelity_map(effort);
    progress.inc(1);
    DynamicsLab {
        effort,
        references,
        work_precision,
        outside_reference,
        stability,
        imaginary_axis_limits: [Method::Rk4, Method::Dopri5, Method::Dop853, Method::Radau5]
            .iter()
            .map(|m| (m.name().to_string(), imaginary_axis_limit(*m)))
            .collect(),
        long_run,
        step_budgets,
        failures,
        fidelity,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

/// Figures of the ensemble, for completeness of the JSON.
pub fn all_figures() -> &'static [&'static str] {
    &FIGURES
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_file() {
        let s = scenes_from_toml(
            "[[scene]]\nname = \"a\"\nset = [\"clearance_mm=0.2\"]\n[[scene]]\npreset = \"flores\"\n",
        )
        .unwrap();
        assert_eq!(s.len(), 2);
        assert!((s[0].params.clearance - 0.2e-3).abs() < 1e-15);
        assert_eq!(s[1].params.preset, "flores");
        assert!(
            scenes_from_toml("[[scene]]\nset = [\"m4_kg=-1\"]")
                .unwrap_err()
                .contains("m4_kg")
        );
        assert!(scenes_from_toml("x = 1").is_err());
    }

    /// The quick work–precision: errors shrink as the tolerance tightens, the
    /// impact count is exact at tight tolerance, and every run reports work.
    #[test]
    fn quick_work_precision_is_consistent() {
        let (refs, pts) =
            work_precision(Effort::Quick, &scenes(Effort::Quick), &Progress::hidden());
        assert_eq!(refs.len(), 2);
        for sc in &refs {
            for m in ["dop853", "dopri5"] {
                let mine: Vec<&WpPoint> = pts
                    .iter()
                    .filter(|p| p.scene == sc.scene && p.method == m && p.failed.is_none())
                    .collect();
                assert!(mine.len() >= 4, "{m} on {}", sc.scene);
                let loose = mine.first().unwrap();
                let tight = mine.last().unwrap();
                assert!(
                    tight.stroke_err_mm < loose.stroke_err_mm,
                    "{m} {}: {loose:?} {tight:?}",
                    sc.scene
                );
                assert_eq!(tight.impact_count_error, 0, "{m} {}", sc.scene);
                assert!(tight.rhs_evals > loose.rhs_evals);
            }
        }
    }

    /// Below the predicted stable step RK4 stays stable; far above it fails.
    #[test]
    fn rk4_stability_limit_brackets_the_prediction() {
        let rows = stability_study(Effort::Quick, &Progress::hidden());
        let rk4: Vec<&StabilityRow> = rows.iter().filter(|r| r.method == "rk4").collect();
        assert!(!rk4.is_empty());
        for r in rk4 {
            let stable = r.measured_stable_step_s.expect("some step must be stable");
            assert!(stable >= 0.5 * r.predicted_stable_step_s, "{r:?}");
            let last = r.trials.last().unwrap();
            assert_ne!(
                last.1,
                Outcome::Accurate,
                "4× the limit cannot be accurate: {r:?}"
            );
        }
    }

    /// The outside reference agrees with ours on the smooth scene.
    #[test]
    fn outside_reference_agrees_on_the_smooth_scene() {
        let pts = outside_reference(Effort::Quick);
        for rtol in [1e-6, 1e-9] {
            let ours = pts
                .iter()
                .find(|p| p.solver == "pinsight dop853" && p.rtol == rtol)
                .unwrap();
            let theirs = pts
                .iter()
                .find(|p| {
                    p.solver == "ode_solvers dop853"
                        && p.rtol == rtol
                        && p.scene == "smooth free flight"
                })
                .unwrap();
            assert!(theirs.failed.is_none(), "{theirs:?}");
            // Same formula, same tolerance: errors within two orders of magnitude.
            assert!(
                ours.error <= 100.0 * theirs.error.max(1e-14),
                "{ours:?} vs {theirs:?}"
            );
            assert!(
                theirs.error <= 100.0 * ours.error.max(1e-14),
                "{ours:?} vs {theirs:?}"
            );
        }
        // The crate's DOP853 with time as its argument does not give the
        // right answer (its 12th stage sits at t, not t + h).
        let broken = pts
            .iter()
            .find(|p| p.solver == "ode_solvers dop853 (time as argument)")
            .unwrap();
        assert!(broken.failed.is_some() || broken.error > 1e-3, "{broken:?}");
    }
}
