//! Every file pinsight writes goes out through here.
//!
//! - [`atomic::write_file`]: one file, written to a temporary in the same
//!   folder, fsynced, renamed over the final name, the folder fsynced. A
//!   reader (or a crash, Ctrl-C, a full disk) sees the old file or the new
//!   one, never a truncated mix.
//! - [`atomic::Report`]: a report of several files (yield, sweep, overlay,
//!   methods, inspect). Every file is staged as a complete, fsynced
//!   temporary first; only when all are staged are they renamed over the
//!   old ones, one after the other (microseconds). A failure or interrupt
//!   while staging leaves the old report untouched and removes the
//!   temporaries.
//!
//! Why staged renames rather than a run folder switched at the end: `--out`
//! is a folder the user names and may hold other things (other reports,
//! `--out .`); swapping the whole folder would move or copy those too.
//! The price is the commit window — the renames themselves — where a
//! SIGKILL or power loss can leave some new files beside some old ones; it
//! is a few microseconds against the seconds of computing and staging
//! (docs/reliability.md).

pub mod atomic;

pub use atomic::{OutputError, Report, write_file};
