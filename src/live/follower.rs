//! The follower: every followed log and folder, polled together. One
//! [`Follower::poll`] reads what was written since the last one, finds the
//! new cycles (and judges them with a process recipe), inspects the new
//! images, updates the yield and the alarms, and returns it all as a
//! [`LiveBatch`]. `pinsight watch` prints the batch's events; the TUI's
//! live thread sends the batch to the interface.

use super::alarms::{Alarms, CycleInput};
use super::cycles::CycleTracker;
use super::decode::LiveDecoder;
use super::events::*;
use super::folder::{FileIdentity, FolderTail, file_identity};
use super::tail::{McapTail, TailState};
use super::{FollowConfig, FollowInputs};
use crate::process::{CycleStatus, ProcessRecipe, learn, monitor};
use crate::rig::channel_map::SignalKind;
use crate::rig::cycles::CycleSet;
use crate::rig::meta::RigMeta;
use crate::rig::report::{Finding, FindingCode, Severity};
use crate::vision::InspectOptions;
use crate::vision::batch::{
    Item, ItemMeta, ItemResult, ItemStatus, RecipeBook, Source, inspect_item,
};
use crate::vision::report::{GroupBy, YieldReport};
use crate::vision::yield_acc::YieldAcc;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The process monitor of one log: held back until its envelopes are learned.
struct Judge {
    recipe: ProcessRecipe,
    learn: usize,
    learned: bool,
    held: Option<CycleSet>,
}

struct LogFollow {
    name: String,
    tail: McapTail,
    dec: LiveDecoder,
    tracker: CycleTracker,
    meta_raw: BTreeMap<String, String>,
    state: FileState,
    told: Option<FileState>,
    judge: Option<Judge>,
    setpoint: Option<f64>,
    /// Metadata of its images (lot, part, rig, speed).
    meta: RigMeta,
    started: Instant,
    bytes: u64,
}

impl LogFollow {
    /// The log's state as the interface lists it.
    fn file_event(&self) -> FileEvent {
        FileEvent {
            path: self.name.clone(),
            state: self.state,
            bytes: self.bytes,
            cycles: self.tracker.reported,
        }
    }

    /// Tells `b` the log's state (in its file list and as an event).
    fn tell(&mut self, b: &mut LiveBatch) {
        self.told = Some(self.state);
        let e = self.file_event();
        b.files.push(e.clone());
        b.events.push(LiveEvent::File(e));
    }
}

/// Most images inspected in one poll (a larger backlog over several): one
/// poll's results travel to the interface as one batch, so a backlog of
/// thousands (a camera folder found full, a follower that fell behind)
/// must not become one batch of thousands.
pub const IMAGES_PER_POLL: usize = 64;

/// Most images waiting in the follower's queue: the rest of a backlog
/// stays on disk, found again by the folder's next scan.
pub const IMAGES_QUEUED: usize = 4 * IMAGES_PER_POLL;

/// An image waiting to be inspected.
struct ImageJob {
    item: Item,
    path: Option<PathBuf>,
    bytes: Option<Arc<Vec<u8>>>,
    tries: u8,
}

impl ImageJob {
    /// An image file (named explicitly or found in a folder); its cycle
    /// from its name where the name carries one.
    fn file(p: PathBuf) -> Self {
        ImageJob {
            item: Item {
                name: p.display().to_string(),
                source: Source::Path(p.clone()),
                meta: ItemMeta {
                    cycle: cycle_of_name(&p),
                    ..Default::default()
                },
            },
            path: Some(p),
            bytes: None,
            tries: 0,
        }
    }
}

/// A followed folder and what it is for.
struct FolderFollow {
    tail: FolderTail,
    /// Images are read from it (false: only new logs, the rotation of a followed file).
    images: bool,
}

/// Counts for the end of a `watch` and the Session pane.
#[derive(Debug, Clone, Serialize)]
pub struct LiveSummary {
    pub logs: Vec<FileEvent>,
    pub cycles: u64,
    pub images: u64,
    pub process_ok: u64,
    pub process_nok: u64,
    pub process_not_evaluated: u64,
    pub findings: u64,
    pub alarms_raised: u64,
    pub yields: Option<YieldReport>,
}

