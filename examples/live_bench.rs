//! The live mode's latency benchmark of issue 18 (BENCHMARKS.md, "Live
//! follow"): from a chunk flushed by the rig to the frame that shows it.
//!
//! ```sh
//! cargo run --release --example live_bench -- [SECONDS=60] [DIR]
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

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
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
