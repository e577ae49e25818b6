//! # pinsight
//!
//! A terminal workstation for continuous pin-insertion lines: the
//! clearance-joint dynamics of the crank – connecting rod – pin bar mechanism,
//! rig logs (MCAP) compared cycle by cycle with the model, a pin-position /
//! defect vision pipeline with yield reports, and a TUI whose every pane also
//! runs headless.
//!
//! Layout (each module knows nothing of the terminal unless it says so):
//!
//! | module | holds |
//! |---|---|
//! | [`model`] | mechanism parameters, presets, materials, kinematics, kinetostatics, contact laws, the clearance ODE |
//! | [`solver`] | integrators (RK4, Dormand–Prince 5(4) and 8(5,3) with dense output, Radau IIA), event location, work counters |
//! | [`sim`] | the simulation protocol (warmup + reported revolutions), summary figures, ensembles, prediction horizon, the parameter sweep |
//! | [`rig`] | rig logs: MCAP loading, channel maps, signals, cycles |
//! | [`overlay`] | measured vs predicted per cycle, residuals, calibration |
//! | [`process`] | process monitoring: evaluation objects on each cycle's force curve (OK/NOK with reasons), SPC (Cp/Cpk, X̄/R, run rules) |
//! | [`vision`] | connector images: recipes, pin detection, grid fit, verdicts, yield |
//! | [`methods`] | the methods lab: work–precision, stability, fidelity |
//! | [`engine`] | the one layer under the faces: loading every input, running every job |
//! | [`fmt`] | numbers as messages name them |
//! | [`plant`] | plant scale: `--shard k/n` partition of a batch (Kubernetes Indexed Jobs, Slurm arrays) |
//! | [`plot`] | PNG charts with an embedded font (no system fonts needed) |
//! | [`export`] | results in other tools' formats: MCAP that Foxglove shows (overlay, inspections, simulations) |
//! | [`output`] | every file written: atomic single files, multi-file reports complete or unchanged |
//! | [`allocator`] | the C allocator tuned per kind of run: a shift of following (flat memory) or a batch (no page faults per image) |
//! | [`progress`] | progress and cancellation shared by batch bars and TUI gauges |
//! | [`panes`] | view models: one pure function per pane from session state to plain data |
//! | [`tui`] | the terminal front end (ratatui + crossterm), drawing view models only |
//! | [`batch`] | headless rendering of panes and batch scripts with checks |
//! | [`cli`] | the `pinsight` command line |

// Numerical code: `!(x > 0.0)` is how a validation also rejects NaN, and
// kernels index several arrays in lock step.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod allocator;
pub mod batch;
pub mod cli;
pub mod engine;
pub mod export;
pub mod fmt;
pub mod input;
pub mod live;
pub mod methods;
pub mod model;
pub mod output;
pub mod overlay;
pub mod panes;
pub mod plant;
pub mod plot;
pub mod process;
pub mod progress;
pub mod rig;
pub mod rng;
pub mod sim;
pub mod solver;
pub mod tui;
pub mod vision;
pub mod wear;
