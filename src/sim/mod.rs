//! The simulation protocol: warm-up revolutions, then the reported window;
//! summary figures, curves on a crank-angle grid, contact events, work.
//!
//! Entry point: [`simulate`]. Levels `kinematic` and `ideal` are closed form
//! evaluated on the crank-angle grid (their peaks refined by Brent's method);
//! `clearance` integrates the contact-impact model with event location
//! ([`clearance_run`]). Because the clearance motion is chaotic
//! (model.md), a single run past the first revolution is one realisation;
//! [`ensemble`] gives the statistics and the prediction horizon.

pub mod clearance_run;
pub mod curves;
pub mod ensemble;
pub mod fidelity;
pub mod ideal_run;
pub mod motor_run;
pub mod summary;
pub mod sweep;

use crate::model::params::{Driver, Params};
use crate::progress::Progress;
use crate::solver::{Method, Stats, StepError};
use serde::{Deserialize, Serialize};

pub use curves::Curves;
pub use summary::Summary;

/// Fidelity level (model.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    Kinematic,
    Ideal,
    Clearance,
    Motor,
}

impl Level {
    pub fn name(self) -> &'static str {
        match self {
            Level::Kinematic => "kinematic",
            Level::Ideal => "ideal",
            Level::Clearance => "clearance",
            Level::Motor => "motor",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim() {
            "kinematic" => Some(Level::Kinematic),
            "ideal" => Some(Level::Ideal),
            "clearance" => Some(Level::Clearance),
            "motor" => Some(Level::Motor),
            _ => None,
        }
    }
}

/// Level requested: a fixed one, or `auto` (the cheapest sufficient one, see [`fidelity`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LevelChoice {
    Auto,
    Fixed(Level),
}

impl LevelChoice {
    pub fn parse(s: &str) -> Option<Self> {
        if s.trim() == "auto" {
            Some(LevelChoice::Auto)
        } else {
            Level::parse(s).map(LevelChoice::Fixed)
        }
    }
}

/// How to run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimOptions {
    pub level: Level,
    pub method: Method,
    pub rtol: f64,
    /// Absolute tolerance (SI: m for positions, m/s for velocities).
    pub atol: f64,
    /// Fixed step (s): required meaning for RK4 (default period/20 000 when
    /// None); for the adaptive methods a given step switches error control off.
    pub step: Option<f64>,
    /// Warm-up revolutions (may be fractional).
    pub warmup: f64,
    /// Reported revolutions (may be fractional).
    pub revs: f64,
    /// Crank-angle spacing of the output curves in degrees (None: no curves).
    pub grid_deg: Option<f64>,
    /// Event location tolerance on |δ|, relative to the clearance.
    pub event_tol: f64,
    /// Offset of the pin bar's initial position (m), for ensemble realisations.
    pub perturb_x4: f64,
    /// Work budget of one run: steps (accepted + rejected, and event
    /// restarts) …
    pub max_steps: u64,
    /// … and wall-clock seconds. A run over either budget fails with where
    /// it was (time, crank angle, what ran out) instead of spinning.
    pub max_wall_s: f64,
    /// Keep the list of contact events.
    pub record_events: bool,
    /// Compute the summary's continuous-time figures: peaks refined on the
    /// dense output, the time averages of |Δs| and |Δv|, the ideal
    /// mechanism's peaks. An ensemble that only needs the curves (the
    /// calibration's and the overlay's predictions) turns them off: they
    /// cost about a tenth of such a run and do not touch the trajectory.
    /// Off, those figures read NaN. Not a user setting (never serialised).
    #[serde(skip, default = "figures_on")]
    pub figures: bool,
    /// Sample only the stroke and the process force on the crank-angle
    /// grid ([`Curves::push_lean`]: the other columns stay empty). The
    /// calibration's and the overlay's predictions read nothing else, and a
    /// full evaluation of the model at each of the 720 points of every
    /// revolution (the joint's forces, the rod, the ideal mechanism beside)
    /// was a tenth of a calibration. The same numbers either way. Not a
    /// user setting (never serialised).
    #[serde(skip)]
    pub lean_curves: bool,
}

fn figures_on() -> bool {
    true
}

