//! Errors that stop a rig log from being read at all.
//!
//! Most problems in a log are not errors: a missing channel, a gap, a bad
//! chunk or a truncated tail are *findings* in the [`LoadReport`]
//! (crate::rig::report::LoadReport) and the rest of the log still loads.
//! [`LogError`] is kept for the cases where nothing useful can be returned:
//! the file cannot be opened, is empty, is not MCAP, or the channel map
//! given by the user is invalid.

use std::path::Path;

/// A rig log (or its channel map) that cannot be read at all.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be opened, mapped or read.
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The file has zero bytes.
    #[error("{file}: empty file (0 bytes), not an MCAP log")]
    Empty { file: String },
    /// The file does not start with the MCAP magic.
    #[error(
        "{file}: not an MCAP file: starts with {found} instead of the MCAP magic 89 4D 43 41 50 30 0D 0A"
    )]
    BadMagic { file: String, found: String },
    /// The file is MCAP but nothing in it can be read (e.g. cut right after the magic).
    #[error("{file}: {message}")]
    Unreadable { file: String, message: String },
    /// The channel map (TOML) is invalid.
    #[error("channel map {source_name}: {message}")]
    ChannelMap {
        source_name: String,
        message: String,
    },
    /// A requested item (an image, a chunk) is not in the file.
    #[error("{file}: {message}")]
    NotFound { file: String, message: String },
}

impl LogError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        LogError::Io {
            file: path.display().to_string(),
            source,
        }
    }

    /// The file (or channel map) the error is about.
    pub fn file(&self) -> &str {
        match self {
            LogError::Io { file, .. }
            | LogError::Empty { file }
            | LogError::BadMagic { file, .. }
            | LogError::Unreadable { file, .. }
            | LogError::NotFound { file, .. } => file,
            LogError::ChannelMap { source_name, .. } => source_name,
        }
    }
}
