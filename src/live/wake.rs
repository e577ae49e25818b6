//! When to poll: file-system events through `notify` and its debouncer
//! (a poll as soon as data is written), with a fixed interval as the
//! safety net, or the interval alone (`--poll 2s`: network shares, where
//! events do not arrive).

use notify::{RecommendedWatcher, RecursiveMode};
use notify_debouncer_mini::{DebounceEventResult, Debouncer, new_debouncer};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

/// What woke the follower.
#[derive(Debug, Default)]
pub struct Wakeup {
    /// Paths named by file-system events (None: list everything: the
    /// interval's poll, or events were lost).
    pub changed: Option<Vec<PathBuf>>,
}

/// The follower's alarm clock.
pub struct Wake {
    rx: Option<Receiver<DebounceEventResult>>,
    debouncer: Option<Debouncer<RecommendedWatcher>>,
    poll: Duration,
    last_full: Instant,
    unwatched: Vec<(PathBuf, bool)>,
    /// Why events are not used, if they are not.
    pub note: Option<String>,
}

impl Wake {
    /// Watches `paths` (folder, recursive) with events when `notify`, and
    /// polls at least every `poll_s` seconds.
    pub fn new(paths: &[(PathBuf, bool)], notify: bool, poll_s: f64, debounce_ms: u64) -> Self {
        let mut w = Wake {
            rx: None,
            debouncer: None,
            poll: Duration::from_secs_f64(poll_s.clamp(0.01, 3600.0)),
            last_full: Instant::now(),
            unwatched: paths.to_vec(),
            note: None,
        };
        if notify {
            let (tx, rx) = channel();
            match new_debouncer(Duration::from_millis(debounce_ms.max(1)), tx) {
                Ok(d) => {
                    w.debouncer = Some(d);
                    w.rx = Some(rx);
                    w.watch_missing();
                }
                Err(e) => w.note = Some(format!("file-system events unavailable ({e}); polling")),
            }
        } else {
            w.note = Some(format!("polling every {:.2} s", poll_s));
        }
        w
    }

    /// (Re-)watches the folders not watched yet (one that did not exist).
    fn watch_missing(&mut self) {
        let Some(d) = self.debouncer.as_mut() else {
            return;
        };
        self.unwatched.retain(|(p, rec)| {
            let mode = if *rec {
                RecursiveMode::Recursive
            } else {
                RecursiveMode::NonRecursive
            };
            d.watcher().watch(p, mode).is_err()
        });
    }

    /// Waits for an event or the interval.
    pub fn wait(&mut self) -> Wakeup {
        self.wait_up_to(None)
    }

    /// The wake-up of a follower with a backlog: does not wait; the events
    /// already there (none: `Some(empty)`), or the interval's full listing
    /// when it is due.
    pub fn take(&mut self) -> Wakeup {
        self.wait_up_to(Some(Duration::ZERO))
    }

    /// After a poll: [`Self::take`] when the follower is `behind`, else
    /// [`Self::wait`].
    pub fn next(&mut self, behind: bool) -> Wakeup {
        if behind { self.take() } else { self.wait() }
    }

    fn wait_up_to(&mut self, most: Option<Duration>) -> Wakeup {
        let Some(rx) = &self.rx else {
            // Polling only: a backlog is read on at once (the follower
            // lists its folders in full every 30 s whatever it is told).
            if most.is_some() {
                return Wakeup {
                    changed: Some(Vec::new()),
                };
            }
            std::thread::sleep(self.poll);
            return Wakeup { changed: None };
        };
        let left = self.poll.saturating_sub(self.last_full.elapsed());
        let wait = most.map_or(left, |m| m.min(left));
        match rx.recv_timeout(wait) {
            Ok(Ok(events)) => {
                let mut paths: Vec<PathBuf> = events.into_iter().map(|e| e.path).collect();
                while let Ok(more) = rx.try_recv() {
                    match more {
                        Ok(ev) => paths.extend(ev.into_iter().map(|e| e.path)),
                        Err(_) => return self.full(),
                    }
                }
                paths.sort();
                paths.dedup();
                Wakeup {
                    changed: Some(paths),
                }
            }
            Err(RecvTimeoutError::Timeout) if wait < left => Wakeup {
                changed: Some(Vec::new()),
            },
            Ok(Err(_)) | Err(RecvTimeoutError::Timeout) => self.full(),
            Err(RecvTimeoutError::Disconnected) => {
                self.rx = None;
                self.full()
            }
        }
    }

    fn full(&mut self) -> Wakeup {
        self.last_full = Instant::now();
        if !self.unwatched.is_empty() {
            self.watch_missing();
        }
        Wakeup { changed: None }
    }
}
