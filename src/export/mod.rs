//! Results in the formats of the tools a line already runs: MCAP for
//! Foxglove ([`mcap`]), Parquet for a plant's data tools ([`parquet`]). Each exporter is a pure function from a result to
//! the file's bytes; the command that asked writes them atomically.

pub mod mcap;
pub mod parquet;
