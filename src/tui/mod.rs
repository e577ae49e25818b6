//! The terminal front end (ratatui + crossterm). It draws view models from
//! [`crate::panes`] and nothing else.
//!
//! - [`app`]: state, messages and the update function.
//! - [`worker`]: background jobs (model, study, loading) with progress and cancel.
//! - [`event_loop`]: the loop between the terminal's events, the worker,
//!   the live follower and the frames.
//! - [`draw`]: the screen (tabs, status line, help, prompt) and the image cache.
//! - [`panes`]: drawing of each pane's view.
//! - [`theme`]: colours (16-colour safe, `NO_COLOR`).
//! - [`fit`]: labels fitted to their cells without cutting words (the
//!   abbreviation table).
//! - [`keys`]: every key, for the help overlay and the docs.
//! - [`config`]: the technician's config file (key bindings, colours,
//!   mouse capture; follow and alarm sections passed through).
//! - [`input`]: keys between the terminal and the app (bindings, `y` copy).
//! - [`clipboard`]: what `y` copies, as OSC 52.
//!
//! The loop redraws only when something changed (a key, a resize, a job's
//! progress or result), and ratatui sends only the cells that differ from
//! the previous frame, so a slow SSH link carries little.

pub mod app;
pub mod clipboard;
pub mod config;
pub mod draw;
pub mod event_loop;
pub mod fit;
pub mod image_cache;
pub mod input;
pub mod jobs;
pub mod keys;
pub mod panes;
pub mod theme;
pub mod widgets;
pub mod worker;

use crate::panes::Session;
use app::App;
use draw::{ImageCache, draw_screen};
use input::Input;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use std::io::Write;
use std::time::Instant;
use theme::Theme;
use worker::Worker;

/// How to start the TUI.
#[derive(Debug, Clone)]
pub struct Options {
    /// Image protocol: `auto` (ask the terminal), `halfblocks`, `off`.
    pub images: draw::ImageMode,
    /// Overrides the colour detection (`NO_COLOR`, `COLORTERM`, `TERM`).
    pub theme: Option<Theme>,
    /// Start on this pane.
    pub pane: crate::panes::PaneId,
    /// The config file as loaded (`--config FILE`); None: read the
    /// default path ([`config::default_path`]) at start.
    pub config: Option<config::Loaded>,
    /// Follow a live line (`tui --follow`, `demo --live`); its follow
    /// defaults and alarm rules come from the same config file.
    pub follow: Option<crate::live::FollowInputs>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            images: draw::ImageMode::Auto,
            theme: None,
            pane: crate::panes::PaneId::Session,
            config: None,
            follow: None,
        }
    }
}

/// Draws one screen of `app` into a buffer of `width`×`height` cells
/// (headless: tests, `pinsight render`, benchmarks).
pub fn render_app(
    app: &App,
    width: u16,
    height: u16,
    theme: &Theme,
    img: &mut ImageCache,
) -> Buffer {
    let view = app.view();
    let chrome = app.chrome();
    render_view(&chrome, &view, width, height, theme, img)
}

/// Draws a view with its chrome into a buffer.
pub fn render_view(
    chrome: &draw::Chrome,
    view: &crate::panes::PaneView,
    width: u16,
    height: u16,
    theme: &Theme,
    img: &mut ImageCache,
) -> Buffer {
    let backend = TestBackend::new(width, height);
    let mut terminal = match Terminal::new(backend) {
        Ok(t) => t,
        Err(_) => return Buffer::empty(ratatui::layout::Rect::new(0, 0, width, height)),
    };
    let _ = terminal.draw(|f| draw_screen(f, chrome, view, theme, img));
    terminal.backend().buffer().clone()
}

/// A buffer's characters as text lines (trailing spaces trimmed), as
/// `pinsight render` prints them.
pub fn buffer_text(buf: &Buffer) -> String {
    let area = buf.area;
    let mut out = String::new();
    for y in 0..area.height {
        let mut line = String::new();
        let mut skip = 0usize;
        for x in 0..area.width {
            if skip > 0 {
                skip -= 1;
                continue;
            }
            let sym = buf[(x, y)].symbol();
            line.push_str(sym);
            let w = unicode_width(sym);
            if w > 1 {
                skip = w - 1;
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

fn unicode_width(s: &str) -> usize {
    use ratatui::text::Span;
    Span::raw(s).width().max(1)
}

/// Restores the terminal (raw mode off, main screen, mouse and paste off).
fn restore_terminal() {
    let mut out = std::io::stdout();
    let _ = crossterm::execute!(
        out,
        crossterm::event::DisableBracketedPaste,
        crossterm::event::DisableMouseCapture
    );
    ratatui::restore();
    let _ = out.flush();
}

/// Restores the terminal when the UI thread panics (worker panics are
/// caught and reported in the status line, without touching the screen).
fn install_panic_hook() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let on_ui = std::thread::current().name() == Some("main");
        if on_ui {
            restore_terminal();
            previous(info);
        }
    }));
}

/// Batches that may wait for the interface before the follower waits too.
///
/// The channel is bounded so that a rig writing faster than the interface
/// draws (a shift replayed at full speed, a slow SSH terminal) holds its
/// data on disk, where it already is, and not in a queue in memory: the
/// follower simply reads further when the interface has caught up. An
/// unbounded queue was the first suspect of the 8-hour shift's growth.
pub const FOLLOW_QUEUE: usize = 8;

