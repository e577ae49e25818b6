//! Cycles of a growing log, each found once: the samples since the last
//! reported cycle are kept in a short analysis window, and the rig's own
//! cycle analysis ([`crate::rig::cycles::analyse`]) runs on that window at
//! every poll. A cycle is reported when it is complete and the samples
//! after its end (the resampling's margin) have arrived; then the window
//! is cut a quarter of a cycle before the next cycle's start.
//!
//! Why the same analysis gives the batch's figures: a cycle's grid and
//! figures depend only on its own samples (plus a margin) and on the
//! run's sensor zeros. The zeros come from the `rig` metadata when the
//! rig writes them (a calibrated rig; `pinsight rig-sim` does); when it
//! does not, they are estimated on the first [`super::FollowConfig::
//! warmup_cycles`] cycles and then held (a batch run estimates them over
//! the whole file, so its figures differ by that estimate's change; the
//! force tare is then a constant, where a batch run fits its drift).

use super::decode::Samples;
use crate::rig::channel_map::{ChannelMap, SignalKind};
use crate::rig::cycles::{CycleOptions, CycleSet, CycleSource, analyse};
use crate::rig::load::{RigLog, Signals};
use crate::rig::mcap_read::ContainerInfo;
use crate::rig::meta::RigMeta;
use crate::rig::report::{Finding, FindingCode, LoadReport, LoadStatus, ReadCounts, Severity};
use crate::rig::signals::Signal;
use std::collections::BTreeMap;

/// Longest window kept while no cycle is found (s of log time).
pub const MAX_WINDOW_S: f64 = 20.0;

/// A signal's samples in the window, sorted by time.
#[derive(Debug, Clone, Default)]
struct Series {
    t: Vec<i64>,
    v: Vec<f64>,
}

impl Series {
    /// Adds samples (any order): sorted, the first of equal times kept.
    fn add(&mut self, mut s: Samples) {
        if s.is_empty() {
            return;
        }
        let sorted = s.windows(2).all(|w| w[0].0 <= w[1].0);
        if !sorted {
            s.sort_by_key(|x| x.0);
        }
        if self.t.last().is_none_or(|&l| s[0].0 > l) {
            for (t, v) in s {
                if self.t.last() != Some(&t) {
                    self.t.push(t);
                    self.v.push(v);
                }
            }
            return;
        }
        // Late samples: merge (rare: blocks written slightly out of order).
        let mut all: Vec<(i64, f64)> = self.t.iter().copied().zip(self.v.iter().copied()).collect();
        all.extend(s);
        all.sort_by_key(|x| x.0);
        all.dedup_by_key(|x| x.0);
        self.t = all.iter().map(|x| x.0).collect();
        self.v = all.iter().map(|x| x.1).collect();
    }

    fn cut_before(&mut self, t0: i64) {
        let i = self.t.partition_point(|&t| t < t0);
        self.t.drain(..i);
        self.v.drain(..i);
        super::ring::give_back_room(&mut self.t, &mut self.v);
    }
}

/// What one analysis found.
#[derive(Debug, Default)]
pub struct NewCycles {
    /// The cycle set of the window with only the new cycles in it (its
    /// grid, ideal stroke, standoff and offsets describe them).
    pub set: Option<CycleSet>,
    pub findings: Vec<Finding>,
}

/// Finds the cycles of one log as it grows.
pub struct CycleTracker {
    file: String,
    map: ChannelMap,
    meta: RigMeta,
    base: CycleOptions,
    opts: CycleOptions,
    frozen: bool,
    warmup: usize,
    window: BTreeMap<SignalKind, Series>,
    last_start: Option<i64>,
    last_dur_ns: i64,
    /// Cycles reported so far.
    pub reported: u64,
    said_no_cycles: bool,
}

impl CycleTracker {
    pub fn new(file: &str, map: ChannelMap, opts: CycleOptions, warmup: usize) -> Self {
        CycleTracker {
            file: file.to_string(),
            map,
            meta: RigMeta::default(),
            base: opts.clone(),
            opts,
            frozen: false,
            warmup: warmup.max(1),
            window: BTreeMap::new(),
            last_start: None,
            last_dur_ns: 0,
            reported: 0,
            said_no_cycles: false,
        }
    }

    /// The run's metadata (read from the file's `rig` record).
    pub fn set_meta(&mut self, meta: RigMeta) {
        self.meta = meta;
        self.opts = self.base.clone();
        self.frozen = false;
    }

    pub fn meta(&self) -> &RigMeta {
        &self.meta
    }

    pub fn push(&mut self, kind: SignalKind, s: Samples) {
        self.window.entry(kind).or_default().add(s);
    }

    /// Latest sample time of a signal in the window.
    pub fn last_time(&self, kind: SignalKind) -> Option<i64> {
        self.window.get(&kind).and_then(|s| s.t.last().copied())
    }

    /// Samples held (for the memory bound).
    pub fn samples(&self) -> usize {
        self.window.values().map(|s| s.t.len()).sum()
    }

