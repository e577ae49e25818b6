//! The load report: what was found while reading a rig log.
//!
//! Every problem is a [`Finding`] whose `message` is a complete sentence a
//! technician can read on its own: it names the file, the channel (topic and
//! signal) and the place (byte offset in the file and/or log time). The
//! structured fields beside it (`code`, `channel`, `place`, `count`) are for
//! programs (tests, batch checks, the TUI's Session pane).
//!
//! The overall [`LoadStatus`] follows from the worst finding:
//! `info` → `ok`, `warning` → `ok_with_warnings`, `data_loss` → `partial`,
//! `error` → `error` (nothing usable was loaded).

use serde::Serialize;

/// How bad a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Worth knowing, nothing wrong (e.g. the file was not in time order and was sorted).
    Info,
    /// The data is usable but flawed (gaps, NaN samples, a missing channel).
    Warning,
    /// Part of the file could not be read (truncation, a corrupt chunk): the result is partial.
    DataLoss,
    /// Nothing usable could be loaded.
    Error,
}

/// Overall status of a load.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadStatus {
    Ok,
    OkWithWarnings,
    Partial,
    Error,
}

impl LoadStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            LoadStatus::Ok => "ok",
            LoadStatus::OkWithWarnings => "ok_with_warnings",
            LoadStatus::Partial => "partial",
            LoadStatus::Error => "error",
        }
    }
}

impl std::fmt::Display for LoadStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What a finding is about (stable identifiers for programs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FindingCode {
    /// The file ends inside a record (no footer / end magic).
    Truncated,
    /// Messages were recovered from a chunk cut by the truncation (CRC not verifiable).
    PartialChunkRecovered,
    /// A record's length field is impossible (runs past the end of the file).
    CorruptRecord,
    /// A chunk's CRC does not match its content: the chunk is dropped.
    BadChunkCrc,
    /// The data section CRC (DataEnd) does not match.
    BadDataCrc,
    /// The summary section CRC does not match: the summary is ignored.
    BadSummaryCrc,
    /// An attachment's CRC does not match.
    BadAttachmentCrc,
    /// A chunk could not be decompressed.
    ChunkDecompress,
    /// A chunk uses a compression pinsight cannot decode.
    UnknownCompression,
    /// A record is larger than the configured record-length limit.
    RecordTooLarge,
    /// A record with an unknown opcode was skipped.
    UnknownRecord,
    /// The file has no summary section (read linearly).
    NoSummary,
    /// The summary's statistics disagree with what was read.
    SummaryMismatch,
    /// Two definitions of the same channel or schema id disagree.
    ChannelConflict,
    /// A message refers to a channel that is never defined.
    UnknownChannel,
    /// A channel's message encoding is not one pinsight decodes.
    UnknownEncoding,
    /// A signal of the channel map has no channel in the file.
    MissingChannel,
    /// A signal is derived from another one (speed from the angle, cycles from the angle).
    DerivedSignal,
    /// A channel in the file is not used by the channel map.
    UnusedChannel,
    /// Messages lack the mapped JSON field.
    MissingField,
    /// A message's shape does not match its channel (a block on a scalar channel or the reverse).
    WrongShape,
    /// A message is not valid JSON.
    MalformedMessage,
    /// Samples written as NaN, null or ±Infinity, or not a number: missing samples.
    InvalidSamples,
    /// Several samples share a timestamp: the first is kept.
    DuplicateTimestamps,
    /// A gap in a channel's samples.
    Gap,
    /// A channel's log_time steps back in file order (clock jump).
    TimeBackwards,
    /// Messages are not in log_time order in the file (they were sorted).
    OutOfOrder,
    /// A block's `t0_ns` differs from its message log_time.
    BlockTimeMismatch,
    /// A channel has no samples at all.
    EmptyChannel,
    /// A channel carries blocks of samples.
    BlockMessages,
    /// A metadata value could not be understood.
    Metadata,
    /// The `rig` metadata record is missing.
    MetadataMissing,
    /// An attachment (recipe, parameter file) is present.
    Attachment,
    /// Images on the camera topic.
    Images,
    /// The user cancelled the load.
    Cancelled,
    /// An internal error was caught (a bug in pinsight): the item is skipped.
    InternalError,
    /// The crank angle and the cycle marks disagree.
    AngleMismatch,
    /// A sensor offset (angle zero, laser zero mark, force tare) was estimated.
    OffsetEstimated,
    /// A cycle-level problem (missing cycle mark, too few samples, speed outside range).
    Cycle,
}

/// Where in the file / in time a finding is.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Place {
    /// Byte offset in the file (start of the record concerned).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub byte_offset: Option<u64>,
    /// log_time (ns since the Unix epoch) of the first sample concerned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_time_ns: Option<i64>,
    /// log_time of the last sample concerned (ranges such as gaps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_log_time_ns: Option<i64>,
}

