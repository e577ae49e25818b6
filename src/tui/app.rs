//! The application state and its update function (the Elm-style loop of
//! ratatui's templates): [`App::update`] takes a [`Msg`] (a key, a mouse
//! event, a paste, a resize, a finished job) and changes the state; it
//! never draws and never blocks. Work that takes time is queued as a
//! [`JobRequest`] that the runtime ([`super::run`]) hands to the worker.

use super::draw::{Chrome, Status, help_rows, tabs};
use super::worker::{JobKind, JobOutput, JobRequest};
use crate::panes::model::{self, Edit};
use crate::panes::{self, PaneId, PaneState, PaneView, Session};
use crate::progress::Progress;
use crossterm::event::{
    KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
};
use std::path::PathBuf;
use std::sync::Arc;

/// Everything that can happen to the app.
#[derive(Debug)]
pub enum Msg {
    Key(KeyEvent),
    Mouse(MouseEvent),
    /// Pasted text (bracketed paste; a file dropped on the terminal).
    Paste(String),
    Resize(u16, u16),
    JobDone(u64, Box<JobOutput>),
    /// What the live follower found since its last batch.
    Live(Box<crate::live::LiveBatch>),
}

/// A job the app is waiting for.
#[derive(Debug, Clone)]
pub struct Running {
    pub id: u64,
    pub kind: JobKind,
    pub label: String,
    pub progress: Arc<Progress>,
}

/// The whole interface state.
pub struct App {
    pub session: Session,
    pub ui: PaneState,
    pub pane: PaneId,
    pub help: bool,
    pub help_scroll: usize,
    /// Open-file prompt text while it is open.
    pub prompt: Option<String>,
    /// Status message (text, is_error).
    pub message: Option<(String, bool)>,
    pub running: Vec<Running>,
    /// Jobs queued for the runtime to start.
    pub requests: Vec<(u64, JobRequest, Arc<Progress>)>,
    pub(super) next_id: u64,
    pub quit: bool,
    /// Background analyses the user cancelled: not restarted by themselves
    /// until asked (`r`) or the subject changes.
    pub(super) suppressed: Vec<JobKind>,
}

impl App {
    /// A new app on a session; queues the model run if the session has none.
    pub fn new(session: Session, width: u16, height: u16) -> Self {
        let mut app = Self {
            session,
            ui: PaneState::new(width, height),
            pane: PaneId::Session,
            help: false,
            help_scroll: 0,
            prompt: None,
            message: None,
            running: Vec::new(),
            requests: Vec::new(),
            next_id: 1,
            quit: false,
            suppressed: Vec::new(),
        };
        if app.session.model.is_none() {
            app.start_model();
        }
        app
    }

    /// The current pane's view.
    pub fn view(&self) -> PaneView {
        panes::view(self.pane, &self.session, &self.ui)
    }

    /// What surrounds the pane.
    pub fn chrome(&self) -> Chrome {
        let status = if let Some(r) = self.running.first() {
            let label = {
                let m = r.progress.message();
                if m.is_empty() { r.label.clone() } else { m }
            };
            Status::Job {
                label,
                fraction: r.progress.fraction(),
                done: r.progress.done(),
                total: r.progress.total(),
                more: self.running.len() - 1,
            }
        } else if let Some((text, error)) = &self.message {
            Status::Message {
                text: text.clone(),
                error: *error,
            }
        } else {
            Status::Hints
        };
        Chrome {
            pane: self.pane,
            title: self.session.title.clone(),
            status,
            help: self.help,
            help_scroll: self.help_scroll,
            prompt: self.prompt.clone(),
            live: self
                .session
                .live
                .as_ref()
                .map(|l| super::draw::LiveIndicator {
                    following: self.ui.follow,
                    text: l.status(
                        self.session
                            .yields
                            .as_ref()
                            .and_then(|y| y.report.yield_frac),
                    ),
                    alarm: !l.active_alarms.is_empty(),
                }),
        }
    }

    /// Handles one message.
    pub fn update(&mut self, msg: Msg) {
        self.update_inner(msg);
        self.schedule();
    }

