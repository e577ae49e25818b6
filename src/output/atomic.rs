//! Atomic file and multi-file report writing (see the module above).

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Marker in the names of temporaries, so a later run can sweep away those
/// a killed run left behind.
const TMP_MARK: &str = ".pinsight-tmp.";

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The filesystem is full: how much the write needed and how much was
    /// free (after removing our own temporaries).
    #[error(
        "cannot write {path}: no space left on the device (needed {needed} bytes, {free} bytes free); nothing was replaced"
    )]
    DiskFull {
        path: PathBuf,
        needed: u64,
        free: u64,
    },
    /// Any other I/O failure, with the file it concerns.
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl OutputError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Bytes available to an unprivileged writer on the filesystem of `dir`.
pub fn free_bytes(dir: &Path) -> Option<u64> {
    let s = rustix::fs::statvfs(dir).ok()?;
    Some(s.f_bavail.saturating_mul(s.f_frsize))
}

/// A unique temporary name in `dir` for the final name `name`.
fn temp_path(dir: &Path, name: &str) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!(".{name}{TMP_MARK}{}.{n}", std::process::id()))
}

/// The folder of `path` (`.` for a bare file name) and its file name.
fn split(path: &Path) -> Result<(PathBuf, String), OutputError> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| {
            OutputError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
            )
        })?
        .to_string();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((dir, name))
}

/// fsyncs a folder so the renames in it survive a power loss.
fn sync_dir(dir: &Path) -> Result<(), OutputError> {
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(|e| OutputError::io(dir, e))
}

/// fsyncs a folder and every folder below it (a staged data set's
/// partition folders), deepest first.
fn sync_tree(dir: &Path) -> Result<(), OutputError> {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                sync_tree(&e.path())?;
            }
        }
    }
    sync_dir(dir)
}

/// Writes `bytes` to a new temporary `tmp` and fsyncs it; on failure the
/// temporary is removed.
fn stage(tmp: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let r = (|| {
        let mut f = OpenOptions::new().write(true).create_new(true).open(tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    if r.is_err() {
        let _ = std::fs::remove_file(tmp);
    }
    r
}

/// Turns a staging failure into an error naming the final file; a full
/// disk reports `needed` bytes and what is free.
fn stage_error(final_path: &Path, dir: &Path, needed: u64, e: std::io::Error) -> OutputError {
    if e.raw_os_error() == Some(28) || e.kind() == std::io::ErrorKind::StorageFull {
        OutputError::DiskFull {
            path: final_path.to_path_buf(),
            needed,
            free: free_bytes(dir).unwrap_or(0),
        }
    } else {
        OutputError::io(final_path, e)
    }
}

/// The file a write to `path` must replace: a symbolic link is followed
/// (the link stays, its target gets the new content, as `sed -i
/// --follow-symlinks` does), up to 40 links deep. `None` when the path is
/// or leads through `/dev` or `/proc` (`/dev/stdout` is a link to
/// `/proc/self/fd/1`, whose target is the process's own output): those are
/// written through, never replaced.
fn follow_links(path: &Path) -> Option<PathBuf> {
    let special = |p: &Path| p.starts_with("/dev") || p.starts_with("/proc");
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        if special(&p) {
            return None;
        }
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let Ok(target) = std::fs::read_link(&p) else {
                    break;
                };
                p = match p.parent() {
                    Some(parent) if target.is_relative() => parent.join(target),
                    _ => target,
                };
            }
            _ => break,
        }
    }
    (!special(&p)).then_some(p)
}

/// Writes `bytes` straight into a file that is not a regular file (a
/// terminal, `/dev/null`, `/dev/stdout`, a named pipe): it cannot be
/// replaced by a rename, and must never be (renaming over `/dev/null`
/// would put a plain file in its place).
fn write_through(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    // Appending: `--csv /dev/stdout > file` adds after what was printed.
    OpenOptions::new()
        .append(true)
        .open(path)
        .and_then(|mut f| f.write_all(bytes))
        .map_err(|e| OutputError::io(path, e))
}