    fn rig_log(&self) -> RigLog {
        let mut signals = Signals::default();
        let mut start: Option<i64> = None;
        let mut end: Option<i64> = None;
        for (k, s) in &self.window {
            if s.t.is_empty() {
                continue;
            }
            start = Some(start.map_or(s.t[0], |x| x.min(s.t[0])));
            end = Some(end.map_or(s.t[s.t.len() - 1], |x| x.max(s.t[s.t.len() - 1])));
            let src = self.map.get(*k);
            let sig = Signal {
                kind: *k,
                topic: src.map(|s| s.topic.clone()).unwrap_or_default(),
                field: src.map(|s| s.field.clone()).unwrap_or_default(),
                unit: k.unit().into(),
                t_ns: s.t.clone(),
                values: s.v.clone(),
            };
            match k {
                SignalKind::Angle => signals.angle = Some(sig),
                SignalKind::Speed => signals.speed = Some(sig),
                SignalKind::Force => signals.force = Some(sig),
                SignalKind::Displacement => signals.displacement = Some(sig),
                SignalKind::Cycle => signals.cycle = Some(sig),
            }
        }
        RigLog {
            file: self.file.clone(),
            container: ContainerInfo::default(),
            meta: self.meta.clone(),
            channel_map: self.map.clone(),
            channels: Vec::new(),
            signals,
            stats: Vec::new(),
            attachments: Vec::new(),
            images: Vec::new(),
            log_start_ns: start,
            log_end_ns: end,
            report: LoadReport {
                file: self.file.clone(),
                status: LoadStatus::Ok,
                findings: Vec::new(),
                counts: ReadCounts::default(),
                elapsed_s: 0.0,
            },
        }
    }

    fn needs_warmup(&self) -> bool {
        let has = |k| self.window.contains_key(&k);
        (self.meta.angle_offset_rad.is_none() && self.base.angle_offset_rad.is_none())
            || (has(SignalKind::Displacement)
                && self.meta.laser_zero_mm.is_none()
                && self.base.laser_zero_mm.is_none())
            || (has(SignalKind::Force)
                && self.meta.force_tare_n.is_none()
                && self.base.force_tare_n.is_none())
    }

    /// Analyses the window; `ended`: no more samples will come (then every
    /// complete cycle is reported).
    pub fn analyse(&mut self, ended: bool) -> NewCycles {
        let mut out = NewCycles::default();
        let log = self.rig_log();
        let Some(latest) = log.log_end_ns else {
            return out;
        };
        let mut cs = analyse(&log, &self.opts);
        if !self.frozen {
            if self.needs_warmup() && cs.cycles.len() < self.warmup && !ended {
                self.bound_window(latest, &mut out);
                return out;
            }
            let o = &cs.offsets;
            if self.needs_warmup() {
                out.findings.push(Finding::new(
                    Severity::Info,
                    FindingCode::OffsetEstimated,
                    &self.file,
                    None,
                    None,
                    format!(
                        "live: sensor zeros missing from the metadata were estimated on the first {} cycles and are held from now on (angle offset {:.5} rad, laser zero {:.4} mm, force tare {:.4} N)",
                        cs.cycles.len(),
                        o.angle_offset_rad.applied,
                        o.laser_zero_mm.applied,
                        o.force_tare_n.applied
                    ),
                ));
            }
            self.opts.angle_offset_rad = Some(o.angle_offset_rad.applied);
            if self.window.contains_key(&SignalKind::Displacement) {
                self.opts.laser_zero_mm = Some(o.laser_zero_mm.applied);
            }
            if self.window.contains_key(&SignalKind::Force) {
                self.opts.force_tare_n = Some(o.force_tare_n.applied);
            }
            self.frozen = true;
            // The zeros now held are the ones just used: no second analysis.
        }
        // Complete: every signal present has samples past the cycle's end
        // plus the resampling's margin.
        let horizon = [
            SignalKind::Angle,
            SignalKind::Displacement,
            SignalKind::Force,
            SignalKind::Speed,
        ]
        .into_iter()
        .filter_map(|k| self.last_time(k))
        .min()
        .unwrap_or(latest);
        let marks = cs.source == CycleSource::Marks;
        let mut keep = Vec::new();
        for mut c in std::mem::take(&mut cs.cycles) {
            let dur = c.t_end_ns - c.t_start_ns;
            let new = self.last_start.is_none_or(|s| c.t_start_ns > s + dur / 2);
            let complete = ended || c.t_end_ns + dur / 10 <= horizon;
            if !new || !complete {
                continue;
            }
            if !marks {
                c.index = self.reported;
            }
            self.last_start = Some(c.t_start_ns);
            self.last_dur_ns = dur;
            self.reported += 1;
            keep.push(c);
        }
        if let Some(last) = keep.last() {
            let cut = last.t_end_ns - self.last_dur_ns / 4;
            for s in self.window.values_mut() {
                s.cut_before(cut);
            }
            self.said_no_cycles = false;
        } else {
            self.bound_window(latest, &mut out);
        }
        if !keep.is_empty() {
            cs.cycles = keep;
            cs.findings.clear();
            out.set = Some(cs);
        }
        out
    }

    /// Keeps the window bounded while no cycle is found.
    fn bound_window(&mut self, latest: i64, out: &mut NewCycles) {
        let first = self
            .window
            .values()
            .filter_map(|s| s.t.first())
            .min()
            .copied();
        let span = (MAX_WINDOW_S * 1e9) as i64;
        if first.is_some_and(|f| latest - f > span) {
            let cut = latest - span / 2;
            for s in self.window.values_mut() {
                s.cut_before(cut);
            }
            if !self.said_no_cycles {
                self.said_no_cycles = true;
                out.findings.push(Finding::new(
                    Severity::Warning,
                    FindingCode::Cycle,
                    &self.file,
                    None,
                    None,
                    format!(
                        "live: no complete cycle in the last {MAX_WINDOW_S:.0} s of the log (no crank angle, or the crank stands still); older samples are dropped"
                    ),
                ));
            }
        }
    }
}
