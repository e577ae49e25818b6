//! Speed targets of the TUI (issue 5), as criterion benchmarks:
//! - first frame on the demo: building the demo session and the app,
//!   computing the Session pane's view and drawing the screen at 120×40
//!   (target ≤ 200 ms; the model runs on the worker, not before the frame);
//! - one frame of the Signals pane with 10⁶-sample channels at 200×60: the
//!   view (min/max decimation per column) plus the drawing (target ≤ 10 ms);
//!   with one channel and with four, whole log and zoomed in.
//!
//! Run: `cargo bench --bench tui`. Frames are drawn into ratatui's
//! TestBackend (the terminal's own write is a diff of changed cells).

use criterion::{Criterion, criterion_group, criterion_main};
use pinsight::panes::session::{Channel, LogEntry, SignalSet};
use pinsight::panes::{PaneId, PaneState, Session};
use pinsight::tui::app::App;
use pinsight::tui::draw::{Chrome, ImageCache};
use pinsight::tui::theme::Theme;
use pinsight::tui::{render_app, render_view};
use std::hint::black_box;
use std::time::Duration;

fn first_frame(c: &mut Criterion) {
    c.bench_function("first_frame_demo_120x40", |b| {
        b.iter(|| {
            let app = App::new(Session::demo(), 120, 40);
            let mut img = ImageCache::off();
            black_box(render_app(&app, 120, 40, &Theme::ansi16(), &mut img))
        })
    });
}

/// A log of `channels` channels with `n` samples each at 20 kHz: a noisy
/// stroke-like wave with a spike now and then.
fn big_log(channels: usize, n: usize) -> Session {
    let dt = 5e-5;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
    let mut chans = Vec::new();
    for k in 0..channels {
        let values: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let w = (2.0 * std::f64::consts::PI * 20.0 * x + k as f64).cos();
                let noise = ((i * 7919 + k * 104729) % 1000) as f64 * 1e-4;
                let spike = if i % 99_991 == 0 { 5.0 } else { 0.0 };
                8.0 * (1.0 - w) + noise + spike
            })
            .collect();
        chans.push(Channel::new(format!("ch{k}"), "mm", t.clone(), values));
    }
    let cycles = (0..(n as f64 * dt * 20.0) as u64)
        .map(|k| (k as f64 / 20.0, k))
        .collect();
    let mut s = Session::new("bench");
    s.logs.push(LogEntry {
        path: "synthetic.mcap".into(),
        signals: SignalSet {
            source: "synthetic".into(),
            channels: chans,
            cycles,
            meta: Vec::new(),
        },
        rig: None,
    });
    s
}

fn signals_frame(c: &mut Criterion) {
    let mut g = c.benchmark_group("signals_frame_200x60");
    g.measurement_time(Duration::from_secs(5));
    for channels in [1usize, 4] {
        let s = big_log(channels, 1_000_000);
        for (label, window) in [("whole", None), ("zoom_1s", Some([20.0, 21.0]))] {
            let mut ui = PaneState::new(200, 60);
            ui.signals.window = window;
            g.bench_function(format!("{channels}x1e6_{label}"), |b| {
                b.iter(|| {
                    let view = pinsight::panes::view(PaneId::Signals, &s, &ui);
                    let chrome = Chrome::new(PaneId::Signals, "bench");
                    let mut img = ImageCache::off();
                    black_box(render_view(
                        &chrome,
                        &view,
                        200,
                        60,
                        &Theme::ansi16(),
                        &mut img,
                    ))
                })
            });
        }
    }
    g.finish();
}

// No criterion plots: its plotters backend looks for system fonts (pitfalls.md).
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = first_frame, signals_frame
}
criterion_main!(benches);
