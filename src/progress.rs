//! Progress and cancellation for long work.
//!
//! Library code (simulation sweeps, batch vision, log loading) takes a
//! `&Progress` and advances it; it checks [`Progress::is_cancelled`] at
//! convenient points and stops early with whatever it has. The front ends
//! read the same counters: the CLI draws an `indicatif` bar when stderr is a
//! terminal ([`ProgressBarGuard`]), the TUI draws a gauge. Nothing here knows
//! about a terminal except the guard.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Shared, thread-safe progress counter with a cancel flag.
#[derive(Debug, Default)]
pub struct Progress {
    done: AtomicU64,
    total: AtomicU64,
    /// Shared so a signal handler can set it ([`Progress::cancel_on_ctrl_c`]).
    cancelled: Arc<AtomicBool>,
    message: Mutex<String>,
}

impl Progress {
    /// A new counter with `total` units of work.
    pub fn new(total: u64) -> Arc<Self> {
        let p = Self::default();
        p.total.store(total, Ordering::Relaxed);
        Arc::new(p)
    }

    /// A counter nobody watches (for tests and library callers that don't care).
    pub fn hidden() -> Arc<Self> {
        Self::new(0)
    }

    /// A counter of its own for a part of this work that shares its cancel
    /// flag: Ctrl-C on a batch also stops the study one of its steps runs.
    pub fn child(&self) -> Arc<Self> {
        Arc::new(Self {
            cancelled: self.cancelled.clone(),
            ..Self::default()
        })
    }

    pub fn set_total(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
    }

    pub fn inc(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    pub fn set_done(&self, n: u64) {
        self.done.store(n, Ordering::Relaxed);
    }

    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    pub fn total(&self) -> u64 {
        self.total.load(Ordering::Relaxed)
    }

    /// Fraction done in [0, 1] (0 when the total is unknown).
    pub fn fraction(&self) -> f64 {
        let t = self.total();
        if t == 0 {
            0.0
        } else {
            (self.done() as f64 / t as f64).clamp(0.0, 1.0)
        }
    }

    pub fn set_message(&self, msg: impl Into<String>) {
        if let Ok(mut m) = self.message.lock() {
            *m = msg.into();
        }
    }

    pub fn message(&self) -> String {
        self.message.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// Ask the work to stop at its next check.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }

    /// The first Ctrl-C (SIGINT) cancels the work (it stops at its next
    /// check, writes nothing half-done and says what it wrote); a second
    /// one exits at once with status 130. Unix only; a no-op elsewhere.
    pub fn cancel_on_ctrl_c(&self) -> std::io::Result<()> {
        #[cfg(unix)]
        {
            use signal_hook::consts::SIGINT;
            signal_hook::flag::register_conditional_shutdown(SIGINT, 130, self.cancelled.clone())?;
            signal_hook::flag::register(SIGINT, self.cancelled.clone())?;
        }
        Ok(())
    }
}

/// Sets `stop` on Ctrl-C (SIGINT) or SIGTERM, for the long-running
/// commands that end cleanly at their next check (`rig-sim` writes its last
/// chunk and footer, `watch` its summary); a second Ctrl-C exits at once
/// with status 130. Unix only; a no-op elsewhere.
pub fn stop_on_signals(stop: &Arc<AtomicBool>) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        signal_hook::flag::register_conditional_shutdown(SIGINT, 130, stop.clone())?;
        signal_hook::flag::register(SIGINT, stop.clone())?;
        signal_hook::flag::register(SIGTERM, stop.clone())?;
    }
    #[cfg(not(unix))]
    let _ = stop;
    Ok(())
}

/// Draws an `indicatif` bar for a [`Progress`] on stderr while alive, only
/// when stderr is a terminal (batch runs in CI stay quiet).
pub struct ProgressBarGuard {
    stop: Arc<AtomicBool>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl ProgressBarGuard {
    pub fn start(progress: Arc<Progress>, label: &str) -> Self {
        use std::io::IsTerminal;
        let stop = Arc::new(AtomicBool::new(false));
        if !std::io::stderr().is_terminal() {
            return Self { stop, handle: None };
        }
        let label = label.to_string();
        let stop2 = stop.clone();
        let handle = std::thread::spawn(move || {
            let bar = indicatif::ProgressBar::new(progress.total().max(1));
            let style = indicatif::ProgressStyle::with_template(
                "{prefix} [{bar:40}] {pos}/{len} ({eta}) {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> ");
            bar.set_style(style);
            bar.set_prefix(label);
            loop {
                bar.set_length(progress.total().max(1));
                bar.set_position(progress.done());
                bar.set_message(progress.message());
                if stop2.load(Ordering::Relaxed) {
                    break;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
            bar.finish_and_clear();
        });
        Self {
            stop,
            handle: Some(handle),
        }
    }
}

impl Drop for ProgressBarGuard {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fraction_and_cancel() {
        let p = Progress::new(4);
        assert_eq!(p.fraction(), 0.0);
        p.inc(1);
        p.inc(2);
        assert!((p.fraction() - 0.75).abs() < 1e-12);
        assert!(!p.is_cancelled());
        let c = p.child();
        p.cancel();
        assert!(p.is_cancelled());
        assert!(c.is_cancelled(), "a child shares the cancel flag");
        assert_eq!(Progress::hidden().fraction(), 0.0);
    }
}
