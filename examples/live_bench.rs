//! The live mode's latency benchmark of issue 18 (BENCHMARKS.md, "Live
//! follow"): from a chunk flushed by the rig to the frame that shows it.
//!
//! ```sh
//! cargo run --release --example live_bench -- [SECONDS=60] [DIR]
//! cargo run --release --example live_bench -- shift HOURS SPINDLE_HZ SIGNAL_HZ IMAGES(0|1) [DIR [RATE=max]]
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
//!   backend instead of a terminal (`event_loop::drive_headless`).
//!
//! A chunk is on screen at the first frame drawn after the newest sample
//! it holds has reached the Signals pane; its latency is that frame's end
//! minus the flush. Prints the median, 90th percentile and maximum over
//! the chunks, and how many chunks were never shown.
//!
//! `shift`: the memory of a whole shift, compressed. The same follower and
//! loop, the rig (`pinsight rig-sim`, its own process as on a line)
//! writing at `RATE` (`max`: as fast as it can, which outruns the
//! inspection of one photograph per cycle on two cores: the photographs
//! then wait on disk; `10x`: a pace the follower keeps), a new file every 20 minutes
//! of log time (each deleted once the follower has finished it, and each
//! photograph once it has been inspected, as a line's archive job would:
//! only the disk is spared, the follower's work is the same); prints the
//! resident memory of the follower + TUI process (and of the rig's) at
//! every eighth of the shift and the growth from the first mark to the last;
//! and, read once a second, the median and maximum of each eighth and their
//! growth from the first eighth to the last. With `LIVE_BENCH_EXIT_HOT=1`
//! it exits without dropping anything, for a heap profiler's live set.

use pinsight::live::sim::{FlushMark, SimOptions};
use pinsight::live::{AlarmRules, LiveBatch};
use pinsight::panes::{PaneId, Session};
use pinsight::tui::app::App;
use pinsight::tui::event_loop::{QuitWhen, drive_headless};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

fn pct(v: &[f64], p: f64) -> f64 {
    let i = ((v.len() - 1) as f64 * p).round() as usize;
    v[i]
}

/// Resident memory of this process (kB), from /proc.
fn rss_kb() -> u64 {
    rss_kb_of("/proc/self/status")
}

