//! A watched folder: camera images arriving, and rig logs of new runs
//! (a rig that starts a new file per run). Each file is reported once, in
//! the order it arrived (by modification time, then name).
//!
//! The files already seen are remembered for [`FORGET_S`] seconds after
//! their modification time; older ones are summarised by a watermark (a
//! file modified before it is not new), so a shift's thousands of images
//! do not grow the memory. A file copied in later with an old modification
//! time (`cp -p`) is therefore not seen.
//!
//! A scan hands out at most the images its caller has room for (the
//! follower's queue is bounded); the rest are neither remembered nor held
//! but found again by the next scan, which lists the whole folder while
//! any are left ([`FolderTail::behind`]). So a folder found full, or a
//! camera faster than the inspection, costs disk, not memory.

use crate::rig::report::{Finding, FindingCode, Severity};
use crate::vision::batch::IMAGE_EXTENSIONS;
use std::collections::{BinaryHeap, HashMap};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// Seconds a seen file is remembered by name.
pub const FORGET_S: u64 = 120;
/// An image file must be this old (s) before it is read (a camera writing
/// in place may not have finished it).
pub const SETTLE_MS: u64 = 150;

/// New files found by a scan.
#[derive(Debug, Default)]
pub struct FolderScan {
    pub images: Vec<PathBuf>,
    pub logs: Vec<PathBuf>,
    pub findings: Vec<Finding>,
    /// The folder's state changed to missing (true) or back (false).
    pub missing_changed: Option<bool>,
}

/// One watched folder.
pub struct FolderTail {
    pub path: PathBuf,
    seen: HashMap<PathBuf, SystemTime>,
    watermark: Option<SystemTime>,
    pub missing: bool,
    /// Images found but not settled yet (looked at again at every scan).
    pending: Vec<(PathBuf, SystemTime)>,
    /// The folder was there at some scan.
    ever: bool,
    /// Images present at the first scan are read too (the run's backlog);
    /// logs present then: only the newest one.
    first: bool,
    /// The last scan left images for a later one (no room for them), or
    /// a scan was skipped: the next lists the whole folder.
    pub behind: bool,
}

