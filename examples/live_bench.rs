//! The live mode's latency benchmark of issue 18 (BENCHMARKS.md, "Live
//! follow"): from a chunk flushed by the rig to the frame that shows it.
//!
//! ```sh
//! cargo run --release --example live_bench -- [SECONDS=60] [DIR]
//! cargo run --release --example live_bench -- shift HOURS SPINDLE_HZ SIGNAL_HZ IMAGES(0|1) [DIR]
//! ```
//!
//! In one process, as `pinsight rig-sim` and `pinsight tui --follow` would
//! run on a line:
//! - the simulated rig (`live::sim::run`, the code of `rig-sim`) writes the
//!   issue's line in real time: 1500 rpm, 20 kHz force and displacement,
//!   10 kHz spindle, one photograph per cycle into a folder, a chunk every
//!   0.25 s; it tells the benchmark the newest sample of every chunk it
//!   flushes and when the flush returned;
//! - the follower thread of the TUI (`tui::spawn_follower`) and the TUI's
//!   own loop (`tui::event_loop::drive`, the very loop of `pinsight tui`)
//!   with no key pressed, drawing the Signals pane into a 120×40 test
//!   backend instead of a terminal.
//!
//! A chunk is on screen at the first frame drawn after the newest sample
//! it holds has reached the Signals pane; its latency is that frame's end
//! minus the flush. Prints the median, 90th percentile and maximum over
//! the chunks, and how many chunks were never shown.
//!
//! `shift`: the memory of a whole shift, compressed. The same rig, follower
//! and loop, the rig writing as fast as it can, a new file every 20 minutes
//! of log time (each deleted once the follower has finished it, and each
//! photograph once it has been inspected, as a line's archive job would:
//! only the disk is spared, the follower's work is the same); prints the
//! resident memory of the process (rig + follower + TUI) at every hour of
//! log time and the growth from hour 1 to the last.

use crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
use pinsight::live::sim::{FlushMark, SimOptions};
use pinsight::panes::{PaneId, Session};
use pinsight::tui::app::App;
use pinsight::tui::event_loop::{Context, Events, drive};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// No key until the deadline, then Ctrl-C. Waits as a terminal does: the
/// whole timeout when nothing is typed.
struct Quiet {
    until: Instant,
}

impl Events for Quiet {
    fn poll(&mut self, timeout: Duration) -> std::io::Result<bool> {
        let now = Instant::now();
        if now >= self.until {
            return Ok(true);
        }
        std::thread::sleep(timeout.min(self.until - now));
        Ok(Instant::now() >= self.until)
    }
    fn read(&mut self) -> std::io::Result<Event> {
        Ok(Event::Key(KeyEvent::new(
            KeyCode::Char('c'),
            KeyModifiers::CONTROL,
        )))
    }
}

fn pct(v: &[f64], p: f64) -> f64 {
    let i = ((v.len() - 1) as f64 * p).round() as usize;
    v[i]
}