    fn update_inner(&mut self, msg: Msg) {
        match msg {
            Msg::Key(k) => {
                if k.kind == KeyEventKind::Press || k.kind == KeyEventKind::Repeat {
                    self.key(k)
                }
            }
            Msg::Mouse(m) => self.mouse(m),
            Msg::Paste(text) => self.paste(&text),
            Msg::Resize(w, h) => {
                self.ui.width = w;
                self.ui.height = h;
            }
            Msg::JobDone(id, out) => self.job_done(id, *out),
            Msg::Live(b) => {
                self.session.absorb_live(*b);
                self.follow_now();
            }
        }
    }

    /// In follow mode, moves the views to the newest data: the Signals
    /// window ends at the newest sample (keeping its width), Vision shows
    /// the latest connector.
    pub fn follow_now(&mut self) {
        if !self.ui.follow {
            return;
        }
        let Some(live) = &self.session.live else {
            return;
        };
        if let Some(t1) = live.latest_s {
            let span = self
                .ui
                .signals
                .window
                .map(|[a, b]| b - a)
                .filter(|w| w.is_finite() && *w > 0.0)
                .unwrap_or(2.0)
                .min(live.config.window_s);
            self.ui.signals.window = Some([t1 - span, t1]);
            self.ui.signals.cursor = Some(t1);
        }
        if !self.session.images.is_empty() {
            self.ui.vision.image = self.session.images.len() - 1;
        }
    }

    /// A key that looks back in live mode pauses following.
    fn pause_follow(&mut self) {
        if self.session.live.is_some() {
            self.ui.follow = false;
        }
    }

    fn paste(&mut self, text: &str) {
        if let Some(p) = self.prompt.as_mut() {
            p.push_str(text.trim_end_matches(['\n', '\r']));
            return;
        }
        if self.pane == PaneId::Model
            && let Some(e) = self.ui.model.editing.as_mut()
        {
            e.push_str(text.trim());
            return;
        }
        let paths = parse_dropped(text);
        if paths.is_empty() {
            self.message = Some(("pasted text is not a path".into(), true));
        } else {
            self.open(paths);
        }
    }

    fn mouse(&mut self, m: MouseEvent) {
        match m.kind {
            MouseEventKind::Down(MouseButton::Left) if m.row == 0 => {
                if let Some((p, ..)) = tabs(self.ui.width)
                    .into_iter()
                    .find(|(_, _, a, b)| m.column >= *a && m.column < *b)
                {
                    self.switch(p);
                }
            }
            MouseEventKind::ScrollDown => {
                if self.pane == PaneId::Signals {
                    self.signals_zoom(1.25)
                } else {
                    self.rows(1)
                }
            }
            MouseEventKind::ScrollUp => {
                if self.pane == PaneId::Signals {
                    self.signals_zoom(0.8)
                } else {
                    self.rows(-1)
                }
            }
            _ => {}
        }
    }

    fn switch(&mut self, p: PaneId) {
        self.pane = p;
        self.message = None;
        // The quick methods lab runs the first time its pane is shown.
        if p == PaneId::Methods
            && self.session.methods.is_none()
            && self.session.methods_error.is_none()
            && !self.running.iter().any(|r| r.kind == JobKind::Methods)
        {
            self.start(JobRequest::Methods);
        }
    }