/// Writes one file atomically: temporary in the same folder, fsync,
/// rename, fsync of the folder. The folder is created if needed. On any
/// error the old file (if any) is untouched and no temporary remains.
///
/// A symbolic link is followed (its target is replaced, the link kept);
/// an existing file keeps its permissions; a device or a named pipe
/// (`/dev/stdout`, `/dev/null`) is written through, not replaced; a folder
/// is refused.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let Some(target) = follow_links(path) else {
        return write_through(path, bytes);
    };
    let existing = std::fs::metadata(&target).ok();
    match &existing {
        Some(m) if m.is_dir() => {
            return Err(OutputError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "it is a folder"),
            ));
        }
        Some(m) if !m.is_file() => return write_through(&target, bytes),
        _ => {}
    }
    let (dir, name) = split(&target)?;
    std::fs::create_dir_all(&dir).map_err(|e| OutputError::io(&dir, e))?;
    sweep_stale(&dir);
    let tmp = temp_path(&dir, &name);
    stage(&tmp, bytes).map_err(|e| stage_error(path, &dir, bytes.len() as u64, e))?;
    if let Some(m) = &existing {
        // Best effort: a file the user made read-only for others stays so.
        let _ = std::fs::set_permissions(&tmp, m.permissions());
    }
    if let Err(e) = std::fs::rename(&tmp, &target) {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::io(path, e));
    }
    sync_dir(&dir)
}

/// Publishes one file of a stream read as it appears (camera photographs,
/// `rig-sim --images`): a hidden temporary renamed into place, so a reader
/// sees it whole or not at all; not fsynced (many small files; a power loss
/// may lose the last ones). The folder must exist.
pub fn publish_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let (dir, name) = split(path)?;
    let tmp = temp_path(&dir, &name);
    let r = OpenOptions::new().write(true).create_new(true).open(&tmp);
    if let Err(e) = r.and_then(|mut f| f.write_all(bytes)) {
        let _ = std::fs::remove_file(&tmp);
        return Err(stage_error(path, &dir, bytes.len() as u64, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::io(path, e)
    })
}

/// How a [`Report`] reaches its folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommitMode {
    /// A fresh folder beside `--out`, holding the new files and hard links
    /// of everything else, exchanged with `--out` in one
    /// `renameat2(RENAME_EXCHANGE)`: readers see the whole old folder or
    /// the whole new one.
    Switch,
    /// The staged files renamed into `--out` one after the other (each
    /// file old-or-new; a kill inside the renames can leave a mix). Used
    /// when a switch cannot be made: `--out` is (or holds) the current
    /// directory, its parent is not writable, it is a mount point, it holds
    /// more than [`MAX_CARRIED`] entries, or the filesystem has no
    /// exchange.
    Renames,
}

/// Most entries of `--out` a folder switch carries across (hard links);
/// above, the report falls back to [`CommitMode::Renames`].
pub const MAX_CARRIED: usize = 10_000;

/// A multi-file report: stage every file, then [`Report::commit`]. Dropped
/// without a commit (an error, a panic, an early return) it removes its
/// staging folder and leaves `--out` as it was.
///
/// Files are staged in a hidden folder: beside `--out`
/// (`.OUT.pinsight-tmp.PID.N`) when a folder switch is possible, inside it
/// otherwise. The staging folder holds a marker file named after itself
/// from its first instant, so a sweep after a kill can tell a staging
/// folder (delete it) from the old content a switch moved aside (put back
/// anything `--out` lacks, then delete it).
#[derive(Debug)]
pub struct Report {
    dir: PathBuf,
    stage: PathBuf,
    marker: String,
    mode: CommitMode,
    /// File names staged, in the order added (the last add of a name wins).
    staged: Vec<String>,
    staged_bytes: u64,
    /// Entries of `--out` the commit removes (an output this run does not
    /// write again in that form, e.g. a partitioned folder now one file).
    removed: Vec<String>,
}

/// The marker a staging folder named `.X{TMP_MARK}SUFFIX` holds.
fn marker_name(stage_name: &str) -> Option<String> {
    let pos = stage_name.find(TMP_MARK)?;
    Some(format!(".staging{}", &stage_name[pos..]))
}

/// Whether `dir` is the current directory or one of its ancestors (a
/// switch would leave this process, or the shell that started it, in a
/// folder that no longer has a name).
fn holds_cwd(dir: &Path) -> bool {
    match std::env::current_dir().and_then(|c| c.canonicalize()) {
        Ok(cwd) => cwd.starts_with(dir),
        Err(_) => true,
    }
}

/// Creates a staging folder at `path` with its marker first.
fn make_stage(path: &Path) -> std::io::Result<String> {
    std::fs::create_dir(path)?;
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    let marker = marker_name(name).unwrap_or_else(|| ".staging".into());
    if let Err(e) = File::create(path.join(&marker)) {
        let _ = std::fs::remove_dir_all(path);
        return Err(e);
    }
    Ok(marker)
}