impl Place {
    pub fn byte(offset: u64) -> Self {
        Place {
            byte_offset: Some(offset),
            ..Place::default()
        }
    }
    pub fn time(t: i64) -> Self {
        Place {
            log_time_ns: Some(t),
            ..Place::default()
        }
    }
    pub fn span(t0: i64, t1: i64) -> Self {
        Place {
            log_time_ns: Some(t0),
            end_log_time_ns: Some(t1),
            ..Place::default()
        }
    }
}

/// One thing found while loading.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    pub severity: Severity,
    pub code: FindingCode,
    /// The file the finding is about.
    pub file: String,
    /// Topic (and signal) concerned, when the finding is about a channel.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub place: Option<Place>,
    /// How many items (samples, messages, bytes) are concerned, when that is meaningful.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub count: Option<u64>,
    /// The full sentence: names the file, the channel and the place.
    pub message: String,
}

impl Finding {
    /// A finding whose message is `"{file}: {channel}: {text}"` (channel part omitted when none).
    pub fn new(
        severity: Severity,
        code: FindingCode,
        file: &str,
        channel: Option<&str>,
        place: Option<Place>,
        text: impl AsRef<str>,
    ) -> Self {
        let message = match channel {
            Some(c) => format!("{file}: {c}: {}", text.as_ref()),
            None => format!("{file}: {}", text.as_ref()),
        };
        Finding {
            severity,
            code,
            file: file.to_string(),
            channel: channel.map(str::to_string),
            place,
            count: None,
            message,
        }
    }

    pub fn with_count(mut self, n: u64) -> Self {
        self.count = Some(n);
        self
    }
}

/// The status that a set of findings implies.
pub fn status_of(findings: &[Finding]) -> LoadStatus {
    match findings.iter().map(|f| f.severity).max() {
        None | Some(Severity::Info) => LoadStatus::Ok,
        Some(Severity::Warning) => LoadStatus::OkWithWarnings,
        Some(Severity::DataLoss) => LoadStatus::Partial,
        Some(Severity::Error) => LoadStatus::Error,
    }
}

/// Formats a log time for messages: the absolute ns value (what the file
/// holds, so it can be searched for) and the offset from the log start.
pub fn fmt_time(t_ns: i64, log_start_ns: Option<i64>) -> String {
    match log_start_ns {
        Some(t0) => format!("log_time {t_ns} ns (t{:+.4} s)", (t_ns - t0) as f64 * 1e-9),
        None => format!("log_time {t_ns} ns"),
    }
}

/// Counts of chunks and messages read.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ReadCounts {
    /// Chunks found (by the linear scan and the summary's chunk index).
    pub chunks: u64,
    /// Chunks whose messages were all read.
    pub chunks_read: u64,
    /// Chunks that could not be read (bad CRC, corrupt, unknown compression).
    pub chunks_failed: u64,
    /// Messages read (all channels).
    pub messages: u64,
    /// Bytes of the file covered by records that were read.
    pub bytes_read: u64,
    /// Uncompressed bytes of chunk content decoded.
    pub bytes_decompressed: u64,
}

/// Everything found while loading one log.
#[derive(Debug, Clone, Serialize)]
pub struct LoadReport {
    pub file: String,
    pub status: LoadStatus,
    pub findings: Vec<Finding>,
    pub counts: ReadCounts,
    /// Wall time of the load in seconds (not deterministic; for the record).
    pub elapsed_s: f64,
}

impl LoadReport {
    /// Findings with a given code.
    pub fn with_code(&self, code: FindingCode) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(move |f| f.code == code)
    }

    /// Whether any finding has this code.
    pub fn has(&self, code: FindingCode) -> bool {
        self.with_code(code).next().is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_follows_worst_finding() {
        let f = |s| Finding::new(s, FindingCode::Gap, "a.mcap", Some("/rig/force"), None, "x");
        assert_eq!(status_of(&[]), LoadStatus::Ok);
        assert_eq!(status_of(&[f(Severity::Info)]), LoadStatus::Ok);
        assert_eq!(
            status_of(&[f(Severity::Info), f(Severity::Warning)]),
            LoadStatus::OkWithWarnings
        );
        assert_eq!(
            status_of(&[f(Severity::DataLoss), f(Severity::Warning)]),
            LoadStatus::Partial
        );
        assert_eq!(status_of(&[f(Severity::Error)]), LoadStatus::Error);
    }

    #[test]
    fn message_names_file_and_channel() {
        let f = Finding::new(
            Severity::Warning,
            FindingCode::Gap,
            "run.mcap",
            Some("/rig/force (force)"),
            Some(Place::time(5)),
            "gap",
        );
        assert_eq!(f.message, "run.mcap: /rig/force (force): gap");
        assert_eq!(
            fmt_time(1_500_000_000, Some(1_000_000_000)),
            "log_time 1500000000 ns (t+0.5000 s)"
        );
    }
}
