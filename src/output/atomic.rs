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

/// Writes one file atomically: temporary in the same folder, fsync,
/// rename, fsync of the folder. The folder is created if needed. On any
/// error the old file (if any) is untouched and no temporary remains.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut r = Report::new_in(path.parent().unwrap_or(Path::new("")))?;
    let (_, name) = split(path)?;
    r.add(&name, bytes)?;
    r.commit()?;
    Ok(())
}

/// A multi-file report: stage every file, then [`Report::commit`]. Dropped
/// without a commit (an error, a panic, an early return) it removes its
/// temporaries and leaves the folder as it was.
#[derive(Debug)]
pub struct Report {
    dir: PathBuf,
    /// (temporary, final) pairs, in the order added.
    staged: Vec<(PathBuf, PathBuf)>,
    staged_bytes: u64,
}

impl Report {
    /// A report written into `dir` (created if needed). Temporaries that a
    /// killed earlier run left there are removed.
    pub fn new_in(dir: &Path) -> Result<Self, OutputError> {
        let dir = if dir.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            dir.to_path_buf()
        };
        std::fs::create_dir_all(&dir).map_err(|e| OutputError::io(&dir, e))?;
        sweep_stale(&dir);
        Ok(Report {
            dir,
            staged: Vec::new(),
            staged_bytes: 0,
        })
    }

    /// The folder the report goes to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Stages `name` (a file name in the report's folder) with `bytes`.
    /// Adding the same name twice keeps the last.
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let final_path = self.dir.join(name);
        if name.is_empty() || Path::new(name).file_name() != Some(std::ffi::OsStr::new(name)) {
            return Err(OutputError::io(
                &final_path,
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "a report file name must be a plain name inside the output folder",
                ),
            ));
        }
        let tmp = temp_path(&self.dir, name);
        stage(&tmp, bytes).map_err(|e| {
            // Free what we hold so the figure of free space is the real one.
            let needed = self.staged_bytes + bytes.len() as u64;
            self.discard();
            stage_error(&final_path, &self.dir, needed, e)
        })?;
        if let Some(i) = self.staged.iter().position(|(_, f)| *f == final_path) {
            let (old_tmp, _) = self.staged.remove(i);
            let _ = std::fs::remove_file(old_tmp);
        }
        self.staged_bytes += bytes.len() as u64;
        self.staged.push((tmp, final_path.clone()));
        Ok(final_path)
    }

    /// Renames every staged file over its final name and fsyncs the
    /// folder; returns the files written, in the order added.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let staged = std::mem::take(&mut self.staged);
        let mut done = Vec::with_capacity(staged.len());
        for (i, (tmp, fin)) in staged.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, fin) {
                for (t, _) in &staged[i..] {
                    let _ = std::fs::remove_file(t);
                }
                return Err(OutputError::io(fin, e));
            }
            done.push(fin.clone());
        }
        sync_dir(&self.dir)?;
        Ok(done)
    }

    /// Removes every temporary staged so far.
    fn discard(&mut self) {
        for (tmp, _) in self.staged.drain(..) {
            let _ = std::fs::remove_file(tmp);
        }
        self.staged_bytes = 0;
    }
}

impl Drop for Report {
    fn drop(&mut self) {
        self.discard();
    }
}

/// Removes temporaries of processes that no longer run (a SIGKILLed or
/// crashed earlier write). Best effort: a folder that cannot be read is
/// left alone.
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
        if !alive {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_file_replaces_and_leaves_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.json");
        write_file(&p, b"old").unwrap();
        write_file(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        assert_eq!(names(d.path()), vec!["a.json"]);
        // A folder that does not exist yet is created.
        let q = d.path().join("sub/b.csv");
        write_file(&q, b"x").unwrap();
        assert_eq!(std::fs::read(&q).unwrap(), b"x");
    }

    #[test]
    fn report_dropped_before_commit_keeps_the_old_files() {
        let d = tempfile::tempdir().unwrap();
        let mut r = Report::new_in(d.path()).unwrap();
        r.add("a", b"1").unwrap();
        r.add("b", b"1").unwrap();
        r.commit().unwrap();
        let mut r = Report::new_in(d.path()).unwrap();
        r.add("a", b"2").unwrap();
        drop(r); // an error while producing "b"
        assert_eq!(std::fs::read(d.path().join("a")).unwrap(), b"1");
        assert_eq!(std::fs::read(d.path().join("b")).unwrap(), b"1");
        assert_eq!(names(d.path()), vec!["a", "b"]);
    }

    #[test]
    fn commit_writes_every_file_and_names_them() {
        let d = tempfile::tempdir().unwrap();
        let mut r = Report::new_in(d.path()).unwrap();
        r.add("x.json", b"{}").unwrap();
        r.add("y.csv", b"a\n").unwrap();
        r.add("x.json", b"[]").unwrap();
        let files = r.commit().unwrap();
        assert_eq!(files, vec![d.path().join("y.csv"), d.path().join("x.json")]);
        assert_eq!(std::fs::read(d.path().join("x.json")).unwrap(), b"[]");
        assert_eq!(names(d.path()), vec!["x.json", "y.csv"]);
    }

    #[test]
    fn names_that_leave_the_folder_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let mut r = Report::new_in(d.path()).unwrap();
        for bad in ["../x", "a/b", "", ".."] {
            assert!(r.add(bad, b"1").is_err(), "{bad}");
        }
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_swept() {
        let d = tempfile::tempdir().unwrap();
        // pid 0 is never a user process: its temporaries are stale.
        let stale = d.path().join(format!(".a{TMP_MARK}0.7"));
        std::fs::write(&stale, b"half").unwrap();
        let mine = temp_path(d.path(), "b");
        std::fs::write(&mine, b"busy").unwrap();
        let _r = Report::new_in(d.path()).unwrap();
        assert!(!stale.exists());
        assert!(mine.exists(), "a live process's temporary is kept");
    }

    #[test]
    fn disk_full_names_the_file_and_the_space() {
        // A real full filesystem: /dev/full fails every write with ENOSPC
        // (Linux); we cannot create a temporary there, so check the error
        // mapping on the errno the kernel gives.
        let e = stage_error(
            Path::new("/out/yield.json"),
            Path::new("/"),
            2_500_000,
            std::io::Error::from_raw_os_error(28),
        );
        let msg = e.to_string();
        assert!(msg.contains("/out/yield.json"), "{msg}");
        assert!(msg.contains("needed 2500000 bytes"), "{msg}");
        assert!(matches!(e, OutputError::DiskFull { .. }));
    }
}
