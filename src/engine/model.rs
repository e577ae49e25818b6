//! The model jobs: a simulation at the chosen fidelity level (with the
//! fidelity assessment that says why), the parameter study, the quick
//! methods lab, and the model's predicted channels over time.
//!
//! Plain functions taking a [`Progress`] for a gauge and cancellation;
//! their results are plain data the Model, Study, Methods and Signals
//! panes show and the command line prints.

use super::signals::{Channel, SignalSet};
use crate::model::params::Params;
use crate::progress::Progress;
use crate::sim::fidelity::{FidelityReport, SceneResolution, assess};
use crate::sim::sweep::{SweepGrid, SweepResult, run_sweep};
use crate::sim::{Level, LevelChoice, SimOptions, SimResult, simulate};
use crate::solver::Method;
use serde::Serialize;

/// The latest model run: what was run and what came out.
#[derive(Debug, Clone, Serialize)]
pub struct ModelRun {
    pub params: Params,
    pub choice: String,
    pub level: Level,
    /// Why this level (forced by the user, or the fidelity chooser's reason).
    pub level_reason: String,
    pub options: SimOptions,
    pub result: SimResult,
    pub fidelity: Option<FidelityReport>,
}

/// Options of the study run from the Study pane or a batch step.
#[derive(Debug, Clone, Serialize)]
pub struct StudySetup {
    pub grid: SweepGrid,
    pub warmup: f64,
    pub revs: f64,
}

impl Default for StudySetup {
    /// The paper's study with the default protocol (2 warm-up + 3 reported
    /// revolutions per case).
    fn default() -> Self {
        Self {
            grid: SweepGrid::default(),
            warmup: 2.0,
            revs: 3.0,
        }
    }
}

/// The model's predicted channels over time (stroke, load-cell force, drive
/// torque, pin-bar speed), for the Signals pane when no log is loaded.
pub fn predicted_signals(run: &ModelRun) -> SignalSet {
    let mut channels = Vec::new();
    let mut cycles = Vec::new();
    if let Some(c) = &run.result.curves {
        let t0 = c.t_s.first().copied().unwrap_or(0.0);
        let t: Vec<f64> = c.t_s.iter().map(|t| t - t0).collect();
        let ch =
            |name: &str, unit: &str, v: &Vec<f64>| Channel::new(name, unit, t.clone(), v.clone());
        channels.push(ch("stroke", "mm", &c.stroke_mm));
        channels.push(ch("force", "N", &c.process_force_n));
        channels.push(ch("torque", "N·m", &c.torque_nm));
        channels.push(ch("speed", "m/s", &c.vel_mps));
        // A cycle starts at top dead centre, where the wrapped crank angle
        // passes the TDC angle (180° for zero offset; the smallest stroke).
        let period = run.params.period();
        if period > 0.0 && !t.is_empty() {
            // Find the first TDC (minimum stroke in the first period).
            let n1 = t.iter().take_while(|&&x| x < period).count().max(1);
            let i0 = (0..n1.min(c.stroke_mm.len()))
                .min_by(|&a, &b| c.stroke_mm[a].total_cmp(&c.stroke_mm[b]))
                .unwrap_or(0);
            let mut k = 0u64;
            let mut tc = t[i0];
            let end = t.last().copied().unwrap_or(0.0);
            while tc <= end + 1e-12 {
                cycles.push((tc, k));
                k += 1;
                tc = t[i0] + k as f64 * period;
            }
        }
    }
    SignalSet {
        source: format!(
            "model prediction ({} level, {}): no rig log loaded",
            run.level.name(),
            run.result.summary.view
        ),
        channels,
        cycles,
        meta: vec![
            ("preset".into(), run.params.preset.clone()),
            (
                "clearance".into(),
                format!("{} mm", run.params.clearance * 1e3),
            ),
            ("speed".into(), format!("{} rpm", run.params.motor_rpm)),
        ],
    }
}

/// Runs the model for the Model, Overlay and Signals panes: the fidelity
/// assessment (so the user sees which level the scene needs and why), then
/// the chosen or forced level over the default protocol (2 warm-up + 3
/// reported revolutions) with curves on a 0.5° grid.
pub fn run_model(
    params: &Params,
    choice: LevelChoice,
    progress: &Progress,
) -> Result<ModelRun, String> {
    params.validate().map_err(|e| e.to_string())?;
    progress.set_total(2);
    progress.set_done(0);
    progress.set_message("fidelity assessment");
    let fidelity = assess(params, SceneResolution::default(), Method::Dop853);
    progress.inc(1);
    if progress.is_cancelled() {
        return Err("cancelled".into());
    }
    let (level, level_reason, fidelity) = match (choice, fidelity) {
        (LevelChoice::Fixed(l), f) => (l, "forced by the user".to_string(), f.ok()),
        (LevelChoice::Auto, Ok(f)) => (f.chosen, f.reason.clone(), Some(f)),
        (LevelChoice::Auto, Err(e)) => (
            Level::Clearance,
            format!("the fidelity assessment failed ({e}); running the clearance level"),
            None,
        ),
    };
    let options = SimOptions {
        level,
        grid_deg: Some(0.5),
        record_events: true,
        ..SimOptions::default()
    };
    progress.set_message(format!("simulating ({} level)", level.name()));
    let result = simulate(params, &options, progress).map_err(|e| e.to_string())?;
    progress.inc(1);
    Ok(ModelRun {
        params: params.clone(),
        choice: match choice {
            LevelChoice::Auto => "auto".into(),
            LevelChoice::Fixed(l) => l.name().into(),
        },
        level,
        level_reason,
        options,
        result,
        fidelity,
    })
}

/// Runs the study (the paper's sweep by default) in parallel.
pub fn run_study(params: &Params, setup: &StudySetup, progress: &Progress) -> SweepResult {
    let opts = SimOptions {
        warmup: setup.warmup,
        revs: setup.revs,
        ..SimOptions::default()
    };
    progress.set_message(format!("study: {} cases", setup.grid.len()));
    run_sweep(params, &setup.grid, &opts, progress)
}

/// Runs the quick methods lab (seconds): work–precision, stability, long
/// run, step budgets, fidelity map; then the vision lab (localisers' speed
/// against error, where the pipeline breaks).
pub fn run_methods(progress: &Progress) -> MethodsLab {
    let dynamics =
        crate::methods::dynamics::run_dynamics_lab(crate::methods::Effort::Quick, None, progress);
    // The vision lab resets the progress total; cancelling stops it too.
    let vision = if progress.is_cancelled() {
        None
    } else {
        Some(crate::vision::lab::run_lab(
            crate::vision::lab::LabMode::Quick,
            progress,
        ))
    };
    MethodsLab { dynamics, vision }
}

/// Both labs of the Methods pane (the quick effort of `pinsight methods
/// dynamics` and `pinsight methods vision`).
#[derive(Debug, Clone)]
pub struct MethodsLab {
    pub dynamics: crate::methods::dynamics::DynamicsLab,
    /// None when the run was cancelled before the vision lab.
    pub vision: Option<crate::vision::lab::VisionLab>,
}