/// The live follower on its own thread: polls when the files change (or
/// at its interval) and sends each batch with data to the interface
/// (waiting while [`FOLLOW_QUEUE`] batches are not taken yet); stops when
/// `stop` is set or the interface is gone.
pub fn spawn_follower(
    inputs: crate::live::FollowInputs,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> std::io::Result<std::sync::mpsc::Receiver<crate::live::LiveBatch>> {
    use std::sync::atomic::Ordering;
    let (tx, rx) = std::sync::mpsc::sync_channel(FOLLOW_QUEUE);
    std::thread::Builder::new()
        .name("pinsight-live".into())
        .spawn(move || {
            let cfg = inputs.config.clone();
            let mut f = crate::live::Follower::new(inputs);
            let mut wake = crate::live::wake::Wake::new(
                &f.watch_paths(),
                cfg.notify,
                cfg.poll_s,
                cfg.debounce_ms,
            );
            let mut changed = None;
            while !stop.load(Ordering::Relaxed) {
                let b = f.poll(changed.as_deref());
                if !b.is_empty() && tx.send(b).is_err() {
                    return;
                }
                changed = wake.next(f.behind()).changed;
            }
        })?;
    Ok(rx)
}

/// Makes the session live and starts the follower thread: returns its
/// batches and the alarm rules (the loop announces raised alarms by them).
pub fn start_follow(
    session: &mut Session,
    inputs: crate::live::FollowInputs,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> std::io::Result<(
    std::sync::mpsc::Receiver<crate::live::LiveBatch>,
    crate::live::AlarmRules,
)> {
    // Before the follower's thread exists, so its arena is one of the two.
    crate::allocator::settle_for_a_shift();
    session.start_live(
        inputs.config.clone(),
        inputs
            .paths
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    );
    let rules = inputs.alarms.clone();
    Ok((spawn_follower(inputs, stop)?, rules))
}

/// Runs the TUI on a session until the user quits.
pub fn run(mut session: Session, opts: Options) -> anyhow::Result<()> {
    let start = Instant::now();
    // NO_COLOR is applied by the theme; crossterm's own handling would emit
    // empty colour codes that reset bold and reverse video (pitfalls.md).
    crossterm::style::force_color_output(true);
    // A bad config never stops the TUI: its findings are shown once it runs.
    let cfg = opts.config.clone().unwrap_or_else(|| config::load(None));
    let theme = opts.theme.unwrap_or_else(|| cfg.config.theme());
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let mut live_rx = None;
    let mut rules = crate::live::AlarmRules::default();
    if let Some(inputs) = opts.follow.clone() {
        let (rx, r) = start_follow(&mut session, inputs, stop.clone())?;
        live_rx = Some(rx);
        rules = r;
    }
    install_panic_hook();
    let mut terminal = ratatui::try_init()?;
    let result = (|| -> anyhow::Result<()> {
        crossterm::execute!(std::io::stdout(), crossterm::event::EnableBracketedPaste)?;
        // Mouse capture is off unless the config asks: a terminal that
        // reports the mouse does not select text with it (over SSH the way
        // to copy), and `y` copies the selection anyway.
        if cfg.config.mouse {
            crossterm::execute!(std::io::stdout(), crossterm::event::EnableMouseCapture)?;
        }
        let size = terminal.size()?;
        let mut app = App::new(session, size.width, size.height);
        app.pane = opts.pane;
        if let Some(entry) = cfg.file_entry() {
            app.session.files.push(entry);
        }
        if let Some(first) = cfg.findings.first() {
            let more = match cfg.findings.len() {
                1 => String::new(),
                n => format!(" (+{} more on the Session pane)", n - 1),
            };
            app.message = Some((format!("config: {first}{more}"), true));
        }
        let input = Input::new(cfg.config.keys.clone());
        let mouse = if cfg.config.mouse { "on" } else { "off" };
        // Background work starts before the first frame.
        let worker = Worker::default();
        for (id, req, progress) in app.take_requests() {
            worker.spawn(id, req, progress);
        }
        let colours = match theme.depth {
            theme::ColorDepth::None => "no colour (NO_COLOR)",
            theme::ColorDepth::Ansi16 => "16 colours",
            theme::ColorDepth::Ansi256 => "256 colours",
            theme::ColorDepth::TrueColor => "truecolor",
        };
        // First frame at once; the image protocol query comes after it (it
        // can wait for the terminal) but before any input event is read.
        let mut img = ImageCache::off();
        if opts.images == draw::ImageMode::Auto {
            app.session.display = Some(format!("{colours}; images: asking the terminal…"));
        }
        {
            let view = app.view();
            let chrome = app.chrome();
            terminal.draw(|f| draw_screen(f, &chrome, &view, &theme, &mut img))?;
        }
        if let Ok(path) = std::env::var("PINSIGHT_FIRST_FRAME_LOG") {
            let _ = std::fs::write(
                path,
                format!("{:.3}\n", start.elapsed().as_secs_f64() * 1e3),
            );
        }
        img = match opts.images {
            draw::ImageMode::Auto => ImageCache::query_terminal(),
            draw::ImageMode::Halfblocks => ImageCache::halfblocks(),
            draw::ImageMode::Off => ImageCache::off(),
        };
        app.session.display = Some(format!(
            "{colours}; images: {}; mouse {mouse}",
            img.protocol_name()
        ));
        event_loop::drive(
            &mut terminal,
            &mut app,
            event_loop::Context {
                worker: &worker,
                theme: &theme,
                img: &mut img,
                input: &input,
                events: &mut event_loop::TerminalEvents,
                live: live_rx.as_ref().map(|rx| (rx, &rules)),
                on_frame: &mut |_| {},
            },
        )
    })();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    restore_terminal();
    result
}