/// The wall-clock deadline of all model work in this process, from the
/// environment variable `PINSIGHT_MAX_WALL_S` (seconds, counted from the
/// first call; the command line calls it at start-up). An unattended job
/// (CI, a line PC) sets it to be sure a command ends: every simulation
/// running past it fails with "work budget exceeded", a sweep records the
/// cases that did not run in time as failed and writes the others. Unset,
/// zero or not a number: no deadline beyond each run's own
/// [`SimOptions::max_wall_s`].
pub fn process_deadline() -> Option<std::time::Instant> {
    static DEADLINE: std::sync::OnceLock<Option<std::time::Instant>> = std::sync::OnceLock::new();
    *DEADLINE.get_or_init(|| {
        let s: f64 = std::env::var("PINSIGHT_MAX_WALL_S")
            .ok()?
            .trim()
            .parse()
            .ok()?;
        (s.is_finite() && s > 0.0)
            .then(|| std::time::Instant::now() + std::time::Duration::from_secs_f64(s.min(1e9)))
    })
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            level: Level::Clearance,
            method: Method::Dop853,
            rtol: 1e-8,
            atol: 1e-14,
            step: None,
            warmup: 2.0,
            revs: 3.0,
            grid_deg: None,
            event_tol: 1e-9,
            perturb_x4: 0.0,
            max_steps: 50_000_000,
            max_wall_s: 300.0,
            record_events: false,
            figures: true,
            lean_curves: false,
        }
    }
}

impl SimOptions {
    /// The deterministic window of model.md: from the start, half a revolution.
    pub fn deterministic_window(rtol: f64) -> Self {
        Self {
            warmup: 0.0,
            revs: 0.5,
            rtol,
            record_events: true,
            ..Self::default()
        }
    }

    pub fn validate(&self) -> Result<(), SimError> {
        use crate::fmt::fmt_num;
        let bad = |what: &str, v: String, allowed: &str| {
            Err(SimError::Options(format!(
                "invalid {what}: {v} (allowed: {allowed})"
            )))
        };
        if !(self.rtol > 0.0 && self.rtol < 1.0) {
            return bad("rtol", fmt_num(self.rtol), "0 < rtol < 1");
        }
        if !(self.atol >= 0.0) || !self.atol.is_finite() {
            return bad("atol", fmt_num(self.atol), "≥ 0");
        }
        if let Some(h) = self.step
            && (!(h > 0.0) || !h.is_finite())
        {
            return bad("step", fmt_num(h), "> 0 s");
        }
        if !(self.warmup >= 0.0) || !self.warmup.is_finite() {
            return bad("warmup", fmt_num(self.warmup), "≥ 0 revolutions");
        }
        // Below a thousandth of a revolution (0.36° of crank) no figure of
        // the summary is defined.
        if !(self.revs >= 1e-3) || !self.revs.is_finite() || self.revs > 1e6 {
            return bad("revs", fmt_num(self.revs), "1e-3 ≤ revs ≤ 1e6 revolutions");
        }
        if let Some(g) = self.grid_deg {
            if !(g > 0.0) || g > 360.0 {
                return bad("grid", fmt_num(g), "0 < grid ≤ 360 degrees");
            }
            let n = self.revs * 360.0 / g;
            if n > 5e7 {
                return bad("grid", format!("{n:.0} points"), "at most 5e7 points");
            }
        }
        if !(self.event_tol > 0.0 && self.event_tol <= 1e-5) {
            return bad(
                "event_tol",
                crate::fmt::fmt_num(self.event_tol),
                "0 < event_tol ≤ 1e-5 (relative to c)",
            );
        }
        Ok(())
    }

    /// Whether this run is the deterministic window or one realisation.
    pub fn view(&self) -> &'static str {
        if self.warmup == 0.0 && self.revs <= 1.0 {
            "deterministic window"
        } else {
            "single realisation"
        }
    }
}

/// A located contact event.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactEvent {
    /// true: onset (impact), false: loss of contact.
    pub onset: bool,
    pub t_s: f64,
    pub crank_deg: f64,
    /// Penetration rate at the event (m/s): the approach velocity at an onset.
    pub delta_dot_mps: f64,
    /// |δ| at the located point, relative to the clearance.
    pub residual_rel: f64,
    pub in_report: bool,
}

/// The result of one run.
#[derive(Debug, Clone, Serialize)]
pub struct SimResult {
    pub summary: Summary,
    pub curves: Option<Curves>,
    pub events: Vec<ContactEvent>,
    pub stats: Stats,
    /// Remarks for the user (level fallbacks, guards that fired …).
    pub notes: Vec<String>,
}