impl Report {
    /// A report written into `dir` (created if needed). What a killed
    /// earlier run left (temporaries, a staging folder, an old folder
    /// moved aside) is cleaned up first, putting back anything of the
    /// user's.
    pub fn new_in(dir: &Path) -> Result<Self, OutputError> {
        let dir = if dir.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            dir.to_path_buf()
        };
        if std::fs::metadata(&dir).is_ok_and(|m| !m.is_dir()) {
            return Err(OutputError::io(
                &dir,
                std::io::Error::new(
                    std::io::ErrorKind::NotADirectory,
                    "it exists and is not a folder",
                ),
            ));
        }
        std::fs::create_dir_all(&dir).map_err(|e| OutputError::io(&dir, e))?;
        let abs = dir.canonicalize().map_err(|e| OutputError::io(&dir, e))?;
        // `--out` given as a symbolic link to a folder: the switch must
        // exchange the folder, not the link (which would be replaced by a
        // plain folder and the link's target left with the old report).
        let dir = if std::fs::symlink_metadata(&dir).is_ok_and(|m| m.file_type().is_symlink()) {
            abs.clone()
        } else {
            dir
        };
        sweep_stale(&dir);
        let parent = abs.parent().filter(|_| !holds_cwd(&abs));
        let base = abs.file_name().and_then(|n| n.to_str());
        if let (Some(parent), Some(base)) = (parent, base) {
            sweep_stale(parent);
            let stage = temp_path(parent, base);
            if let Ok(marker) = make_stage(&stage) {
                return Ok(Report {
                    dir,
                    stage,
                    marker,
                    mode: CommitMode::Switch,
                    staged: Vec::new(),
                    staged_bytes: 0,
                    removed: Vec::new(),
                });
            }
        }
        let stage = temp_path(&dir, "report");
        let marker = make_stage(&stage).map_err(|e| OutputError::io(&dir, e))?;
        Ok(Report {
            dir,
            stage,
            marker,
            mode: CommitMode::Renames,
            staged: Vec::new(),
            staged_bytes: 0,
            removed: Vec::new(),
        })
    }

    /// The folder the report goes to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// How the commit will be made (a switch may still fall back to
    /// renames at commit time; [`Report::commit`] says which happened).
    pub fn mode(&self) -> CommitMode {
        self.mode
    }

    /// Stages `name` (a file name in the report's folder, or a path of
    /// plain names below it, `images/part=A/data.parquet`) with `bytes`.
    /// Adding the same name twice keeps the last.
    ///
    /// A nested file makes its top folder (`images/`) part of the report:
    /// the commit replaces that whole folder (a partitioned data set
    /// written again leaves no partition of the old run behind).
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let final_path = self.dir.join(name);
        let plain = |n: &str| {
            !n.is_empty()
                && n != "."
                && n != ".."
                && !n.contains(TMP_MARK)
                && Path::new(n).file_name() == Some(std::ffi::OsStr::new(n))
        };
        if name.is_empty() || !name.split('/').all(plain) {
            return Err(OutputError::io(
                &final_path,
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "a report file name must be a plain name (or a path of plain names) inside the output folder",
                ),
            ));
        }
        if let Some(top) = name.split_once('/').map(|(t, _)| t)
            && self.staged.iter().any(|s| s == top)
        {
            return Err(OutputError::io(
                &final_path,
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("`{top}` is staged as a file of the report, not a folder"),
                ),
            ));
        }
        let tmp = self.stage.join(name);
        if let Some(parent) = tmp.parent() {
            std::fs::create_dir_all(parent).map_err(|e| OutputError::io(&final_path, e))?;
        }
        if let Some(i) = self.staged.iter().position(|n| n == name) {
            self.staged.remove(i);
            let _ = std::fs::remove_file(&tmp);
        }
        stage(&tmp, bytes).map_err(|e| {
            // Free what we hold so the figure of free space is the real one.
            let needed = self.staged_bytes + bytes.len() as u64;
            self.discard();
            stage_error(&final_path, &self.dir, needed, e)
        })?;
        self.staged_bytes += bytes.len() as u64;
        self.staged.push(name.to_string());
        Ok(final_path)
    }

    /// Marks `name`, a top-level file or folder of `--out`, to be removed
    /// by the commit (nothing happens to it before). A name also staged
    /// is written, not removed.
    pub fn remove(&mut self, name: &str) {
        if !self.removed.iter().any(|r| r == name) {
            self.removed.push(name.to_string());
        }
    }

    /// Removed entries that the report does not write again.
    fn to_remove(&self) -> Vec<String> {
        let tops = self.tops();
        self.removed
            .iter()
            .filter(|r| !tops.contains(&r.as_str()))
            .cloned()
            .collect()
    }

    /// Puts the staged files in place and fsyncs; returns the files
    /// written, in the order added, and how it was done.
    pub fn commit_with_mode(mut self) -> Result<(Vec<PathBuf>, CommitMode), OutputError> {
        let done: Vec<PathBuf> = self.staged.iter().map(|n| self.dir.join(n)).collect();
        let mut mode = self.mode;
        if mode == CommitMode::Switch && !self.switch()? {
            mode = CommitMode::Renames;
            self.renames()?;
        } else if mode == CommitMode::Renames {
            self.renames()?;
        }
        self.staged.clear();
        self.discard();
        Ok((done, mode))
    }

    /// Puts the staged files in place; returns the files written, in the
    /// order added.
    pub fn commit(self) -> Result<Vec<PathBuf>, OutputError> {
        self.commit_with_mode().map(|(files, _)| files)
    }

    /// The top-level entries of `--out` the report writes (files, and the
    /// top folders of nested files), each once, in the order first added.
    fn tops(&self) -> Vec<&str> {
        let mut v: Vec<&str> = Vec::new();
        for n in &self.staged {
            let top = n.split('/').next().unwrap_or(n);
            if !v.contains(&top) {
                v.push(top);
            }
        }
        v
    }

    /// Renames every staged file into the folder, then fsyncs it. A staged
    /// folder replaces the old one of that name: the old is removed first
    /// (a kill between leaves the folder absent, never a mix of runs).
    fn renames(&mut self) -> Result<(), OutputError> {
        for r in self.to_remove() {
            let p = self.dir.join(&r);
            let gone = match std::fs::symlink_metadata(&p) {
                Err(_) => Ok(()),
                Ok(m) if m.is_dir() => std::fs::remove_dir_all(&p),
                Ok(_) => std::fs::remove_file(&p),
            };
            gone.map_err(|e| OutputError::io(&p, e))?;
        }
        for top in self.tops() {
            let fin = self.dir.join(top);
            let src = self.stage.join(top);
            if src.is_dir() {
                // Staged folders hold their files' fsynced data; the
                // folders themselves are synced here before the move.
                sync_tree(&src)?;
                if std::fs::symlink_metadata(&fin).is_ok_and(|m| m.is_dir()) {
                    std::fs::remove_dir_all(&fin).map_err(|e| OutputError::io(&fin, e))?;
                }
            }
            std::fs::rename(&src, &fin).map_err(|e| OutputError::io(&fin, e))?;
        }
        sync_dir(&self.dir)
    }

    /// The folder switch. `Ok(false)` when it cannot be made here (the
    /// caller then renames); the folder is untouched in that case.
    fn switch(&mut self) -> Result<bool, OutputError> {
        // Carry everything of the folder the report does not replace.
        let Ok(rd) = std::fs::read_dir(&self.dir) else {
            return Ok(false);
        };
        let mut carried = 0usize;
        let tops: Vec<String> = self.tops().into_iter().map(str::to_string).collect();
        let mut tops: Vec<&str> = tops.iter().map(String::as_str).collect();
        let removed = self.to_remove();
        tops.extend(removed.iter().map(String::as_str));
        for e in rd {
            let Ok(e) = e else { return Ok(false) };
            let name = e.file_name();
            let Some(n) = name.to_str() else {
                return Ok(false);
            };
            if n.contains(TMP_MARK) || tops.contains(&n) {
                continue;
            }
            if !carry(&e, &self.stage.join(n), &mut carried) {
                return Ok(false);
            }
        }
        if let Ok(meta) = std::fs::metadata(&self.dir) {
            let _ = std::fs::set_permissions(&self.stage, meta.permissions());
        }
        if sync_tree(&self.stage).is_err() {
            return Ok(false);
        }
        let cwd = rustix::fs::CWD;
        if rustix::fs::renameat_with(
            cwd,
            &self.stage,
            cwd,
            &self.dir,
            rustix::fs::RenameFlags::EXCHANGE,
        )
        .is_err()
        {
            return Ok(false);
        }
        // From here `self.stage` names the old folder, `self.dir` the new.
        let _ = std::fs::remove_file(self.dir.join(&self.marker));
        for r in &removed {
            let old = self.stage.join(r);
            let _ = if old.is_dir() {
                std::fs::remove_dir_all(&old)
            } else {
                std::fs::remove_file(&old)
            };
        }
        let left = restore_missing(&self.stage, &self.dir);
        sync_dir(&self.dir)?;
        if let Some(p) = self.stage.parent() {
            sync_dir(p)?;
        }
        if let Err(e) = left {
            // Keep the old folder rather than lose what could not be moved.
            let kept = std::mem::take(&mut self.stage);
            return Err(OutputError::io(
                &self.dir,
                std::io::Error::other(format!(
                    "the report was written, but {e}; the previous folder is kept at {}",
                    kept.display()
                )),
            ));
        }
        Ok(true)
    }

    /// Removes the staging folder (and whatever it holds).
    fn discard(&mut self) {
        if !self.stage.as_os_str().is_empty() {
            let _ = std::fs::remove_dir_all(&self.stage);
            self.stage = PathBuf::new();
        }
        self.staged.clear();
        self.staged_bytes = 0;
    }
}

