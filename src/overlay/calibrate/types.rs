//! What a calibration is asked ([`CalibrateOptions`], with the settings
//! its ensembles and fits run at) and what it answers ([`Estimate`],
//! [`Residuals`], [`CalibrationReport`]): the types, beside the procedure
//! in `mod.rs`.

use super::super::predict::PredictOptions;
use crate::model::Params;
use crate::solver::Method;
use serde::Serialize;

/// How to calibrate.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrateOptions {
    pub predict: PredictOptions,
    /// Clearances simulated (mm); the nominal one is added.
    pub clearance_grid_mm: Vec<f64>,
    /// Jackknife blocks (of measured cycles and of simulated revolutions).
    pub blocks: usize,
    /// Fit the F_ins table (else only standoff and lag with the nominal table).
    pub fit_f_ins: bool,
    /// The fine grid around the coarse estimate c0: c0 × these factors …
    pub refine_factors: Vec<f64>,
    /// … each simulated for this many revolutions per measured cycle, within (min, max).
    pub refine_cycles_factor: usize,
    pub refine_revs: (usize, usize),
    /// Also fit the flywheel inertia to the logged crank speed ripple (the
    /// motor level, [`flywheel`]); the parameters then say driver = "motor".
    pub flywheel: bool,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            predict: PredictOptions {
                revs: 48,
                rtol: ENSEMBLE_RTOL,
                method: ENSEMBLE_METHOD,
                ..PredictOptions::default()
            },
            clearance_grid_mm: vec![0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0],
            blocks: 8,
            fit_f_ins: true,
            refine_factors: vec![0.76, 0.87, 1.0, 1.15, 1.32],
            refine_cycles_factor: 5,
            refine_revs: (120, 800),
            flywheel: false,
        }
    }
}

/// One estimated quantity.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    pub name: String,
    pub unit: String,
    /// The value before calibration (metadata / parameter file / default).
    pub nominal: Option<f64>,
    pub value: f64,
    /// Standard uncertainty.
    pub sigma: f64,
    /// Expanded uncertainty (~95 %): t₉₅(ν)·σ for the clearance (see the
    /// module docs), 2σ for the others.
    pub u95: f64,
    pub method: String,
}

/// How well a parameter set explains the log.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Residuals {
    /// RMS over φ of measured − predicted spread of the stroke across cycles (mm).
    pub stroke_spread_rms_mm: f64,
    /// RMS over φ of measured − predicted mean stroke (mm).
    pub stroke_mean_rms_mm: f64,
    /// RMS of measured − predicted force over the fitted samples (N).
    pub force_rms_n: f64,
}

/// The result of a calibration.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationReport {
    pub file: String,
    pub motor_rpm: f64,
    pub cycles: usize,
    pub estimates: Vec<Estimate>,
    /// Fitted F_ins table: (depth mm, force N, σ N).
    pub f_ins_table: Vec<(f64, f64, f64)>,
    pub before: Residuals,
    pub after: Residuals,
    /// Objective of the stroke fit against clearance (the profile searched).
    pub clearance_profile: Vec<(f64, f64)>,
    /// The calibrated model parameters.
    pub params: Params,
    /// The parameter file written (TOML that `simulate` and `overlay` read).
    pub params_toml: String,
    pub notes: Vec<String>,
}

/// The integrator's relative tolerance for the calibration's ensembles.
/// Only statistics over many revolutions are compared (mean and spread per
/// crank angle), and those converge at loose tolerances long before single
/// trajectories do (the methods lab's long run; the mean spread of 6 runs ×
/// 300 revolutions at 0.45 mm is 0.1763 mm at 1e-6 and 0.1764 at 1e-8, at
/// 0.3 mm the same to 0.1 % down to 1e-3). 1e-4 instead of the overlay's 1e-6
/// saves a quarter of the model time; the paired comparison over the
/// coverage sweep's logs is in docs/rig-logs.md.
pub(super) const ENSEMBLE_RTOL: f64 = 1e-4;

/// The integrator of the calibration's ensembles: DOPRI5, the fifth-order
/// pair. At the ensembles' loose tolerance its cheaper step (6 right-hand
/// sides against 12) outweighs its shorter steps: 94 against 113 ms over
/// 100 revolutions at 0.3 mm, and a calibration takes 0.83× the time. The
/// statistics it gives are as good (over the coverage sweep's 260 logs:
/// 260/260 inside U95 with DOPRI5 alone, 257/260 together with the single
/// fine stage, against 258/260 before; docs/rig-logs.md, "Sixth round").
/// The overlay's single trajectories stay on DOP853.
pub(super) const ENSEMBLE_METHOD: Method = Method::Dopri5;

/// The coarse grid's scout round runs every node for this fraction of the
/// coarse revolutions (48 / 4 = 12): enough to place the stroke fit's
/// minimum within a node or two, not to fit it.
pub(super) const SCOUT_FRACTION: usize = 4;

/// The scout's estimate is off by a few per cent (a quarter-length
/// ensemble; its windowed spread is biased low against long logs): the
/// range the fine grid will span is widened by this factor each way before
/// the coarse nodes that run at full length are chosen ([`scout_near`]).
pub(super) const SCOUT_MARGIN: f64 = 1.25;

/// Tolerances of the force fit's searches (each nested: the standoff
/// inside, the load cell's lag outside; Brent's method, whose bracket ends
/// within about four times these): 0.1 µm of standoff and 0.1 µs of lag,
/// far under a fiftieth of their σ (~0.02 mm; the lag's is tens of µs,
/// 80–170 µs on the trend benchmark's logs). The lag's was 0.01 µs until
/// the tenth round: 28 % more evaluations for digits below its noise.
/// (They were golden sections of 19 and 15 iterations, brackets of 0.4 µm
/// and 0.04–0.09 µs: ~420 and ~270 evaluations of the whole force record
/// per search, a quarter of a calibration's CPU; docs/rig-logs.md.)
pub(super) const FORCE_TOL_STANDOFF_MM: f64 = 1e-4;
pub(super) const FORCE_TOL_TAU_S: f64 = 1e-7;