fn ext(p: &Path) -> String {
    p.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

impl FolderTail {
    pub fn new(path: &Path) -> Self {
        FolderTail {
            path: path.to_path_buf(),
            seen: HashMap::new(),
            watermark: None,
            missing: false,
            pending: Vec::new(),
            ever: false,
            first: true,
            behind: false,
        }
    }

    /// Every log and image file below `dir` (8 levels at most), given to
    /// `keep` one by one (nothing is collected here: a whole listing of a
    /// folder of waiting images must not cost a vector of all of them).
    fn walk(
        dir: &Path,
        keep: &mut dyn FnMut(PathBuf, SystemTime),
        depth: usize,
    ) -> std::io::Result<()> {
        for e in std::fs::read_dir(dir)?.flatten() {
            let p = e.path();
            let Ok(md) = e.metadata() else { continue };
            if md.is_dir() {
                if depth < 8 {
                    let _ = Self::walk(&p, keep, depth + 1);
                }
            } else if md.is_file() {
                let x = ext(&p);
                if x == "mcap" || IMAGE_EXTENSIONS.contains(&x.as_str()) {
                    keep(p, md.modified().unwrap_or(SystemTime::UNIX_EPOCH));
                }
            }
        }
        Ok(())
    }

    /// A scan skipped by the caller (no room for images): the events it
    /// would have looked at are made up for by a whole listing next time.
    pub fn defer(&mut self) {
        self.behind = true;
    }

    /// Lists the folder (or, with `changed`, looks only at those paths) and
    /// returns the files not seen before, at most `room` images of them
    /// (the oldest first; the others are left for a later scan).
    pub fn scan(&mut self, changed: Option<&[PathBuf]>, room: usize) -> FolderScan {
        let mut out = FolderScan::default();
        let mut files = Vec::new();
        // The oldest image a whole listing left out (past the room).
        let mut dropped: Option<SystemTime> = None;
        let listed = match changed {
            Some(paths) if !self.first && !self.missing && !self.behind => {
                for p in paths.iter().filter(|p| p.starts_with(&self.path)) {
                    let x = ext(p);
                    if x != "mcap" && !IMAGE_EXTENSIONS.contains(&x.as_str()) {
                        continue;
                    }
                    if let Ok(md) = std::fs::metadata(p)
                        && md.is_file()
                    {
                        files.push((p.clone(), md.modified().unwrap_or(SystemTime::UNIX_EPOCH)));
                    }
                }
                Ok(())
            }
            _ => {
                // Every log, and of the images not seen yet only the
                // `room + 1` oldest (a bounded heap; the one past the room
                // tells the scan that images are left).
                let (watermark, seen) = (self.watermark, &self.seen);
                let keep_n = room.saturating_add(1);
                let mut oldest: BinaryHeap<(SystemTime, PathBuf)> = BinaryHeap::new();
                let r = Self::walk(
                    &self.path,
                    &mut |p, m| {
                        if ext(&p) == "mcap" {
                            files.push((p, m));
                        } else if !(watermark.is_some_and(|w| m <= w) || seen.get(&p) == Some(&m)) {
                            oldest.push((m, p));
                            if oldest.len() > keep_n
                                && let Some((m, _)) = oldest.pop()
                            {
                                dropped = Some(dropped.map_or(m, |d: SystemTime| d.min(m)));
                            }
                        }
                    },
                    0,
                );
                files.extend(oldest.into_iter().map(|(m, p)| (p, m)));
                r
            }
        };
        let gone = !self.path.is_dir();
        if gone && !self.ever {
            // Not there yet (a camera that has not started): waited for quietly.
            self.missing = true;
            return out;
        }
        self.ever |= !gone;
        if gone != self.missing {
            self.missing = gone;
            out.missing_changed = Some(gone);
            out.findings.push(Finding::new(
                if gone {
                    Severity::Warning
                } else {
                    Severity::Info
                },
                FindingCode::MissingChannel,
                &self.path.display().to_string(),
                None,
                None,
                if gone {
                    format!(
                        "folder {} is not there (any more){}; it is looked for again at every poll",
                        self.path.display(),
                        match &listed {
                            Err(e) => format!(" ({e})"),
                            Ok(()) => String::new(),
                        }
                    )
                } else {
                    format!("folder {} is there; following it", self.path.display())
                },
            ));
        }
        if gone {
            return out;
        }
        let now = SystemTime::now();
        let settle = Duration::from_millis(SETTLE_MS);
        files.append(&mut self.pending);
        files.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)));
        files.dedup_by(|a, b| a.0 == b.0);
        let mut newest_log: Option<PathBuf> = None;
        let mut held = false;
        // The oldest image left for a later scan (no room for it).
        let mut first_left: Option<SystemTime> = None;
        for (p, m) in files {
            if self.watermark.is_some_and(|w| m <= w) || self.seen.get(&p) == Some(&m) {
                continue;
            }
            let is_log = ext(&p) == "mcap";
            if !is_log && (first_left.is_some() || out.images.len() >= room) {
                first_left.get_or_insert(m);
                continue;
            }
            if !is_log && (held || now.duration_since(m).unwrap_or_default() < settle) {
                // Not settled (or after one that is not): in order, later.
                held = true;
                self.pending.push((p, m));
                continue;
            }
            if is_log && self.seen.contains_key(&p) {
                continue; // a growing log is followed, not found again
            }
            self.seen.insert(p.clone(), m);
            if is_log {
                if self.first {
                    newest_log = Some(p);
                } else {
                    out.logs.push(p);
                }
            } else {
                out.images.push(p);
            }
        }
        if let Some(l) = newest_log {
            out.logs.push(l);
        }
        self.first = false;
        let first_left = first_left.or(dropped);
        self.behind = first_left.is_some();
        // Forget old names behind a watermark (never up to an image left
        // for later: the watermark must stay below it).
        let cutoff = (now - Duration::from_secs(FORGET_S)).min(first_left.unwrap_or(now));
        let old: Vec<(PathBuf, SystemTime)> = self
            .seen
            .iter()
            .filter(|(_, m)| **m < cutoff)
            .map(|(p, m)| (p.clone(), *m))
            .collect();
        for (p, m) in old {
            self.seen.remove(&p);
            self.watermark = Some(self.watermark.map_or(m, |w| w.max(m)));
        }
        self.give_back_room();
        out
    }

    /// A burst of images (a catch-up after a stall, a camera's backlog)
    /// grows the map of seen names past what the forgetting window holds
    /// in steady running; a hash map keeps its largest table for good, so
    /// once the burst is forgotten the room is given back (with a margin:
    /// not at every scan).
    fn give_back_room(&mut self) {
        let len = self.seen.len().max(1024);
        if self.seen.capacity() > 3 * len {
            self.seen.shrink_to(len + len / 2);
        }
    }

    /// Forgets every name and the watermark (tests: a listing after the
    /// forgetting window, on a folder whose files are all still there).
    #[cfg(test)]
    pub(crate) fn forget_all(&mut self) {
        self.seen.clear();
        self.watermark = None;
    }

    /// Marks a file as seen (a log followed by name).
    pub fn mark_seen(&mut self, p: &Path) {
        let m = std::fs::metadata(p)
            .and_then(|m| m.modified())
            .unwrap_or_else(|_| SystemTime::now());
        self.seen.insert(p.to_path_buf(), m);
    }

    /// Names remembered (for the memory bound).
    pub fn remembered(&self) -> usize {
        self.seen.len()
    }
}