impl Drop for Report {
    fn drop(&mut self) {
        self.discard();
    }
}

/// Carries one entry of `--out` into the staging folder: a file (or a
/// symbolic link, not followed) as a hard link; a folder as a new folder
/// of the same permissions holding hard links of its whole tree, so the
/// user's subfolders are in the new folder at the instant of the exchange
/// (a kill just after it must not leave them only in the old folder moved
/// aside). Counts every entry against [`MAX_CARRIED`]; `false` when the
/// tree is too large or cannot be linked (another filesystem mounted
/// inside, an unreadable folder): the caller then renames instead.
fn carry(e: &std::fs::DirEntry, to: &Path, carried: &mut usize) -> bool {
    *carried += 1;
    if *carried > MAX_CARRIED {
        return false;
    }
    let Ok(ft) = e.file_type() else {
        return false;
    };
    if !ft.is_dir() {
        return std::fs::hard_link(e.path(), to).is_ok();
    }
    let Ok(rd) = std::fs::read_dir(e.path()) else {
        return false;
    };
    if std::fs::create_dir(to).is_err() {
        return false;
    }
    if let Ok(meta) = e.metadata() {
        let _ = std::fs::set_permissions(to, meta.permissions());
    }
    rd.into_iter()
        .all(|c| c.is_ok_and(|c| carry(&c, &to.join(c.file_name()), carried)))
}