/// Follows logs and folders.
pub struct Follower {
    inputs: FollowInputs,
    logs: Vec<LogFollow>,
    /// Logs finished and let go ([`Follower::retire`]), as the summary lists them.
    retired: Vec<FileEvent>,
    /// The files of those logs still on disk, by path and identity: a
    /// folder listing that finds one again (its name forgotten by the
    /// folder's tail) must not follow it again from the start.
    retired_files: Vec<(PathBuf, FileIdentity)>,
    folders: Vec<FolderFollow>,
    queue: VecDeque<ImageJob>,
    alarms: Alarms,
    yields: YieldAcc,
    order: u64,
    t0: Option<i64>,
    counts: LiveSummary,
    last_rescan: Instant,
    /// When the allocator last gave free room back (once a minute).
    last_trim: Instant,
}

fn cycle_of_name(p: &Path) -> Option<u64> {
    let s = p.file_stem()?.to_string_lossy().to_string();
    let i = s.find("cycle-")?;
    let digits: String = s[i + 6..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().ok()
}

impl Follower {
    pub fn new(inputs: FollowInputs) -> Self {
        crate::allocator::settle_for_a_shift();
        let alarms = Alarms::new(inputs.alarms.clone());
        let mut f = Follower {
            logs: Vec::new(),
            retired: Vec::new(),
            retired_files: Vec::new(),
            folders: Vec::new(),
            queue: VecDeque::new(),
            alarms,
            yields: YieldAcc::new(GroupBy::Lot),
            order: 0,
            t0: None,
            counts: LiveSummary {
                logs: Vec::new(),
                cycles: 0,
                images: 0,
                process_ok: 0,
                process_nok: 0,
                process_not_evaluated: 0,
                findings: 0,
                alarms_raised: 0,
                yields: None,
            },
            last_rescan: Instant::now(),
            last_trim: Instant::now(),
            inputs,
        };
        for p in f.inputs.paths.clone() {
            let is_log = p
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
            // A bare file name is in the current folder (its rotation is found there).
            let p = if is_log && p.parent().is_some_and(|d| d.as_os_str().is_empty()) {
                Path::new(".").join(&p)
            } else {
                p
            };
            if p.is_dir() || (!p.exists() && !is_log) {
                f.folders.push(FolderFollow {
                    tail: FolderTail::new(&p),
                    images: true,
                });
            } else if is_log {
                f.add_log(&p);
                // A rig that starts a new file per run: its next file.
                let parent = p
                    .parent()
                    .filter(|d| !d.as_os_str().is_empty())
                    .unwrap_or(Path::new("."));
                if !f.folders.iter().any(|d| d.tail.path == parent) {
                    let mut t = FolderTail::new(parent);
                    let _ = t.scan(None, usize::MAX); // what is there now is not new
                    t.mark_seen(&p);
                    f.folders.push(FolderFollow {
                        tail: t,
                        images: false,
                    });
                }
            } else {
                // An image named explicitly.
                f.queue.push_back(ImageJob::file(p.clone()));
            }
        }
        f
    }

    /// Folders and their recursion for file-system events.
    pub fn watch_paths(&self) -> Vec<(PathBuf, bool)> {
        self.folders
            .iter()
            .map(|d| (d.tail.path.clone(), d.images))
            .collect()
    }

    pub fn config(&self) -> &FollowConfig {
        &self.inputs.config
    }

    fn add_log(&mut self, p: &Path) {
        if self.logs.iter().any(|l| l.tail.path == p)
            || self
                .retired_files
                .iter()
                .any(|(r, id)| r == p && file_identity(p).as_ref() == Some(id))
        {
            return;
        }
        let name = p.display().to_string();
        self.logs.push(LogFollow {
            tail: McapTail::new(p),
            dec: LiveDecoder::new(self.inputs.channel_map.clone()),
            tracker: CycleTracker::new(
                &name,
                self.inputs.channel_map.clone(),
                self.inputs.cycle_options.clone(),
                self.inputs.config.warmup_cycles,
            ),
            meta_raw: BTreeMap::new(),
            state: FileState::Waiting,
            told: None,
            judge: self.inputs.process.clone().map(|r| Judge {
                learned: r.envelope.iter().all(|e| !e.x_grid.is_empty()) || self.inputs.learn == 0,
                learn: self.inputs.learn,
                recipe: r,
                held: None,
            }),
            setpoint: None,
            meta: RigMeta::default(),
            started: Instant::now(),
            bytes: 0,
            name,
        });
    }

    /// Work is left over from the last poll (a log read up to
    /// [`crate::live::tail::MAX_READ`], images over [`IMAGES_PER_POLL`]):
    /// poll again at once instead of waiting for the files to change.
    pub fn behind(&self) -> bool {
        // (An image retried because it was caught half-written waits.)
        self.queue.iter().any(|j| j.tries == 0)
            || self.logs.iter().any(|l| l.tail.behind())
            || self.folders.iter().any(|d| d.tail.behind)
    }

    /// Every log followed is finished (or left) and nothing is queued.
    pub fn all_finished(&self) -> bool {
        !self.logs.is_empty()
            && self.queue.is_empty()
            && self.logs.iter().all(|l| {
                matches!(l.state, FileState::Finished | FileState::Abandoned)
                    || (l.state == FileState::Deleted && l.tail.state == TailState::Finished)
            })
    }

    /// Counts so far.
    pub fn summary(&self) -> LiveSummary {
        let mut s = self.counts.clone();
        s.logs = self
            .retired
            .iter()
            .cloned()
            .chain(self.logs.iter().map(LogFollow::file_event))
            .collect();
        s.yields = (self.order > 0).then(|| self.yields.report());
        s
    }

    /// Samples and names held (the memory the follower keeps; bounded).
    pub fn held(&self) -> usize {
        self.logs.iter().map(|l| l.tracker.samples()).sum::<usize>()
            + self
                .folders
                .iter()
                .map(|f| f.tail.remembered())
                .sum::<usize>()
            + self.queue.len()
    }

    /// Reads what is new. `changed`: paths file-system events named (None:
    /// list every folder).
    pub fn poll(&mut self, changed: Option<&[PathBuf]>) -> LiveBatch {
        let mut b = LiveBatch::default();
        let rescan = changed.is_none() || self.last_rescan.elapsed().as_secs() >= 30;
        if rescan {
            self.last_rescan = Instant::now();
        }
        if self.last_trim.elapsed().as_secs() >= 60 {
            self.last_trim = Instant::now();
            crate::allocator::give_back_free_room();
        }
        // Folders: new images and new logs.
        let mut new_logs = Vec::new();
        let queued = self.queue.len();
        for d in &mut self.folders {
            // Images are looked for when the queue is nearly empty (a folder
            // of thousands is listed once per a few polls, not every one).
            if d.images && queued > IMAGES_PER_POLL {
                d.tail.defer();
                continue;
            }
            // (A folder followed for its logs hands out its images unread.)
            let room = if d.images {
                IMAGES_QUEUED - queued
            } else {
                usize::MAX
            };
            let scan = d.tail.scan(if rescan { None } else { changed }, room);
            for f in scan.findings {
                b.events.push(LiveEvent::Finding(f));
            }
            if let Some(missing) = scan.missing_changed {
                b.files.push(FileEvent {
                    path: d.tail.path.display().to_string(),
                    state: if missing {
                        FileState::Missing
                    } else {
                        FileState::Following
                    },
                    bytes: 0,
                    cycles: 0,
                });
            }
            new_logs.extend(scan.logs);
            if d.images {
                for p in scan.images {
                    self.queue.push_back(ImageJob::file(p));
                }
            }
        }
        for p in new_logs {
            self.add_log(&p);
        }
        // Logs.
        for i in 0..self.logs.len() {
            self.poll_log(i, &mut b);
        }
        self.rotate(&mut b);
        self.inspect(&mut b);
        self.retire();
        b.t0_ns = self.t0;
        b.active_alarms = self.alarms.active();
        for e in &b.events {
            match e {
                LiveEvent::Finding(_) => self.counts.findings += 1,
                LiveEvent::Alarm(a) if a.raised => self.counts.alarms_raised += 1,
                _ => {}
            }
        }
        b
    }

    fn poll_log(&mut self, i: usize, b: &mut LiveBatch) {
        let l = &mut self.logs[i];
        if matches!(l.state, FileState::Finished | FileState::Abandoned) {
            return;
        }
        let r = l.tail.poll();
        l.bytes += r.bytes;
        b.bytes += r.bytes;
        let mut state = l.state;
        if l.tail.state != TailState::Opening && state == FileState::Waiting {
            state = FileState::Following;
        }
        if l.tail.detached {
            state = FileState::Deleted;
        }
        for f in r.findings {
            b.events.push(LiveEvent::Finding(f));
        }
        let mut meta_changed = false;
        for m in r.metadata.into_iter().filter(|m| m.name == "rig") {
            l.meta_raw.extend(m.map);
            meta_changed = true;
        }
        if meta_changed {
            let mut findings = Vec::new();
            let mut meta = RigMeta::from_raw(l.meta_raw.clone(), &l.name, &mut findings);
            meta.present = true;
            let meta = meta.apply_overrides(&self.inputs.meta_overrides, &l.name, &mut findings);
            for f in findings
                .into_iter()
                .filter(|f| f.severity >= Severity::Warning)
            {
                b.events.push(LiveEvent::Finding(f));
            }
            l.setpoint = meta.motor_rpm;
            l.meta = meta.clone();
            l.tracker.set_meta(meta);
        }
        l.dec.add_defs(r.schemas, r.channels);
        let mut samples: BTreeMap<SignalKind, Vec<(i64, f64)>> = BTreeMap::new();
        for it in &r.items {
            let d = l.dec.decode(it);
            if let Some((code, sev, text)) = d.problem {
                if d.discarded && it.at_eof && l.tail.retry(it.item.offset) {
                    break; // read again at the next poll: maybe caught mid-write
                }
                b.events.push(LiveEvent::Finding(Finding::new(
                    sev,
                    code,
                    &l.name,
                    None,
                    Some(crate::rig::report::Place::byte(it.item.offset)),
                    format!("{}: {text}", l.name),
                )));
                if d.discarded {
                    continue;
                }
            }
            b.chunks += 1;
            for (k, s) in d.samples {
                samples.entry(k).or_default().extend(s);
            }
            for img in d.images {
                let name = match img.cycle {
                    Some(c) => format!("{}#cycle-{c}", l.name),
                    None => format!("{}#{}", l.name, img.log_time_ns),
                };
                let meta = ItemMeta {
                    lot: l.meta.lot.clone(),
                    part_number: l.meta.part_number.clone(),
                    rig_id: l.meta.rig_id.clone(),
                    motor_rpm: l.meta.motor_rpm,
                    clearance_mm: l.meta.clearance_mm,
                    cycle: img.cycle,
                    log: Some(l.name.clone()),
                    log_time_ns: Some(img.log_time_ns),
                };
                let bytes = img.data.map(Arc::new);
                self.queue.push_back(ImageJob {
                    item: Item {
                        name,
                        source: Source::Bytes(bytes.clone().unwrap_or_default()),
                        meta,
                    },
                    path: None,
                    bytes,
                    tries: 0,
                });
            }
        }
        let ended = l.tail.state == TailState::Finished;
        if ended && state != FileState::Deleted {
            state = FileState::Finished;
        }
        for (k, mut s) in samples {
            s.sort_by_key(|x| x.0);
            if let Some(&(t, _)) = s.first() {
                self.t0 = Some(self.t0.map_or(t, |x| x.min(t)));
            }
            l.tracker.push(k, s.clone());
            b.samples.push((k, s));
        }
        let found = l.tracker.analyse(ended);
        for f in found.findings {
            b.events.push(LiveEvent::Finding(f));
        }
        if let Some(set) = found.set {
            let judged = match l.judge.as_mut() {
                None => vec![(set, None)],
                Some(j) => Self::judge(j, set, ended, &l.name, b),
            };
            for (set, verdicts) in judged {
                let verdicts: Option<Vec<_>> = verdicts;
                let mut template = set.clone();
                template.cycles.clear();
                b.cycle_set = Some(Arc::new(template));
                for (k, c) in set.cycles.into_iter().enumerate() {
                    let v = verdicts.as_ref().and_then(|v| v.get(k).cloned());
                    match v.as_ref().map(|v| v.status) {
                        Some(CycleStatus::Ok) => self.counts.process_ok += 1,
                        Some(CycleStatus::Nok) => self.counts.process_nok += 1,
                        Some(CycleStatus::NotEvaluated) => self.counts.process_not_evaluated += 1,
                        None => {}
                    }
                    self.counts.cycles += 1;
                    let mut al = Vec::new();
                    self.alarms.cycle(
                        &CycleInput {
                            file: &l.name,
                            index: c.index,
                            t_ns: c.t_start_ns,
                            motor_rpm: c.motor_rpm_mean,
                            stroke_dev_rms_mm: c.stroke_dev_rms_mm,
                            nok: v.as_ref().and_then(|v| match v.status {
                                CycleStatus::Ok => Some(false),
                                CycleStatus::Nok => Some(true),
                                CycleStatus::NotEvaluated => None,
                            }),
                            setpoint_rpm: l.setpoint,
                        },
                        &mut al,
                    );
                    b.events
                        .push(LiveEvent::Cycle(CycleEvent::of(&l.name, &c, v.as_ref())));
                    b.events.extend(al.into_iter().map(LiveEvent::Alarm));
                    b.cycles.push(LiveCycle {
                        file: l.name.clone(),
                        cycle: c,
                        verdict: v,
                    });
                }
            }
        }
        let last: Vec<(SignalKind, i64)> = SignalKind::ALL
            .into_iter()
            .filter_map(|k| l.tracker.last_time(k).map(|t| (k, t)))
            .collect();
        let mut al = Vec::new();
        if !ended {
            self.alarms.sensors(&l.name, &last, &mut al);
        }
        b.events.extend(al.into_iter().map(LiveEvent::Alarm));
        l.state = state;
        if l.told != Some(state) {
            l.tell(b);
        }
    }

    /// Judges new cycles, or holds them until the envelopes are learned.
    /// Returns the sets to report with their verdicts.
    fn judge(
        j: &mut Judge,
        set: CycleSet,
        ended: bool,
        name: &str,
        b: &mut LiveBatch,
    ) -> Vec<(CycleSet, Option<Vec<crate::process::CycleVerdict>>)> {
        let set = if j.learned {
            set
        } else {
            let held = match j.held.take() {
                None => set,
                Some(mut h) => {
                    h.cycles.extend(set.cycles);
                    h
                }
            };
            match learn(&j.recipe, &held, j.learn) {
                Ok((r, what)) => {
                    j.recipe = r;
                    j.learned = true;
                    b.events.push(LiveEvent::Finding(Finding::new(
                        Severity::Info,
                        FindingCode::Cycle,
                        name,
                        None,
                        None,
                        format!("live: {what}"),
                    )));
                    held
                }
                Err(e) if ended || held.cycles.len() >= 4 * j.learn.max(1) => {
                    j.learned = true;
                    b.events.push(LiveEvent::Finding(Finding::new(
                        Severity::Warning,
                        FindingCode::Cycle,
                        name,
                        None,
                        None,
                        format!("live: the envelopes could not be learned ({e}); cycles are judged without them"),
                    )));
                    held
                }
                Err(_) => {
                    j.held = Some(held);
                    return Vec::new();
                }
            }
        };
        let rep = monitor(&j.recipe, &set);
        vec![(set, Some(rep.cycles))]
    }

    /// A log that stopped growing while a newer one is followed has been
    /// left by its writer; a deleted log that stopped growing is done.
    fn rotate(&mut self, b: &mut LiveBatch) {
        let grace = self.inputs.config.rotate_grace_s;
        let newest = self.logs.iter().map(|l| l.started).max();
        for l in &mut self.logs {
            let idle = l.tail.last_growth.elapsed().as_secs_f64() > grace;
            let newer = newest.is_some_and(|n| n > l.started);
            let live = matches!(l.state, FileState::Following | FileState::Deleted);
            if !(live && idle && (newer || l.state == FileState::Deleted)) {
                continue;
            }
            if let Some(f) = l.tail.abandon() {
                b.events.push(LiveEvent::Finding(f));
            }
            let found = l.tracker.analyse(true);
            for f in found.findings {
                b.events.push(LiveEvent::Finding(f));
            }
            if let Some(set) = found.set {
                for c in set.cycles {
                    self.counts.cycles += 1;
                    b.events
                        .push(LiveEvent::Cycle(CycleEvent::of(&l.name, &c, None)));
                    b.cycles.push(LiveCycle {
                        file: l.name.clone(),
                        cycle: c,
                        verdict: None,
                    });
                }
            }
            if l.state != FileState::Deleted {
                l.state = FileState::Abandoned;
            }
            l.tell(b);
        }
    }

    /// Lets go of the logs that are done and told, but the newest: their
    /// decoder, cycle tracker, process judge and open file (which holds a
    /// deleted file's disk space) go, their last state stays for the
    /// summary. A shift's rotated files (one every 20 minutes on a line)
    /// must not accumulate in memory.
    fn retire(&mut self) {
        let Some(newest) = self.logs.iter().map(|l| l.started).max() else {
            return;
        };
        let done = |l: &LogFollow| {
            l.started < newest
                && l.told == Some(l.state)
                && (matches!(l.state, FileState::Finished | FileState::Abandoned)
                    || (l.state == FileState::Deleted && l.tail.state == TailState::Finished))
        };
        let (gone, keep): (Vec<LogFollow>, Vec<LogFollow>) =
            std::mem::take(&mut self.logs).into_iter().partition(done);
        self.logs = keep;
        self.retired.extend(gone.iter().map(LogFollow::file_event));
        if !gone.is_empty() {
            // A file deleted since (an archive job) cannot be found again.
            self.retired_files.retain(|(p, _)| p.exists());
        }
        for l in &gone {
            if let Some(id) = file_identity(&l.tail.path) {
                self.retired_files.push((l.tail.path.clone(), id));
            }
        }
    }

    /// Inspects the queued images (in parallel, reported in order), at
    /// most [`IMAGES_PER_POLL`] of them.
    fn inspect(&mut self, b: &mut LiveBatch) {
        if self.queue.is_empty() {
            return;
        }
        let take = self.queue.len().min(IMAGES_PER_POLL);
        let jobs: Vec<ImageJob> = self.queue.drain(..take).collect();
        let book: &RecipeBook = &self.inputs.recipes;
        let n = jobs.len();
        let opts = InspectOptions::default();
        let results: Vec<(ItemResult, Option<crate::vision::Gray>)> = jobs
            .par_iter()
            .enumerate()
            .map(|(k, j)| inspect_item(&j.item, book, &opts, k + 1 == n))
            .collect();
        for (job, (r, gray)) in jobs.into_iter().zip(results) {
            // A file caught while a camera writes it: try again shortly.
            let young = job.path.as_ref().is_some_and(|p| {
                std::fs::metadata(p)
                    .and_then(|m| m.modified())
                    .is_ok_and(|m| m.elapsed().unwrap_or_default().as_secs_f64() < 2.0)
            });
            if r.status == ItemStatus::Error && young && job.tries < 5 {
                self.queue.push_back(ImageJob {
                    tries: job.tries + 1,
                    ..job
                });
                continue;
            }
            self.yields.add(self.order, &r);
            self.order += 1;
            self.counts.images += 1;
            let mut al = Vec::new();
            self.alarms.image(
                &r.name,
                match r.status {
                    ItemStatus::Pass => Some(true),
                    ItemStatus::Fail => Some(false),
                    ItemStatus::Error => None,
                },
                &mut al,
            );
            b.events.push(LiveEvent::Image(ImageEvent::of(&r)));
            b.events.extend(al.into_iter().map(LiveEvent::Alarm));
            let (preview, annotated, w, h) = match (&gray, &r.inspection) {
                (Some(g), ins) => {
                    let disp = image::DynamicImage::ImageLuma8(g.to_display_u8()).to_rgb8();
                    let ann = ins.as_ref().map(|i| {
                        Arc::new(crate::vision::overlay::draw_overlay(
                            g,
                            i,
                            &crate::vision::overlay::OverlayOptions::default(),
                        ))
                    });
                    (Some(Arc::new(disp)), ann, g.width, g.height)
                }
                _ => (None, None, 0, 0),
            };
            b.images.push(LiveImage {
                result: r,
                path: job.path,
                bytes: job.bytes,
                width: w,
                height: h,
                preview,
                annotated,
            });
        }
        if self.order > 0 {
            b.yields = Some(Arc::new(self.yields.report()));
        }
    }

    /// Ends following: every log still open is left as it is (a `watch`
    /// stopped by the user, the end of a demo).
    pub fn stop(&mut self) -> LiveBatch {
        let mut b = LiveBatch::default();
        for l in &mut self.logs {
            if matches!(l.state, FileState::Finished | FileState::Abandoned) {
                continue;
            }
            l.state = FileState::Abandoned;
            l.tell(&mut b);
        }
        b
    }
}

#[cfg(test)]
#[path = "follower_tests.rs"]
mod tests;