    fn key(&mut self, k: KeyEvent) {
        let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
        if ctrl && k.code == KeyCode::Char('c') {
            self.quit = true;
            return;
        }
        // Modal states first: the prompt, an edit, the help overlay.
        if let Some(text) = self.prompt.as_mut() {
            match k.code {
                KeyCode::Esc => self.prompt = None,
                KeyCode::Enter => {
                    let t = std::mem::take(text);
                    self.prompt = None;
                    let paths = parse_dropped(&t);
                    if paths.is_empty() {
                        self.message = Some(("no path typed".into(), true));
                    } else {
                        self.open(paths);
                    }
                }
                KeyCode::Backspace => {
                    text.pop();
                }
                KeyCode::Char('u') if ctrl => text.clear(),
                KeyCode::Char(c) => text.push(c),
                _ => {}
            }
            return;
        }
        if self.pane == PaneId::Model && self.ui.model.editing.is_some() {
            self.edit_key(k, ctrl);
            return;
        }
        if self.help {
            match k.code {
                KeyCode::Esc | KeyCode::Char('?') | KeyCode::Char('q') => self.help = false,
                KeyCode::Down | KeyCode::Char('j') => {
                    self.help_scroll = (self.help_scroll + 1).min(help_rows().saturating_sub(1))
                }
                KeyCode::Up | KeyCode::Char('k') => {
                    self.help_scroll = self.help_scroll.saturating_sub(1)
                }
                _ => {}
            }
            return;
        }
        match k.code {
            KeyCode::Char('q') => self.quit = true,
            KeyCode::Char('?') => {
                self.help = true;
                self.help_scroll = 0;
            }
            KeyCode::Esc => {
                if !self.running.is_empty() {
                    self.cancel_jobs();
                } else {
                    self.message = None;
                }
            }
            KeyCode::Char('c') => self.cancel_jobs(),
            KeyCode::Tab => {
                let i = (self.pane.index() + 1) % PaneId::ALL.len();
                self.switch(PaneId::ALL[i]);
            }
            KeyCode::BackTab => {
                let n = PaneId::ALL.len();
                let i = (self.pane.index() + n - 1) % n;
                self.switch(PaneId::ALL[i]);
            }
            KeyCode::Char(d @ '1'..='9') => {
                let i = d as usize - '1' as usize;
                self.switch(PaneId::ALL[i]);
            }
            KeyCode::Char('T') => self.switch(PaneId::Trend),
            KeyCode::Char('F') if self.session.live.is_some() => {
                self.ui.follow = !self.ui.follow;
                self.follow_now();
            }
            KeyCode::End | KeyCode::Char('G')
                if self.session.live.is_some()
                    && matches!(self.pane, PaneId::Signals | PaneId::Vision) =>
            {
                self.ui.follow = true;
                self.follow_now();
            }
            KeyCode::Char('o') => self.prompt = Some(String::new()),
            KeyCode::Down | KeyCode::Char('j') => self.rows(1),
            KeyCode::Up | KeyCode::Char('k') => self.rows(-1),
            KeyCode::Home | KeyCode::Char('g') => self.rows(-1_000_000),
            KeyCode::End | KeyCode::Char('G') => self.rows(1_000_000),
            _ => self.pane_key(k),
        }
    }

    fn edit_key(&mut self, k: KeyEvent, ctrl: bool) {
        let Some(text) = self.ui.model.editing.as_mut() else {
            return;
        };
        match k.code {
            KeyCode::Esc => {
                self.ui.model.editing = None;
                self.ui.model.error = None;
            }
            KeyCode::Backspace => {
                text.pop();
            }
            KeyCode::Char('u') if ctrl => text.clear(),
            KeyCode::Char(c) => text.push(c),
            KeyCode::Enter => {
                let text = text.clone();
                let key = model::row_key(self.ui.model.selected);
                match model::apply_edit(&self.session.params, key, &text) {
                    Ok(Edit::Params(p)) => {
                        let preset_change = key == "preset";
                        self.session.params = *p;
                        self.session.params_source = if preset_change {
                            format!("preset {}", self.session.params.preset)
                        } else if self.session.params_source.ends_with("+ edits") {
                            self.session.params_source.clone()
                        } else {
                            format!("{} + edits", self.session.params_source)
                        };
                        self.ui.model.editing = None;
                        self.ui.model.error = None;
                        self.ui.model.notice =
                            Some(format!("{key} = {} — re-running", text.trim()));
                        self.start_model();
                    }
                    Ok(Edit::Level(l)) => {
                        self.session.level = l;
                        self.ui.model.editing = None;
                        self.ui.model.error = None;
                        self.ui.model.notice =
                            Some(format!("level = {} — re-running", text.trim()));
                        self.start_model();
                    }
                    Err(e) => {
                        // Stay in the editor with the text so it can be fixed.
                        self.ui.model.error = Some(e);
                        self.ui.model.notice = None;
                    }
                }
            }
            _ => {}
        }
    }