/// Resident memory of this process (kB), from /proc.
fn rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.first().map(String::as_str) == Some("shift") {
        return shift(&a[1..]);
    }
    let secs: f64 = a.first().and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let tmp;
    let dir = match a.get(1) {
        Some(d) => std::path::PathBuf::from(d),
        None => {
            tmp = tempfile::tempdir()?;
            tmp.path().to_path_buf()
        }
    };
    std::fs::create_dir_all(&dir)?;
    let log = dir.join("run.mcap");
    let images = dir.join("img");
    let _ = std::fs::remove_file(&log);
    let _ = std::fs::remove_dir_all(&images);

    let (tx, flushes) = std::sync::mpsc::channel::<FlushMark>();
    let opts = SimOptions {
        out: log.clone(),
        rpm: 1500.0,
        rate: 1.0,
        // The rig runs a little longer than the TUI watches.
        duration_s: secs + 5.0,
        images: Some(images.clone()),
        spindle_hz: 10_000.0,
        force_hz: 20_000.0,
        displacement_hz: 20_000.0,
        on_flush: Some(tx),
        ..SimOptions::default()
    };
    let stop_rig = Arc::new(AtomicBool::new(false));
    let rig = {
        let stop = stop_rig.clone();
        std::thread::spawn(move || pinsight::live::sim::run(&opts, &stop))
    };

    // What `pinsight tui --follow run.mcap img/` starts with.
    let inputs = pinsight::cli::watch::inputs(
        &[log.clone(), images.clone()],
        &[],
        None,
        0,
        Default::default(),
        None,
        &pinsight::cli::common::LogReadArgs {
            channels: None,
            meta: Vec::new(),
        },
    )?;
    let mut session = Session::new("live");
    session.start_live(
        inputs.config.clone(),
        inputs
            .paths
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    );
    let rules = inputs.alarms.clone();
    let stop_follow = Arc::new(AtomicBool::new(false));
    let rx = pinsight::tui::spawn_follower(inputs, stop_follow.clone())?;
    let mut app = App::new(session, 120, 40);
    app.pane = PaneId::Signals;
    let mut terminal = ratatui::Terminal::new(ratatui::backend::TestBackend::new(120, 40))?;
    let worker = pinsight::tui::worker::Worker::default();
    let input = pinsight::tui::input::Input::new(Default::default());
    let theme = pinsight::tui::theme::Theme::ansi16();
    let mut img = pinsight::tui::draw::ImageCache::off();
    // Frames: when each ended and the newest sample (log ns) it showed.
    let mut frames: Vec<(Instant, Option<i64>)> = Vec::new();
    let started = Instant::now();
    drive(
        &mut terminal,
        &mut app,
        Context {
            worker: &worker,
            theme: &theme,
            img: &mut img,
            input: &input,
            events: &mut Quiet {
                until: started + Duration::from_secs_f64(secs),
            },
            live: Some((&rx, &rules)),
            on_frame: &mut |app: &App| {
                let shown = app
                    .session
                    .live
                    .as_ref()
                    .and_then(|l| Some(l.t0_ns? + (l.latest_s? * 1e9).round() as i64));
                frames.push((Instant::now(), shown));
            },
        },
    )?;
    stop_follow.store(true, std::sync::atomic::Ordering::Relaxed);
    stop_rig.store(true, std::sync::atomic::Ordering::Relaxed);
    let report = rig
        .join()
        .map_err(|_| anyhow::anyhow!("the rig panicked"))?;
    let report = report.map_err(|e| anyhow::anyhow!(e))?;
    let cycles = app.session.live.as_ref().map_or(0, |l| l.cycles);
    let shown_images = app.session.live.as_ref().map_or(0, |l| l.images);

    // Each flushed chunk against the first frame that shows its newest sample.
    let end = started + Duration::from_secs_f64(secs);
    let mut lat = Vec::new();
    let mut unseen = 0usize;
    for m in flushes.try_iter() {
        // Chunks flushed in the last second may be on their way at the end.
        if m.at > end - Duration::from_secs(1) {
            continue;
        }
        // 1 µs of rounding in the pane's seconds.
        let want = m.sample_ns as i64 - 1_000;
        match frames
            .iter()
            .find(|(at, shown)| *at >= m.at && shown.is_some_and(|s| s >= want))
        {
            Some((at, _)) => lat.push((*at - m.at).as_secs_f64() * 1e3),
            None => unseen += 1,
        }
    }
    lat.sort_by(f64::total_cmp);
    if lat.is_empty() {
        anyhow::bail!("no chunk was shown ({unseen} flushed)");
    }
    println!(
        "live latency over {secs} s: {} chunks shown, {unseen} not shown; flush -> frame: \
         median {:.0} ms, p90 {:.0} ms, max {:.0} ms; {} frames; {cycles} cycles and \
         {shown_images} images followed; rig wrote {} cycles, {} images, {} messages",
        lat.len(),
        pct(&lat, 0.5),
        pct(&lat, 0.9),
        lat[lat.len() - 1],
        frames.len(),
        report.cycles,
        report.images,
        report.messages
    );
    Ok(())
}