/// `VmRSS` of a /proc status file (kB; 0 when unreadable).
fn rss_kb_of(status: &str) -> u64 {
    std::fs::read_to_string(status)
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// The folder of the run (DIR, or a temporary one), emptied.
fn run_dir(arg: Option<&String>, tmp: &mut Option<tempfile::TempDir>) -> anyhow::Result<PathBuf> {
    let dir = match arg {
        Some(d) => PathBuf::from(d),
        None => tmp.insert(tempfile::tempdir()?).path().to_path_buf(),
    };
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// The rig on its own thread; sets `finished` when it returns.
fn start_rig(
    opts: SimOptions,
    stop: Arc<AtomicBool>,
    finished: Arc<AtomicBool>,
) -> std::thread::JoinHandle<Result<pinsight::live::sim::SimReport, String>> {
    std::thread::spawn(move || {
        let r = pinsight::live::sim::run(&opts, &stop);
        finished.store(true, Ordering::SeqCst);
        r
    })
}

/// What `pinsight tui --follow PATHS` starts with, on the Signals pane.
fn follow(
    paths: &[PathBuf],
    stop: Arc<AtomicBool>,
) -> anyhow::Result<(App, Receiver<LiveBatch>, AlarmRules)> {
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
    let (rx, rules) = pinsight::tui::start_follow(&mut session, inputs, stop)?;
    let mut app = App::new(session, 120, 40);
    app.pane = PaneId::Signals;
    Ok((app, rx, rules))
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.first().map(String::as_str) == Some("shift") {
        return shift(&a[1..]);
    }
    let secs: f64 = a.first().and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let mut tmp = None;
    let dir = run_dir(a.get(1), &mut tmp)?;
    let log = dir.join("run.mcap");
    let images = dir.join("img");
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
    let stop = Arc::new(AtomicBool::new(false));
    let rig = start_rig(opts, stop.clone(), Arc::new(AtomicBool::new(false)));
    let (mut app, rx, rules) = follow(&[log, images], stop.clone())?;
    // Frames: when each ended and the newest sample (log ns) it showed.
    let mut frames: Vec<(Instant, Option<i64>)> = Vec::new();
    let started = Instant::now();
    let end = started + Duration::from_secs_f64(secs);
    drive_headless(
        &mut app,
        (120, 40),
        &mut QuitWhen(|| Instant::now() >= end),
        Some((&rx, &rules)),
        &mut |app: &App| {
            let shown = app
                .session
                .live
                .as_ref()
                .and_then(|l| Some(l.t0_ns? + (l.latest_s? * 1e9).round() as i64));
            frames.push((Instant::now(), shown));
        },
    )?;
    stop.store(true, Ordering::Relaxed);
    let report = rig
        .join()
        .map_err(|_| anyhow::anyhow!("the rig panicked"))?
        .map_err(|e| anyhow::anyhow!(e))?;
    let cycles = app.session.live.as_ref().map_or(0, |l| l.cycles);
    let shown_images = app.session.live.as_ref().map_or(0, |l| l.images);

    // Each flushed chunk against the first frame that shows its newest sample.
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

/// Removes the photographs `from..to` (named by `rig-sim`: `run-cycle-K.png`).
fn archive_images(images: &Path, from: &mut u64, to: u64) {
    while *from < to {
        let _ = std::fs::remove_file(images.join(format!("run-cycle-{:07}.png", *from)));
        *from += 1;
    }
}

fn shift(a: &[String]) -> anyhow::Result<()> {
    let hours: f64 = a.first().and_then(|s| s.parse().ok()).unwrap_or(8.0);
    let spindle_hz: f64 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(10_000.0);
    let signal_hz: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(20_000.0);
    let with_images = a.get(3).is_none_or(|s| s != "0");
    let rate = a.get(5).map_or("max", String::as_str);
    let mut tmp = None;
    let dir = run_dir(a.get(4), &mut tmp)?;
    let logs = dir.join("logs");
    let images = dir.join("img");
    std::fs::create_dir_all(&logs)?;
    std::fs::create_dir_all(&images)?;
    // The rig as on a line: its own process (`pinsight rig-sim`, beside
    // this example in target/release), so the RSS below is the TUI's alone.
    let exe = std::env::current_exe()?;
    let bin = exe
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join("pinsight"))
        .filter(|p| p.is_file())
        .ok_or_else(|| anyhow::anyhow!("build the binary first: cargo build --release"))?;
    let mut child = std::process::Command::new(bin)
        .args([
            "rig-sim", "--rpm", "1500", "--rate", rate, "--rotate", "20m",
        ])
        .arg("--out")
        .arg(logs.join("run.mcap"))
        .arg("--duration")
        .arg(format!("{}s", hours * 3600.0))
        .args(["--spindle-hz", &spindle_hz.to_string()])
        .args(["--force-hz", &signal_hz.to_string()])
        .args(["--displacement-hz", &signal_hz.to_string()])
        .args(if with_images {
            vec!["--images".to_string(), images.display().to_string()]
        } else {
            vec![]
        })
        .stdout(std::process::Stdio::piped())
        .spawn()?;
    let rig_pid = child.id();
    let stop = Arc::new(AtomicBool::new(false));
    let mut paths = vec![logs.clone()];
    if with_images {
        paths.push(images.clone());
    }
    let (mut app, rx, rules) = follow(&paths, stop.clone())?;
    let started = Instant::now();
    // (eighth of the shift, wall s, RSS kB, the rig's RSS kB, cycles, images)
    let mut marks: Vec<(u64, f64, u64, u64, u64, u64)> = Vec::new();
    // RSS (kB) once a second of wall time, by eighth of the shift: one
    // reading is a moment (a batch or a photograph in flight moves it by a
    // few MB), so each eighth is also summarised by its median and maximum.
    let mut samples: Vec<Vec<u64>> = vec![Vec::new(); 9];
    let mut last_sample = Instant::now();
    let mut deleted = std::collections::HashSet::new();
    let mut next_del = 0u64;
    // Ends three quiet seconds after the rig finished.
    let mut since: Option<Instant> = None;
    let mut rig_status = None;
    let mut quiet = QuitWhen(|| {
        if rig_status.is_none() {
            rig_status = child.try_wait().ok().flatten();
        }
        rig_status.is_some()
            && since.get_or_insert_with(Instant::now).elapsed() > Duration::from_secs(3)
    });
    drive_headless(
        &mut app,
        (120, 40),
        &mut quiet,
        Some((&rx, &rules)),
        &mut |app: &App| {
            let Some(l) = app.session.live.as_ref() else {
                return;
            };
            // A mark at every eighth of the shift (every hour of 8 h).
            let step = hours * 3600.0 / 8.0;
            let k = (l.latest_s.unwrap_or(0.0) / step).floor() as u64;
            if last_sample.elapsed() >= Duration::from_secs(1) {
                last_sample = Instant::now();
                samples[(k as usize).min(8)].push(rss_kb());
            }
            if k > marks.last().map_or(0, |m| m.0) {
                marks.push((
                    k,
                    started.elapsed().as_secs_f64(),
                    rss_kb(),
                    rss_kb_of(&format!("/proc/{rig_pid}/status")),
                    l.cycles,
                    l.images,
                ));
                if let Some(m) = marks.last() {
                    eprintln!("mark {m:?}");
                    // The eighth just finished: median and maximum of its readings.
                    let prev = &samples[(k as usize - 1).min(8)];
                    let mut v = prev.clone();
                    v.sort_unstable();
                    if let (Some(mid), Some(max)) = (v.get(v.len() / 2), v.last()) {
                        eprintln!(
                            "eighth {}: {} readings, median {:.1} MB, max {:.1} MB",
                            k - 1,
                            v.len(),
                            *mid as f64 / 1024.0,
                            *max as f64 / 1024.0
                        );
                    }
                }
            }
            // The archive job: finished logs and inspected images go
            // (photographs are inspected in order: 100 cycles behind).
            for (path, state, _, _) in &l.files {
                use pinsight::live::events::FileState;
                if matches!(state, FileState::Finished | FileState::Abandoned)
                    && deleted.insert(path.clone())
                {
                    let _ = std::fs::remove_file(path);
                }
            }
            archive_images(&images, &mut next_del, l.images.saturating_sub(100));
        },
    )?;
    // LIVE_BENCH_EXIT_HOT=1: the follower is left running and the process
    // exits without dropping anything, so that a heap profiler
    // (`heaptrack`) lists the whole live set of the end of the shift, by
    // call stack, as "leaked".
    let hot = std::env::var_os("LIVE_BENCH_EXIT_HOT").is_some();
    if !hot {
        stop.store(true, Ordering::Relaxed);
    }
    let out = child.wait_with_output()?;
    let l = app.session.live.as_ref();
    println!(
        "shift of {hours} h at 1500 rpm, rig at {rate}, spindle {spindle_hz} Hz, force and displacement \
         {signal_hz} Hz, images {}: {:.0} s wall; {} {}; followed {} cycles, {} images; \
         RSS end {} kB",
        if with_images { "one per cycle" } else { "none" },
        started.elapsed().as_secs_f64(),
        out.status,
        String::from_utf8_lossy(&out.stdout).trim(),
        l.map_or(0, |l| l.cycles),
        l.map_or(0, |l| l.images),
        rss_kb()
    );
    println!(
        "| log time (h) | wall s | RSS MB (follower + TUI) | RSS MB (rig-sim) | cycles | images |"
    );
    for (k, w, r, rr, c, i) in &marks {
        println!(
            "| {:.2} | {w:.0} | {:.1} | {:.1} | {c} | {i} |",
            *k as f64 * hours / 8.0,
            *r as f64 / 1024.0,
            *rr as f64 / 1024.0
        );
    }
    // Per eighth of the shift: the readings once a second of wall time.
    println!("| log time (h) | RSS readings | median MB | max MB |");
    let mut summary: Vec<(usize, f64, f64)> = Vec::new();
    for (k, v) in samples.iter_mut().enumerate() {
        if v.is_empty() {
            continue;
        }
        v.sort_unstable();
        let med = v[v.len() / 2] as f64 / 1024.0;
        let max = v[v.len() - 1] as f64 / 1024.0;
        println!(
            "| {:.2}–{:.2} | {} | {med:.1} | {max:.1} |",
            k as f64 * hours / 8.0,
            (k + 1) as f64 * hours / 8.0,
            v.len()
        );
        summary.push((k, med, max));
    }
    // The first hour (of 8) against the last.
    if let (Some(a), Some(b)) = (summary.first(), summary.iter().rev().find(|x| x.0 <= 7)) {
        println!(
            "RSS growth from the eighth {:.2}–{:.2} h to {:.2}–{:.2} h: median {:+.1} %, max {:+.1} %",
            a.0 as f64 * hours / 8.0,
            (a.0 + 1) as f64 * hours / 8.0,
            b.0 as f64 * hours / 8.0,
            (b.0 + 1) as f64 * hours / 8.0,
            100.0 * (b.1 / a.1 - 1.0),
            100.0 * (b.2 / a.2 - 1.0)
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
    if hot {
        use std::io::Write;
        let _ = std::io::stdout().flush();
        std::process::exit(0);
    }
    Ok(())
}
