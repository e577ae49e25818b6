//! Process monitoring in the line engineer's terms (issue 16): each cycle's
//! force curve judged against the evaluation objects of a process recipe,
//! as a press monitor does, and the process values' SPC.
//!
//! - [`recipe`]: the TOML process recipe (windows, thresholds, envelopes,
//!   value checks, SPC settings), validated with readable errors;
//! - [`curve`]: one cycle's force against stroke or crank angle, and the
//!   derived process values;
//! - [`objects`]: OK / NOK per object, with the reason and by how much;
//! - [`monitor`]: every cycle's verdict, envelopes learned from good
//!   cycles, SPC per value check;
//! - [`run`]: several logs' verdicts, totals and SPC (overall, by lot);
//! - [`report`]: the run as text and CSV;
//! - [`charts`]: control charts as PNG;
//! - [`qdas`]: the run as a Q-DAS ASCII transfer file (AQDEF `.dfq`);
//! - [`story`]: each connector's whole story (process verdict, vision
//!   verdict, the model's band) and the confusion of the two verdicts;
//! - [`synth`]: a faulty line for tests and demos (insertion faults in the
//!   force curve, the connectors' photographs, the truth of both);
//! - [`pin_spc`]: the SPC of the pins' positions on the connectors'
//!   photographs (dx, dy, radial offset, true position = 2 × offset,
//!   side-view height);
//! - [`serde_back`]: reading a run back from JSON (for `pinsight merge`);
//! - [`spc`]: capability (Cp, Cpk, Pp, Ppk), X̄/R and I-MR charts, the
//!   Western Electric rules.
//!
//! Knows nothing of files it did not open or of the terminal; the job is
//! `engine::process`, the command `pinsight monitor`.

pub mod charts;
pub mod curve;
pub mod monitor;
pub mod objects;
pub mod pin_spc;
pub mod qdas;
pub mod recipe;
pub mod report;
pub mod run;
pub mod serde_back;
pub mod spc;
pub mod story;
pub mod synth;

pub use monitor::{CycleStatus, CycleVerdict, MonitorReport, learn, monitor};
pub use recipe::ProcessRecipe;
