//! The engine: one layer under the three faces (command line, TUI panes,
//! batch scripts).
//!
//! It loads every kind of input into typed entries with their findings
//! ([`load`], [`entries`]) and runs every job to a serialisable result
//! ([`model`]: simulate, study, methods lab; [`vision`]: inspect, yield;
//! [`overlay`]: measured against predicted; [`calibrate`]: the model's
//! parameters fitted to a log; [`process`]: the monitor; [`trend`]: the
//! wear trend). The faces only parse options,
//! call a job, and print, draw or check its result, so the same inputs give
//! the same answer whichever face asked.
//!
//! The engine knows nothing of the terminal: it imports the analyses
//! (`overlay`, `vision`, `rig`, `sim`, `methods`) and nothing above them.

pub mod calibrate;
pub mod entries;
pub mod load;
pub mod model;
pub mod overlay;
pub mod process;
pub mod signals;
pub mod trend;
pub mod vision;