/// Why a simulation could not run or finish.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Params(#[from] crate::model::params::ParamError),
    #[error("{0}")]
    Options(String),
    #[error("{0}")]
    Unsupported(String),
    #[error(
        "integration failed at t = {t:.9} s (crank angle {crank_deg:.3}°, penetration {penetration_um:.4} µm, {mode}): {source}"
    )]
    Integration {
        source: StepError,
        t: f64,
        crank_deg: f64,
        penetration_um: f64,
        mode: &'static str,
    },
    #[error(
        "blow-up at t = {t:.9} s (crank angle {crank_deg:.3}°): penetration {penetration_um:.4e} µm exceeds the journal radius — the step is beyond the method's stability limit for this contact stiffness"
    )]
    BlowUp {
        t: f64,
        crank_deg: f64,
        penetration_um: f64,
    },
    #[error(
        "too many contact events ({0}) — the contact chatters; loosen event tolerance or check parameters"
    )]
    EventStorm(u64),
    #[error(
        "work budget exceeded at t = {t:.9} s (crank angle {crank_deg:.3}°): {what} — the run was stopped instead of spinning; check the parameters (a clearance or contact stiffness far from any real joint) or raise the budget"
    )]
    Budget {
        t: f64,
        crank_deg: f64,
        what: String,
    },
    #[error(
        "the run produced a non-finite {0} (NaN or infinite): no figure is reported; check the parameters (values far from any real mechanism)"
    )]
    NonFinite(&'static str),
    #[error(
        "the motor stalls at {crank_deg:.0}° of crank angle (after top dead centre) in revolution {revolution} (t = {t:.4} s; the crank's speed fell below {fraction_pct}% of its operating speed): the motor gives {motor_torque_nm:.4} N·m where the mechanism demands {demand_nm:.4} N·m at the crank — a stronger motor, a larger flywheel or a higher gear ratio is needed"
    )]
    Stall {
        t: f64,
        /// Crank angle after top dead centre where the crank stopped, degrees.
        crank_deg: f64,
        /// The revolution (1 = the first) in which it stopped.
        revolution: u64,
        /// Motor torque at its shaft at the stop, N·m.
        motor_torque_nm: f64,
        /// Drive torque the mechanism demanded at the crank at the stop, N·m.
        demand_nm: f64,
        /// The stall speed as a percentage of the operating speed.
        fraction_pct: f64,
    },
    #[error("cancelled")]
    Cancelled,
}

/// Runs one simulation at the level in `opts`. A run whose figures are not
/// all finite is an error ([`SimError::NonFinite`]), never a result.
pub fn simulate(p: &Params, opts: &SimOptions, progress: &Progress) -> Result<SimResult, SimError> {
    let r = simulate_unchecked(p, opts, progress)?;
    // Without the figures (NaN by design) the curves carry the run.
    let bad = if opts.figures {
        r.summary.non_finite()
    } else {
        r.curves
            .as_ref()
            .is_some_and(|c| c.stroke_mm.iter().any(|x| !x.is_finite()))
            .then_some("stroke_mm")
    };
    match bad {
        Some(figure) => Err(SimError::NonFinite(figure)),
        None => Ok(r),
    }
}

fn simulate_unchecked(
    p: &Params,
    opts: &SimOptions,
    progress: &Progress,
) -> Result<SimResult, SimError> {
    p.validate()?;
    opts.validate()?;
    if opts.level == Level::Motor {
        return motor_run::run(p, opts, progress);
    }
    // A motor-driven head below the motor level: constant speed, at the
    // motor's operating speed.
    let (q, note) = if p.driver == Driver::Motor {
        let (q, _) = motor_run::operating_params(p);
        let note = format!(
            "driver = motor: at level {} the crank turns at the motor's operating speed, {:.3} rev/min of the motor, constant",
            opts.level.name(),
            q.motor_rpm
        );
        (q, Some(note))
    } else {
        (p.clone(), None)
    };
    let p = &q;
    let mut r = match opts.level {
        Level::Kinematic | Level::Ideal => ideal_run::run(p, opts),
        Level::Clearance if p.clearance == 0.0 => {
            let mut o = opts.clone();
            o.level = Level::Ideal;
            let mut r = ideal_run::run(p, &o);
            r.notes.push(
                "clearance_mm = 0: the joint is ideal, so the clearance level equals the ideal one"
                    .into(),
            );
            r
        }
        Level::Clearance => clearance_run::run(p, opts, progress)?,
        Level::Motor => unreachable!("run above"),
    };
    r.notes.extend(note);
    Ok(r)
}

/// Wraps a crank angle in radians to [0, 360) degrees.
pub(crate) fn wrap_deg(theta: f64) -> f64 {
    theta.to_degrees().rem_euclid(360.0)
}
