//! The TUI's loop: draw when something changed, then wait for a key (or
//! the next tick), the worker's results and the live follower's batches.
//! The terminal's events come through [`Events`], so the very same loop
//! runs on a test backend with scripted keys (the live mode's latency
//! benchmark, `examples/live_bench.rs`, and the tests).

use super::app::{App, Msg};
use super::draw::{ImageCache, draw_screen};
use super::input::Input;
use super::theme::Theme;
use super::worker::Worker;
use crossterm::event::Event;
use ratatui::Terminal;
use ratatui::backend::Backend;
use std::io::Write;
use std::time::Duration;

/// Where the loop's key, mouse, paste and resize events come from.
pub trait Events {
    /// True when an event is ready within `timeout`.
    fn poll(&mut self, timeout: Duration) -> std::io::Result<bool>;
    fn read(&mut self) -> std::io::Result<Event>;
}

/// The terminal's events (crossterm).
pub struct TerminalEvents;

impl Events for TerminalEvents {
    fn poll(&mut self, timeout: Duration) -> std::io::Result<bool> {
        crossterm::event::poll(timeout)
    }
    fn read(&mut self) -> std::io::Result<Event> {
        crossterm::event::read()
    }
}

/// Scripted events for a loop with no one at the keyboard (benchmarks,
/// tests): no key until the predicate holds, then Ctrl-C. Waits the whole
/// timeout, as a terminal does when nothing is typed.
pub struct QuitWhen<F: FnMut() -> bool>(pub F);

impl<F: FnMut() -> bool> Events for QuitWhen<F> {
    fn poll(&mut self, timeout: Duration) -> std::io::Result<bool> {
        if (self.0)() {
            return Ok(true);
        }
        std::thread::sleep(timeout);
        Ok((self.0)())
    }
    fn read(&mut self) -> std::io::Result<Event> {
        Ok(Event::Key(crossterm::event::KeyEvent::new(
            crossterm::event::KeyCode::Char('c'),
            crossterm::event::KeyModifiers::CONTROL,
        )))
    }
}

/// The loop on a test backend of `width` × `height` (no colour, no
/// images, the default keys), as benchmarks and tests run it: returns the
/// last frame.
pub fn drive_headless(
    app: &mut App,
    (width, height): (u16, u16),
    events: &mut dyn Events,
    live: Option<(
        &std::sync::mpsc::Receiver<crate::live::LiveBatch>,
        &crate::live::AlarmRules,
    )>,
    on_frame: &mut dyn FnMut(&App),
) -> anyhow::Result<ratatui::buffer::Buffer> {
    let mut terminal = Terminal::new(ratatui::backend::TestBackend::new(width, height))?;
    drive(
        &mut terminal,
        app,
        Context {
            worker: &Worker::default(),
            theme: &Theme::plain(),
            img: &mut ImageCache::off(),
            input: &Input::new(Default::default()),
            events,
            live,
            on_frame,
        },
    )?;
    Ok(terminal.backend().buffer().clone())
}

/// What the loop runs with besides the terminal and the app.
pub struct Context<'a> {
    pub worker: &'a Worker,
    pub theme: &'a Theme,
    pub img: &'a mut ImageCache,
    pub input: &'a Input,
    pub events: &'a mut dyn Events,
    /// The follower's batches and the alarm rules announcing them.
    pub live: Option<(
        &'a std::sync::mpsc::Receiver<crate::live::LiveBatch>,
        &'a crate::live::AlarmRules,
    )>,
    /// Called after every frame drawn (benchmarks, tests).
    pub on_frame: &'a mut dyn FnMut(&App),
}

/// Runs the loop until the app quits.
pub fn drive<B: Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
    cx: Context,
) -> anyhow::Result<()>
where
    B::Error: Send + Sync + 'static,
{
    let Context {
        worker,
        theme,
        img,
        input,
        events,
        live,
        on_frame,
    } = cx;
    let mut dirty = true;
    let mut last_progress: Vec<(u64, u64, u64)> = Vec::new();
    loop {
        for (id, req, progress) in app.take_requests() {
            worker.spawn(id, req, progress);
        }
        if dirty {
            let view = app.view();
            let chrome = app.chrome();
            terminal.draw(|f| draw_screen(f, &chrome, &view, theme, img))?;
            dirty = false;
            on_frame(app);
        }
        if app.quit {
            for r in &app.running {
                r.progress.cancel();
            }
            return Ok(());
        }
        let timeout = if live.is_some() {
            // New data arrives at any moment: look for it often.
            Duration::from_millis(40)
        } else if app.running.is_empty() {
            Duration::from_millis(500)
        } else {
            Duration::from_millis(100)
        };
        if events.poll(timeout)? {
            // Drain every pending event before drawing again.
            loop {
                let msg = match events.read()? {
                    Event::Key(k) => {
                        // A copy answered by the input layer changes the status line.
                        dirty = true;
                        input.key(app, k, &mut std::io::stdout())
                    }
                    Event::Mouse(m) => Some(Msg::Mouse(m)),
                    Event::Paste(s) => Some(Msg::Paste(s)),
                    Event::Resize(w, h) => Some(Msg::Resize(w, h)),
                    _ => None,
                };
                if let Some(m) = msg {
                    app.update(m);
                    dirty = true;
                }
                if app.quit || !events.poll(Duration::ZERO)? {
                    break;
                }
            }
        }
        for (id, out) in worker.poll() {
            app.update(Msg::JobDone(id, Box::new(out)));
            dirty = true;
        }
        if let Some((rx, rules)) = live {
            // At most a queue's worth per turn, so a follower that keeps
            // sending cannot hold the loop away from drawing and keys.
            for b in rx.try_iter().take(super::FOLLOW_QUEUE) {
                app.update(Msg::Live(Box::new(b)));
                dirty = true;
            }
            // Raised alarms: the bell / OSC 9 when asked for.
            if let Some(l) = app.session.live.as_mut() {
                for a in l.announce.drain(..) {
                    let n = rules.notification(&a);
                    if !n.is_empty() {
                        let mut out = std::io::stdout();
                        let _ = out.write_all(n.as_bytes());
                        let _ = out.flush();
                    }
                }
            }
        }
        // Redraw for a gauge only when a job's progress moved.
        let now: Vec<(u64, u64, u64)> = app
            .running
            .iter()
            .map(|r| (r.id, r.progress.done(), r.progress.total()))
            .collect();
        if now != last_progress {
            last_progress = now;
            dirty = true;
        }
    }
}