    /// Moves the selection of the current pane by `d` rows.
    fn rows(&mut self, d: i64) {
        let step = |cur: usize, n: usize| -> usize {
            if n == 0 {
                0
            } else {
                (cur as i64 + d).clamp(0, n as i64 - 1) as usize
            }
        };
        match self.pane {
            PaneId::Session => {
                self.ui.session.selected = step(self.ui.session.selected, self.session.files.len())
            }
            PaneId::Model => {
                self.ui.model.selected = step(self.ui.model.selected, model::row_count());
                self.ui.model.error = None;
                self.ui.model.notice = None;
            }
            PaneId::Signals => {
                let n = self
                    .session
                    .signal_set(self.ui.signals.log)
                    .map(|s| s.channels.len())
                    .unwrap_or(0);
                self.ui.signals.selected = step(self.ui.signals.selected, n);
            }
            PaneId::Vision => {
                let n = self.session.images.len();
                let pins = (n > 0)
                    .then(|| self.ui.vision.image.min(n - 1))
                    .and_then(|i| self.session.inspection(i))
                    .and_then(|r| r.result.inspection.as_ref())
                    .map_or(0, |i| i.pins.len());
                self.ui.vision.pin = step(self.ui.vision.pin, pins);
            }
            PaneId::Yield => {
                let n = self.session.yields.as_ref().map_or(0, |y| y.results.len());
                self.ui.yields.selected = step(self.ui.yields.selected, n);
            }
            PaneId::Line => {
                let n = crate::panes::line::cycle_count(&self.session, &self.ui);
                let cur = self.ui.line.cycle.unwrap_or(n.saturating_sub(1));
                self.ui.line.cycle = Some(step(cur.min(n.saturating_sub(1)), n));
            }
            PaneId::Trend => {
                let n = match &self.session.trend {
                    Some(Ok(r)) => r.heads.len(),
                    _ => 0,
                };
                self.ui.trend.head = step(self.ui.trend.head, n);
            }
            PaneId::Methods => {
                let n = crate::panes::methods::view(&self.session, &self.ui)
                    .chart_titles
                    .len();
                self.ui.methods.chart = step(self.ui.methods.chart, n);
            }
            _ => {}
        }
    }

    fn signals_zoom(&mut self, factor: f64) {
        if let Some(set) = self.session.signal_set(self.ui.signals.log) {
            let full = set.t_range();
            self.ui.signals.zoom(factor, full);
        }
    }

