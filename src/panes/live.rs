//! The live line as the panes see it: what the follower sent so far, kept
//! bounded for a whole shift. [`Session::absorb_live`] merges a
//! [`LiveBatch`] (on the UI thread; the follower runs on its own thread):
//! - the raw signals of the last `window_s` seconds become the session's
//!   first log's channels (the Signals pane draws them as any log's; in
//!   follow mode its window slides with the newest sample), with a min/max
//!   history of the whole shift per signal;
//! - each judged image enters the session's images with its inspection
//!   (the newest [`FollowConfig::recent_images`] are kept; the Vision pane
//!   shows the latest in follow mode), and the yield over every connector
//!   so far replaces the session's yield;
//! - cycles, alarms, findings and the files' states are kept as counts and
//!   short recent lists for the Session pane and the status line.

pub use super::live_state::{LiveState, RECENT_LINES};
use super::session::{
    FileEntry, FileKind, FileStatus, ImageEntry, ImageSource, Inspected, LogEntry, Session,
    YieldRun,
};
use crate::engine::signals::{Channel, SignalSet};
use crate::live::events::{FileState, LiveEvent};
use crate::live::ring::{MinMaxHistory, slide};
use crate::live::{FollowConfig, LiveBatch};
use crate::rig::channel_map::SignalKind;

fn describe(e: &LiveEvent) -> Option<String> {
    Some(match e {
        LiveEvent::Cycle(c) if c.status == Some("nok") => {
            format!("cycle {} NOK: {}", c.index, c.reasons.join("; "))
        }
        LiveEvent::Cycle(_) => return None,
        LiveEvent::Image(i) if i.status != crate::vision::batch::ItemStatus::Pass => format!(
            "image {} {:?}{}",
            i.cycle
                .map(|c| format!("cycle {c}"))
                .unwrap_or_else(|| i.name.clone()),
            i.status,
            if i.failed_pins.is_empty() {
                i.error
                    .clone()
                    .map(|e| format!(": {e}"))
                    .unwrap_or_default()
            } else {
                format!(": {}", i.failed_pins.join(", "))
            }
        ),
        LiveEvent::Image(_) => return None,
        LiveEvent::Alarm(a) => format!(
            "{} {}: {}",
            if a.raised { "ALARM" } else { "cleared" },
            a.rule,
            a.message
        ),
        LiveEvent::Finding(f) => format!("finding: {}", f.message),
        LiveEvent::File(f) => format!("{} {:?} ({} cycles)", f.path, f.state, f.cycles),
    })
}

impl Session {
    /// Starts a live session (the first log is the live line's signals).
    pub fn start_live(&mut self, config: FollowConfig, sources: Vec<String>) {
        self.title = format!("live: {}", sources.join(", "));
        self.logs.insert(
            0,
            LogEntry {
                path: format!("live: {}", sources.join(", ")),
                signals: SignalSet {
                    source: format!("live: {}", sources.join(", ")),
                    channels: Vec::new(),
                    cycles: Vec::new(),
                    meta: Vec::new(),
                },
                rig: None,
            },
        );
        self.live = Some(LiveState::new(config, sources));
    }

