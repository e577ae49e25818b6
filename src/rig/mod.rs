//! Rig logs: MCAP loading, channel maps, signals, cycles.
//!
//! Entry points:
//! - [`load`]`(path, &LoadOptions, &Progress) -> Result<RigLog, LogError>`:
//!   everything in a log as plain data (signals, metadata, attachments,
//!   image list, load report with every finding).
//! - [`images::read_images`]`(path)`: the decoded connector images.
//!
//! Modules: [`mcap_read`] (crash-proof container reading), [`channel_map`],
//! [`json`] + [`decode`] (messages → samples), [`signals`] (sorted sample
//! arrays and their stream checks), [`meta`] (`rig` metadata), [`images`],
//! [`report`] (findings and status), [`load`] (the orchestration).

pub mod channel_map;
pub mod cycles;
pub mod decode;
pub mod error;
pub mod images;
pub mod json;
pub mod load;
pub mod mcap_read;
pub mod meta;
pub mod report;
pub mod signals;
pub mod summary;
pub mod synth;

pub use channel_map::{ChannelMap, SignalKind, SignalSource};
pub use cycles::{Cycle, CycleOptions, CycleSet, analyse};
pub use error::LogError;
pub use images::{LogImage, read_images};
pub use load::{ImageRef, LoadOptions, LogAttachment, RigLog, Signals, load, load_source};
pub use mcap_read::ReadOptions;
pub use meta::RigMeta;
pub use report::{Finding, FindingCode, LoadReport, LoadStatus, Severity};
pub use signals::{Signal, SignalStats};