/// The tui's follow session on `paths`: the app, the follower's receiver,
/// the alarm rules and the follower's stop flag.
type Followed = (
    App,
    std::sync::mpsc::Receiver<pinsight::live::LiveBatch>,
    pinsight::live::AlarmRules,
    Arc<AtomicBool>,
);

fn follow(paths: &[std::path::PathBuf]) -> anyhow::Result<Followed> {
    let inputs = pinsight::cli::watch::inputs(
        paths,
        &[],
        None,
        0,
        Default::default(),
        None,
        &pinsight::cli::common::LogReadArgs {
            channels: None,
            meta: Vec::new(),
        },
    )?;
    let mut session = Session::new("live");
    session.start_live(
        inputs.config.clone(),
        inputs
            .paths
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    );
    let rules = inputs.alarms.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let rx = pinsight::tui::spawn_follower(inputs, stop.clone())?;
    let mut app = App::new(session, 120, 40);
    app.pane = PaneId::Signals;
    Ok((app, rx, rules, stop))
}

fn shift(a: &[String]) -> anyhow::Result<()> {
    let hours: f64 = a.first().and_then(|s| s.parse().ok()).unwrap_or(8.0);
    let spindle_hz: f64 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(10_000.0);
    let signal_hz: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(20_000.0);
    let with_images = a.get(3).is_none_or(|s| s != "0");
    let tmp;
    let dir = match a.get(4) {
        Some(d) => std::path::PathBuf::from(d),
        None => {
            tmp = tempfile::tempdir()?;
            tmp.path().to_path_buf()
        }
    };
    let _ = std::fs::remove_dir_all(&dir);
    let logs = dir.join("logs");
    let images = dir.join("img");
    std::fs::create_dir_all(&logs)?;
    std::fs::create_dir_all(&images)?;
    let opts = SimOptions {
        out: logs.join("run.mcap"),
        rpm: 1500.0,
        rate: f64::INFINITY,
        duration_s: hours * 3600.0,
        images: with_images.then(|| images.clone()),
        spindle_hz,
        force_hz: signal_hz,
        displacement_hz: signal_hz,
        rotate_s: Some(1200.0),
        ..SimOptions::default()
    };
    let stop_rig = Arc::new(AtomicBool::new(false));
    let rig_finished = Arc::new(AtomicBool::new(false));
    let rig = {
        let stop = stop_rig.clone();
        let finished = rig_finished.clone();
        std::thread::spawn(move || {
            let r = pinsight::live::sim::run(&opts, &stop);
            finished.store(true, std::sync::atomic::Ordering::SeqCst);
            r
        })
    };
    let mut paths = vec![logs.clone()];
    if with_images {
        paths.push(images.clone());
    }
    let (mut app, rx, rules, stop_follow) = follow(&paths)?;
    let mut terminal = ratatui::Terminal::new(ratatui::backend::TestBackend::new(120, 40))?;
    let worker = pinsight::tui::worker::Worker::default();
    let input = pinsight::tui::input::Input::new(Default::default());
    let theme = pinsight::tui::theme::Theme::ansi16();
    let mut img = pinsight::tui::draw::ImageCache::off();
    let started = Instant::now();
    // (eighth of the shift, wall s, RSS kB, cycles, images)
    let mut marks: Vec<(u64, f64, u64, u64, u64)> = Vec::new();
    let mut deleted = std::collections::HashSet::new();
    let mut next_del = 0u64;
    /// No key; Ctrl-C three quiet seconds after the rig finished.
    struct UntilRigDone {
        finished: Arc<AtomicBool>,
        since: Option<Instant>,
    }
    impl Events for UntilRigDone {
        fn poll(&mut self, timeout: Duration) -> std::io::Result<bool> {
            std::thread::sleep(timeout);
            if self.finished.load(std::sync::atomic::Ordering::SeqCst) {
                let since = *self.since.get_or_insert_with(Instant::now);
                return Ok(since.elapsed() > Duration::from_secs(3));
            }
            Ok(false)
        }
        fn read(&mut self) -> std::io::Result<Event> {
            Ok(Event::Key(KeyEvent::new(
                KeyCode::Char('c'),
                KeyModifiers::CONTROL,
            )))
        }
    }
    drive(
        &mut terminal,
        &mut app,
        Context {
            worker: &worker,
            theme: &theme,
            img: &mut img,
            input: &input,
            events: &mut UntilRigDone {
                finished: rig_finished.clone(),
                since: None,
            },
            live: Some((&rx, &rules)),
            on_frame: &mut |app: &App| {
                let Some(l) = app.session.live.as_ref() else {
                    return;
                };
                // A mark at every eighth of the shift (every hour of 8 h).
                let step = hours * 3600.0 / 8.0;
                let k = (l.latest_s.unwrap_or(0.0) / step).floor() as u64;
                if k > marks.last().map_or(0, |m| m.0) {
                    marks.push((
                        k,
                        started.elapsed().as_secs_f64(),
                        rss_kb(),
                        l.cycles,
                        l.images,
                    ));
                    if let Some(m) = marks.last() {
                        eprintln!("mark {m:?}");
                    }
                }
                // The archive job: finished logs and inspected images go.
                for (path, state, _, _) in &l.files {
                    use pinsight::live::events::FileState;
                    if matches!(state, FileState::Finished | FileState::Abandoned)
                        && deleted.insert(path.clone())
                    {
                        let _ = std::fs::remove_file(path);
                    }
                }
                // Photographs are inspected in order: those 100 cycles
                // behind the count inspected are done with.
                while next_del + 100 < l.images {
                    let _ =
                        std::fs::remove_file(images.join(format!("run-cycle-{next_del:07}.png")));
                    next_del += 1;
                }
            },
        },
    )?;
    stop_follow.store(true, std::sync::atomic::Ordering::Relaxed);
    stop_rig.store(true, std::sync::atomic::Ordering::Relaxed);
    let report = rig
        .join()
        .map_err(|_| anyhow::anyhow!("the rig panicked"))?;
    let report = report.map_err(|e| anyhow::anyhow!(e))?;
    let l = app.session.live.as_ref();
    println!(
        "shift of {hours} h at 1500 rpm, spindle {spindle_hz} Hz, force and displacement \
         {signal_hz} Hz, images {}: {:.0} s wall; rig wrote {} cycles, {} images, {} \
         messages in {} files; followed {} cycles, {} images; RSS end {} kB",
        if with_images { "one per cycle" } else { "none" },
        started.elapsed().as_secs_f64(),
        report.cycles,
        report.images,
        report.messages,
        report.files.len(),
        l.map_or(0, |l| l.cycles),
        l.map_or(0, |l| l.images),
        rss_kb()
    );
    println!("| log time (h) | wall s | RSS MB | cycles | images |");
    for (k, w, r, c, i) in &marks {
        println!(
            "| {:.2} | {w:.0} | {:.1} | {c} | {i} |",
            *k as f64 * hours / 8.0,
            *r as f64 / 1024.0
        );
    }
    if let (Some(first), Some(last)) = (marks.first(), marks.last()) {
        println!(
            "RSS growth from {:.2} h to {:.2} h of log: {:+.1} %",
            first.0 as f64 * hours / 8.0,
            last.0 as f64 * hours / 8.0,
            100.0 * (last.2 as f64 / first.2 as f64 - 1.0)
        );
    }
    Ok(())
}
