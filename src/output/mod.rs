//! Every file pinsight writes goes out through here.
//!
//! - [`atomic::write_file`]: one file, written to a temporary in the same
//!   folder, fsynced, renamed over the final name, the folder fsynced. A
//!   reader (or a crash, Ctrl-C, a full disk) sees the old file or the new
//!   one, never a truncated mix.
//! - [`atomic::Report`]: a report of several files (yield, sweep, overlay).
//!   Every file is staged complete and fsynced in a hidden folder beside
//!   `--out`, together with hard links of everything else `--out` holds
//!   (the user's subfolders as new folders of hard links of their whole
//!   tree); the commit exchanges that folder with `--out` in one
//!   `renameat2(RENAME_EXCHANGE)` and removes the old folder. A reader, a SIGKILL or a power loss sees
//!   the whole old folder or the whole new one. Where a switch cannot be
//!   made (`--out` is or holds the current directory, a mount point, an
//!   unwritable parent, a filesystem without exchange, more than
//!   [`atomic::MAX_CARRIED`] entries) the staged files are renamed in one
//!   after the other: each file old-or-new, a kill inside those renames can
//!   leave a mix (docs/reliability.md).
//!
//! - [`json`]: JSON for report files that must be reproducible (the
//!   wall-clock times left out).
//!
//! Whatever a killed run leaves (temporaries, a staging folder, the old
//! folder moved aside) is cleaned by the next write into the same place,
//! and anything of the user's in it is put back first.

pub mod atomic;
pub mod json;

pub use atomic::{CommitMode, OutputError, Report, write_file};