    fn pane_key(&mut self, k: KeyEvent) {
        let shift = k.modifiers.contains(KeyModifiers::SHIFT);
        match self.pane {
            PaneId::Signals => {
                let Some(set) = self.session.signal_set(self.ui.signals.log) else {
                    return;
                };
                let full = set.t_range();
                let cycles = set.cycles.clone();
                let names: Vec<String> = set.channels.iter().map(|c| c.name.clone()).collect();
                drop(set);
                let looks_back = matches!(
                    k.code,
                    KeyCode::Left
                        | KeyCode::Right
                        | KeyCode::Char(
                            'h' | 'l' | 'H' | 'L' | '+' | '=' | '-' | '_' | '0' | '[' | ']'
                        )
                );
                if looks_back {
                    self.pause_follow();
                }
                let s = &mut self.ui.signals;
                match k.code {
                    KeyCode::Left if shift => s.pan(-0.5, full),
                    KeyCode::Right if shift => s.pan(0.5, full),
                    KeyCode::Char('H') => s.pan(-0.5, full),
                    KeyCode::Char('L') => s.pan(0.5, full),
                    KeyCode::Left | KeyCode::Char('h') => s.move_cursor(-0.05, full),
                    KeyCode::Right | KeyCode::Char('l') => s.move_cursor(0.05, full),
                    KeyCode::Char('+') | KeyCode::Char('=') => s.zoom(0.5, full),
                    KeyCode::Char('-') | KeyCode::Char('_') => s.zoom(2.0, full),
                    KeyCode::Char('0') => s.reset(),
                    KeyCode::Char('[') => s.jump_cycle(false, &cycles, full),
                    KeyCode::Char(']') => s.jump_cycle(true, &cycles, full),
                    KeyCode::Char(' ') => {
                        if let Some(n) = names.get(s.selected)
                            && !s.hidden.remove(n)
                        {
                            s.hidden.insert(n.clone());
                        }
                    }
                    _ => {}
                }
            }
            PaneId::Overlay => match k.code {
                KeyCode::Right | KeyCode::Char('n') | KeyCode::Char('l') => {
                    let c = &mut self.ui.overlay.cycle;
                    *c = Some(c.map_or(0, |i| i + 1));
                }
                KeyCode::Left | KeyCode::Char('p') | KeyCode::Char('h') => {
                    let c = &mut self.ui.overlay.cycle;
                    *c = Some(c.map_or(0, |i| i.saturating_sub(1)));
                }
                KeyCode::Char('a') => self.ui.overlay.cycle = None,
                KeyCode::Char('r') if !self.session.logs.is_empty() => {
                    let i = self.ui.overlay.log.min(self.session.logs.len() - 1);
                    self.start_overlay(i);
                }
                KeyCode::Char('C') if !self.session.logs.is_empty() => {
                    let i = self.ui.overlay.log.min(self.session.logs.len() - 1);
                    self.start_calibration(i);
                }
                _ => {}
            },
            PaneId::Yield if k.code == KeyCode::Char('r') && !self.session.images.is_empty() => {
                self.start_yield();
            }
            PaneId::Line => match k.code {
                KeyCode::Char('r') if !self.session.process_recipes.is_empty() => {
                    self.start_monitor()
                }
                _ => {}
            },
            PaneId::Trend if k.code == KeyCode::Char('r') && !self.session.logs.is_empty() => {
                self.start_trend();
            }
            PaneId::Model => match k.code {
                KeyCode::Enter | KeyCode::Char('e') => {
                    self.ui.model.editing =
                        Some(model::row_value(&self.session, self.ui.model.selected));
                    self.ui.model.error = None;
                    self.ui.model.notice = None;
                }
                KeyCode::Char('r') => self.start_model(),
                _ => {}
            },
            PaneId::Study => match k.code {
                KeyCode::Char('r') => self.start_study(),
                KeyCode::Char('f') => self.ui.study.next_factor(),
                KeyCode::Right | KeyCode::Char('l') => self.ui.study.next_quantity(true),
                KeyCode::Left | KeyCode::Char('h') => self.ui.study.next_quantity(false),
                _ => {}
            },
            PaneId::Methods if k.code == KeyCode::Char('r') => {
                self.session.methods_error = None;
                self.start(JobRequest::Methods);
            }
            PaneId::Vision => {
                let n = self.session.images.len();
                if matches!(
                    k.code,
                    KeyCode::Left | KeyCode::Right | KeyCode::Char('n' | 'p' | 'h' | 'l')
                ) {
                    self.pause_follow();
                }
                match k.code {
                    KeyCode::Right | KeyCode::Char('n') | KeyCode::Char('l') if n > 0 => {
                        self.ui.vision.image = (self.ui.vision.image + 1) % n;
                        self.ui.vision.pin = 0;
                        self.suppressed.retain(|k| *k != JobKind::Inspect);
                    }
                    KeyCode::Left | KeyCode::Char('p') | KeyCode::Char('h') if n > 0 => {
                        self.ui.vision.image = (self.ui.vision.image + n - 1) % n;
                        self.ui.vision.pin = 0;
                        self.suppressed.retain(|k| *k != JobKind::Inspect);
                    }
                    KeyCode::Char('r') if n > 0 => {
                        let i = self.ui.vision.image.min(n - 1);
                        self.start_inspect(i);
                    }
                    _ => {}
                }
            }
            _ => {}
        }
    }
}

/// Paths from pasted or dropped text: one per line; quotes, `file://`
/// prefixes and backslash-escaped spaces (how terminals paste a dropped
/// file) are undone.
pub fn parse_dropped(text: &str) -> Vec<PathBuf> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(|l| {
            let l = l
                .strip_prefix('\'')
                .and_then(|x| x.strip_suffix('\''))
                .or_else(|| l.strip_prefix('"').and_then(|x| x.strip_suffix('"')))
                .unwrap_or(l);
            let l = l.strip_prefix("file://").unwrap_or(l);
            let l = l.replace("\\ ", " ");
            match (l.strip_prefix("~/"), std::env::var_os("HOME")) {
                (Some(rest), Some(home)) => PathBuf::from(home).join(rest),
                _ => PathBuf::from(l),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dropped_paths() {
        let p = parse_dropped("'/tmp/a b.mcap'\nfile:///x/y.png\n/z/with\\ space.toml\n\n");
        assert_eq!(
            p,
            vec![
                PathBuf::from("/tmp/a b.mcap"),
                PathBuf::from("/x/y.png"),
                PathBuf::from("/z/with space.toml")
            ]
        );
        assert!(parse_dropped("  \n").is_empty());
    }
}