    /// Merges what the follower found (see the module doc).
    pub fn absorb_live(&mut self, b: LiveBatch) {
        let Some(mut live) = self.live.take() else {
            return;
        };
        if live.t0_ns.is_none() {
            live.t0_ns = b.t0_ns;
        }
        let t0 = live.t0_ns.unwrap_or(0);
        let span = live.config.window_s.max(1.0);
        let hist_cap = live.config.history_buckets;
        if !b.samples.is_empty() || !b.cycles.is_empty() {
            live.last_data = Some(std::time::Instant::now());
        }
        live.bytes += b.bytes;
        if let Some(log) = self.logs.first_mut() {
            let set = &mut log.signals;
            for (k, s) in &b.samples {
                if *k == SignalKind::Cycle {
                    continue;
                }
                let name = k.name();
                let i = match set.channels.iter().position(|c| c.name == name) {
                    Some(i) => i,
                    None => {
                        set.channels
                            .push(Channel::new(name, k.unit(), Vec::new(), Vec::new()));
                        live.history.push((*k, MinMaxHistory::new(hist_cap, 0.01)));
                        set.channels.len() - 1
                    }
                };
                let t: Vec<f64> = s.iter().map(|x| (x.0 - t0) as f64 * 1e-9).collect();
                let v: Vec<f64> = s.iter().map(|x| x.1).collect();
                let c = &mut set.channels[i];
                slide(&mut c.t_s, &mut c.values, &t, &v, span);
                c.blocks = std::sync::OnceLock::new();
                if let Some(h) = live.history.iter_mut().find(|h| h.0 == *k) {
                    h.1.add(&t, &v);
                }
                if let Some(&l) = t.last() {
                    live.latest_s = Some(live.latest_s.map_or(l, |x: f64| x.max(l)));
                }
            }
            for c in &b.cycles {
                set.cycles
                    .push(((c.cycle.t_start_ns - t0) as f64 * 1e-9, c.cycle.index));
            }
            if let Some(&(first, _)) = set.cycles.first()
                && let Some(c0) = set.channels.first().and_then(|c| c.t_s.first())
                && first < *c0
            {
                let cut = set.cycles.partition_point(|x| x.0 < *c0);
                set.cycles.drain(..cut);
            }
        }
        live.cycles += b.cycles.len() as u64;
        for c in b.cycles {
            live.recent_cycles.push_back(c);
        }
        while live.recent_cycles.len() > live.config.recent_cycles.max(1) {
            live.recent_cycles.pop_front();
        }
        // Images with their inspections.
        let keep = live.config.recent_images.max(1);
        for img in b.images {
            live.images += 1;
            let idx = self.images.len();
            let name = img.result.name.clone();
            self.images.push(ImageEntry {
                name: name.clone(),
                source: match (&img.path, &img.bytes) {
                    (Some(p), _) => ImageSource::File(p.clone()),
                    (None, Some(b)) => ImageSource::Bytes(b.clone()),
                    (None, None) => ImageSource::Bytes(Default::default()),
                },
                width: img.width,
                height: img.height,
                preview: img.preview,
                meta: img.result.meta.clone(),
                load_error: None,
            });
            let note = img
                .result
                .inspection
                .as_ref()
                .map(|i| format!("{} (live)", i.part_number))
                .unwrap_or_else(|| "none".into());
            self.set_inspection(Inspected {
                image: idx,
                result: img.result,
                recipe_note: note,
                wall_ms: 0.0,
                annotated: img.annotated,
            });
        }
        if self.images.len() > keep {
            let drop = self.images.len() - keep;
            self.images.drain(..drop);
            let old = std::mem::take(&mut self.inspections);
            self.inspections = old
                .into_iter()
                .filter(|(i, _)| *i >= drop)
                .map(|(i, mut r)| {
                    r.image = i - drop;
                    (i - drop, r)
                })
                .collect();
        }
        if let Some(y) = b.yields {
            let results = self
                .inspections
                .values()
                .map(|i| i.result.clone())
                .collect();
            self.yields = Some(YieldRun {
                report: (*y).clone(),
                results,
                cancelled: false,
                wall_ms: 0.0,
            });
        }
        for e in &b.events {
            match e {
                LiveEvent::Finding(_) => live.findings += 1,
                LiveEvent::Alarm(a) if a.raised => {
                    live.alarms_raised += 1;
                    live.last_alarm = Some(format!("{}: {}", a.rule, a.message));
                    live.announce.push(format!("{}: {}", a.rule, a.message));
                }
                _ => {}
            }
            if let Some(l) = describe(e) {
                live.line(l);
            }
        }
        live.active_alarms = b.active_alarms;
        for f in b.files {
            match live.files.iter_mut().find(|x| x.0 == f.path) {
                Some(x) => *x = (f.path, f.state, f.bytes, f.cycles),
                None => live.files.push((f.path, f.state, f.bytes, f.cycles)),
            }
        }
        // The files as the Session pane lists them.
        self.files.retain(|f| !f.detail.starts_with("live:"));
        for (p, st, bytes, cycles) in &live.files {
            self.files.push(FileEntry {
                path: p.clone(),
                kind: if p.ends_with(".mcap") {
                    FileKind::RigLog
                } else {
                    FileKind::Folder
                },
                status: match st {
                    FileState::Deleted | FileState::Missing => {
                        FileStatus::Warning(format!("{st:?}"))
                    }
                    _ => FileStatus::Loaded,
                },
                detail: format!(
                    "live: {st:?}, {cycles} cycles, {:.1} MB",
                    *bytes as f64 / 1e6
                ),
            });
        }
        self.live = Some(live);
    }
}