/// What tells a file from another of the same name (a rig that reuses
/// a name writes a new file): its inode and length where there are inodes,
/// else its length and modification time.
pub(super) type FileIdentity = (u64, u64);

pub(super) fn file_identity(p: &Path) -> Option<FileIdentity> {
    let md = std::fs::metadata(p).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((md.ino(), md.len()))
    }
    #[cfg(not(unix))]
    {
        let m = md.modified().ok()?;
        let ns = m
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        Some((ns, md.len()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs::File;

    /// `n` images with modification times one second apart, old enough to
    /// be settled.
    fn folder(n: usize) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        let t0 = SystemTime::now() - Duration::from_secs(3600);
        for i in 0..n {
            let f = File::create(d.path().join(format!("img-{i:04}.png"))).unwrap();
            f.set_modified(t0 + Duration::from_secs(i as u64)).unwrap();
        }
        d
    }

    fn names(v: &[PathBuf]) -> Vec<String> {
        v.iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect()
    }

    #[test]
    fn a_full_folder_is_handed_out_in_order_a_room_at_a_time_each_image_once() {
        let d = folder(50);
        let mut t = FolderTail::new(d.path());
        let mut got = Vec::new();
        let mut scans = 0;
        loop {
            // Events name nothing: while behind, the scan lists anyway.
            let s = t.scan(Some(&[]), 16);
            assert!(s.images.len() <= 16);
            got.extend(names(&s.images));
            scans += 1;
            if !t.behind {
                break;
            }
            assert!(scans < 10);
        }
        let want: Vec<String> = (0..50).map(|i| format!("img-{i:04}.png")).collect();
        assert_eq!(got, want);
        assert_eq!(scans, 4);
        // Nothing new afterwards, and nothing remembered beyond the bound.
        assert!(t.scan(None, 16).images.is_empty());
        assert!(t.remembered() <= 50);
    }

    #[test]
    fn the_watermark_never_passes_an_image_left_for_later() {
        // All images older than FORGET_S: each scan forgets what it handed
        // out behind a watermark, which must stay below those left.
        let d = folder(10);
        let mut t = FolderTail::new(d.path());
        let a = t.scan(None, 3);
        assert_eq!(
            names(&a.images),
            ["img-0000.png", "img-0001.png", "img-0002.png"]
        );
        assert!(t.behind);
        let b = t.scan(None, 100);
        assert_eq!(b.images.len(), 7, "{:?}", names(&b.images));
        assert!(!t.behind);
        assert_eq!(t.remembered(), 0, "all forgotten behind the watermark");
    }

    #[test]
    fn a_burst_of_images_does_not_keep_its_room() {
        // 10 000 images at once (a catch-up): remembered while handed out,
        // forgotten behind the watermark in the same scan (all are older
        // than FORGET_S); the map's table must not stay sized for them.
        let d = tempfile::tempdir().unwrap();
        let t0 = SystemTime::now() - Duration::from_secs(3 * 3600);
        for i in 0..10_000u64 {
            let f = File::create(d.path().join(format!("img-{i:05}.png"))).unwrap();
            f.set_modified(t0 + Duration::from_secs(i)).unwrap();
        }
        let mut t = FolderTail::new(d.path());
        assert_eq!(t.scan(None, 20_000).images.len(), 10_000);
        assert_eq!(t.remembered(), 0);
        assert!(
            t.seen.capacity() < 4 * 1024,
            "room kept: {}",
            t.seen.capacity()
        );
        // A steady map (within the margin) is not shrunk at every scan.
        for i in 0..900 {
            t.seen
                .insert(PathBuf::from(format!("x{i}")), SystemTime::now());
        }
        let cap = t.seen.capacity();
        t.give_back_room();
        assert_eq!(t.seen.capacity(), cap);
        // A burst of twice the steady names, then back to the steady
        // number (a shift's hour after a catch-up): the burst's table goes.
        t.seen.clear();
        for i in 0..60_000 {
            t.seen
                .insert(PathBuf::from(format!("y{i}")), SystemTime::now());
        }
        t.seen
            .retain(|p, _| p.to_string_lossy()[1..].parse::<u32>().unwrap() % 2 == 0);
        t.give_back_room();
        assert!(
            t.seen.capacity() <= 60_000,
            "room kept: {}",
            t.seen.capacity()
        );
    }
}