/// Moves every entry of `from` that `to` lacks into `to` (files that
/// appeared in `--out` during the switch).
fn restore_missing(from: &Path, to: &Path) -> Result<(), String> {
    let rd = std::fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))?;
    for e in rd.flatten() {
        let target = to.join(e.file_name());
        if std::fs::symlink_metadata(&target).is_err() {
            std::fs::rename(e.path(), &target)
                .map_err(|err| format!("{} could not be moved back: {err}", target.display()))?;
        }
    }
    Ok(())
}

/// Cleans what processes that no longer run left in `dir` (a SIGKILLed or
/// crashed earlier write): temporary files are removed; a staging folder
/// (it holds its marker) is removed; an old folder a switch moved aside
/// first gives back what the folder it came from lacks. Best effort: a
/// folder that cannot be read is left alone.
fn sweep_stale(dir: &Path) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(pos) = name.find(TMP_MARK) else {
            continue;
        };
        let pid = name[pos + TMP_MARK.len()..]
            .split('.')
            .next()
            .and_then(|p| p.parse::<u32>().ok());
        let alive = pid
            .is_some_and(|p| p == std::process::id() || Path::new(&format!("/proc/{p}")).exists());
        if alive {
            continue;
        }
        let path = e.path();
        if !e.file_type().is_ok_and(|t| t.is_dir()) {
            let _ = std::fs::remove_file(&path);
            continue;
        }
        let is_stage = marker_name(name).is_some_and(|m| path.join(m).exists());
        // `.BASE.pinsight-tmp…` moved aside from `dir/BASE`.
        let origin = name
            .strip_prefix('.')
            .map(|n| &n[..pos - 1])
            .filter(|b| !b.is_empty())
            .map(|b| dir.join(b));
        if !is_stage {
            match origin {
                Some(o) if o.is_dir() => {
                    if restore_missing(&path, &o).is_err() {
                        continue;
                    }
                }
                // Nowhere to put it back: keep it for a human.
                _ => continue,
            }
        }
        let _ = std::fs::remove_dir_all(&path);
    }
}

#[cfg(test)]
#[path = "atomic_tests.rs"]
mod tests;
