//! The screen: tab bar, the active pane, the status line (hints, messages,
//! or the gauge of the running background work), the `?` help overlay and
//! the open-file prompt. The TUI and `pinsight render` both draw through
//! [`draw_screen`], so headless output is exactly what the terminal shows.

pub use super::image_cache::{ImageCache, ImageMode, QUERY_TIMEOUT_MS};
use super::keys::KEYS;
use super::panes::draw_pane;
use super::theme::Theme;
use super::widgets::{block, block_in, trunc};
use crate::panes::{PaneId, PaneView};
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Gauge, Paragraph, Row, Table};

/// What the status line shows.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// Key hints for the pane.
    Hints,
    /// A message (error or not).
    Message { text: String, error: bool },
    /// Background work: its label, fraction done, counts.
    Job {
        label: String,
        fraction: f64,
        done: u64,
        total: u64,
        more: usize,
    },
}

/// Everything around the pane.
#[derive(Debug, Clone)]
pub struct Chrome {
    pub pane: PaneId,
    pub title: String,
    pub status: Status,
    pub help: bool,
    pub help_scroll: usize,
    /// The open-file prompt's text, while it is open.
    pub prompt: Option<String>,
    /// Live mode: the indicator (following or paused), the counts, and
    /// whether an alarm is raised.
    pub live: Option<LiveIndicator>,
}

/// The live line's indicator at the start of the status line.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveIndicator {
    pub following: bool,
    pub text: String,
    pub alarm: bool,
}

impl Chrome {
    pub fn new(pane: PaneId, title: impl Into<String>) -> Self {
        Self {
            pane,
            title: title.into(),
            status: Status::Hints,
            help: false,
            help_scroll: 0,
            prompt: None,
            live: None,
        }
    }
}

/// Tab labels fitting `width`, with their column ranges (for mouse clicks).
/// Full names when they fit; else the abbreviations of
/// [`super::fit::ABBREVIATIONS`] (Sess, Sig, Ovl: ten tabs in 77 columns);
/// else only the keys, the current pane named.
pub fn tabs(width: u16) -> Vec<(PaneId, String, u16, u16)> {
    tabs_for(width, None)
}

fn tabs_for(width: u16, current: Option<PaneId>) -> Vec<(PaneId, String, u16, u16)> {
    // Panes 1–9 by their digit, the tenth (Trend) by T.
    let key = |i: usize| {
        if i < 9 {
            (i + 1).to_string()
        } else {
            "T".into()
        }
    };
    let build = |name: &dyn Fn(PaneId) -> String| {
        let mut x = 0u16;
        let mut out = Vec::new();
        for (i, p) in PaneId::ALL.iter().enumerate() {
            let n = name(*p);
            let label = if n.is_empty() {
                format!("{} ", key(i))
            } else {
                format!("{} {n} ", key(i))
            };
            let w = super::fit::width(&label) as u16;
            out.push((*p, label, x, x + w));
            x += w;
        }
        (out, x)
    };
    let (full, w) = build(&|p| p.title().to_string());
    if w <= width {
        return full;
    }
    let (short, w) = build(&|p| super::fit::abbreviate(p.title()));
    if w <= width {
        return short;
    }
    build(&|p| {
        if Some(p) == current {
            p.title().to_string()
        } else {
            String::new()
        }
    })
    .0
}

/// Key hints per pane (key, what), most useful first; the status line
/// shows as many whole hints as fit.
fn hints(pane: PaneId) -> &'static [(&'static str, &'static str)] {
    match pane {
        PaneId::Session => &[("j/k", "select"), ("o", "open"), ("y", "copy")],
        PaneId::Signals => &[
            ("h/l", "cursor"),
            ("H/L", "pan"),
            ("+/-", "zoom"),
            ("[ ]", "cycle"),
            ("space", "channel"),
            ("0", "all"),
            ("y", "copy"),
        ],
        PaneId::Overlay => &[
            ("n/p", "cycle"),
            ("a", "envelope"),
            ("C", "calibrate"),
            ("y", "copy"),
        ],
        PaneId::Model => &[
            ("j/k", "select"),
            ("Enter", "edit"),
            ("r", "re-run"),
            ("y", "copy"),
        ],
        PaneId::Study => &[
            ("r", "run"),
            ("f", "factor"),
            ("h/l", "quantity"),
            ("y", "copy"),
        ],
        PaneId::Vision => &[("n/p", "image"), ("j/k", "pin"), ("y", "copy")],
        PaneId::Yield => &[("j/k", "select"), ("r", "re-run"), ("y", "copy")],
        PaneId::Methods => &[("j/k", "chart"), ("r", "re-run"), ("y", "copy")],
        PaneId::Line => &[("j/k", "cycle"), ("r", "re-run"), ("y", "copy")],
        PaneId::Trend => &[("j/k", "head"), ("r", "re-run"), ("y", "copy")],
    }
}

/// The status line's hints: help, quit, pane, then the pane's hints that
/// fit in `width` (whole hints only).
fn hint_line<'a>(pane: PaneId, width: usize, theme: &Theme) -> Line<'a> {
    let mut spans = Vec::new();
    let mut used = 0usize;
    let all = [("?", "help"), ("q", "quit"), ("Tab", "pane")];
    for (i, (k, what)) in all.iter().chain(hints(pane)).enumerate() {
        let w = k.chars().count() + 1 + what.chars().count() + 2;
        if used + w - 2 > width {
            if i < all.len() {
                continue;
            }
            break;
        }
        spans.push(Span::styled(k.to_string(), theme.key()));
        spans.push(Span::styled(format!(" {what}  "), theme.muted()));
        used += w;
    }
    Line::from(spans)
}

/// Draws the whole screen.
pub fn draw_screen(
    f: &mut Frame,
    chrome: &Chrome,
    view: &PaneView,
    theme: &Theme,
    img: &mut ImageCache,
) {
    let area = f.area();
    f.render_widget(Paragraph::new("").style(theme.base()), area);
    if area.height < 3 || area.width < 20 {
        f.render_widget(Paragraph::new("pinsight: window too small"), area);
        return;
    }
    let [top, body, bottom] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Min(1),
        Constraint::Length(1),
    ])
    .areas(area);
    // Tab bar.
    let mut spans = Vec::new();
    for (p, label, _, _) in tabs_for(area.width, Some(chrome.pane)) {
        let style = if p == chrome.pane {
            theme.selected()
        } else {
            theme.muted()
        };
        spans.push(Span::styled(label, style));
    }
    let used: usize = spans.iter().map(|s| s.content.chars().count()).sum();
    let room = (area.width as usize).saturating_sub(used + 1);
    if room > 8 {
        spans.push(Span::styled(
            format!(" {}", trunc(&chrome.title, room)),
            theme.muted(),
        ));
    }
    f.render_widget(Paragraph::new(Line::from(spans)), top);
    draw_pane(f, body, view, theme, img);
    // Status line: the live indicator first, then the status.
    let bottom = match &chrome.live {
        None => bottom,
        Some(li) => {
            let mark = if li.following {
                "▶ FOLLOW "
            } else {
                "❚❚ PAUSED (F/End resumes) "
            };
            let text = trunc(
                &format!("{mark}{} ", li.text),
                (area.width as usize * 2 / 3).max(10),
            );
            let w = (super::fit::width(&text) as u16).min(bottom.width);
            let [ind, rest] =
                Layout::horizontal([Constraint::Length(w), Constraint::Min(0)]).areas(bottom);
            let style = if li.alarm {
                theme.error()
            } else if li.following {
                theme.ok()
            } else {
                theme.key()
            };
            f.render_widget(Paragraph::new(Line::styled(text, style)), ind);
            rest
        }
    };
    match &chrome.status {
        Status::Hints => {
            // Whole hints in the room the live indicator leaves.
            let line = hint_line(chrome.pane, bottom.width as usize, theme);
            f.render_widget(Paragraph::new(line), bottom);
        }
        Status::Message { text, error } => {
            let style = if *error { theme.error() } else { theme.ok() };
            f.render_widget(
                Paragraph::new(Line::styled(trunc(text, bottom.width as usize), style)),
                bottom,
            );
        }
        Status::Job {
            label,
            fraction,
            done,
            total,
            more,
        } => {
            let extra = if *more > 0 {
                format!(" (+{more} queued)")
            } else {
                String::new()
            };
            let text = if *total > 0 {
                format!("{label} {done}/{total}{extra} — Esc/c cancels")
            } else {
                format!("{label}{extra} — Esc/c cancels")
            };
            f.render_widget(
                Gauge::default()
                    .ratio(fraction.clamp(0.0, 1.0))
                    .label(trunc(&text, area.width as usize))
                    .gauge_style(theme.gauge())
                    .use_unicode(true),
                bottom,
            );
        }
    }
    if let Some(p) = &chrome.prompt {
        prompt(f, body, p, theme);
    }
    if chrome.help {
        help(f, body, chrome.help_scroll, theme);
    }
}

/// A centred rectangle of at most `w`×`h` inside `area`.
pub fn centered(area: Rect, w: u16, h: u16) -> Rect {
    let w = w.min(area.width);
    let h = h.min(area.height);
    Rect::new(
        area.x + (area.width - w) / 2,
        area.y + (area.height - h) / 2,
        w,
        h,
    )
}

fn prompt(f: &mut Frame, body: Rect, text: &str, theme: &Theme) {
    let r = centered(body, body.width.saturating_sub(4).min(100), 5);
    f.render_widget(Clear, r);
    let lines = vec![
        Line::from(vec![
            Span::styled("path: ", theme.key()),
            Span::raw(format!("{text}▏")),
        ]),
        Line::styled(
            "a rig log, image, recipe, parameter file or folder — Enter opens, Esc cancels",
            theme.muted(),
        ),
    ];
    f.render_widget(
        Paragraph::new(lines).block(block("Open", theme).border_style(theme.border_focus())),
        r,
    );
}

/// Lines the help table has (for scrolling).
pub fn help_rows() -> usize {
    KEYS.len()
}

fn help(f: &mut Frame, body: Rect, scroll: usize, theme: &Theme) {
    let r = centered(body, body.width.saturating_sub(2).min(110), body.height);
    f.render_widget(Clear, r);
    let inner_w = r.width.saturating_sub(2);
    let (ctx_w, keys_w) = (11u16, 15u16);
    let what_w = inner_w.saturating_sub(ctx_w + keys_w + 2).max(10) as usize;
    // Each row wraps its text at word boundaries: nothing is cut.
    let heights: Vec<usize> = KEYS
        .iter()
        .map(|(_, _, what)| super::fit::wrap(what, what_w).len().max(1))
        .collect();
    let visible = r.height.saturating_sub(3) as usize;
    // The last scroll position that still fills the screen.
    let mut last_start = KEYS.len();
    let mut h = 0;
    while last_start > 0 && h + heights[last_start - 1] <= visible {
        last_start -= 1;
        h += heights[last_start];
    }
    let scroll = scroll.min(last_start);
    let mut last = "";
    let mut shown_h = 0usize;
    let mut shown = 0usize;
    let rows: Vec<Row> = KEYS
        .iter()
        .enumerate()
        .map(|(i, (ctx, keys, what))| {
            // The context is named on the first row of its group (and on the
            // first visible row).
            let c = if *ctx != last || i == scroll {
                *ctx
            } else {
                ""
            };
            last = ctx;
            let lines: Vec<Line> = super::fit::wrap(what, what_w)
                .into_iter()
                .map(Line::raw)
                .collect();
            Row::new(vec![
                ratatui::widgets::Cell::from(Span::styled(c.to_string(), theme.header())),
                ratatui::widgets::Cell::from(Span::styled(keys.to_string(), theme.key())),
                ratatui::widgets::Cell::from(ratatui::text::Text::from(lines)),
            ])
            .height(heights[i] as u16)
        })
        .skip(scroll)
        .collect();
    for h in &heights[scroll..] {
        if shown_h + h > visible {
            break;
        }
        shown_h += h;
        shown += 1;
    }
    let more = if scroll + shown < KEYS.len() {
        " — j/k scroll"
    } else {
        ""
    };
    let t = Table::new(
        rows,
        [
            Constraint::Length(ctx_w),
            Constraint::Length(keys_w),
            Constraint::Min(10),
        ],
    )
    .block(
        block_in(
            r,
            &format!("Help — every key (? or Esc closes){more}"),
            theme,
        )
        .border_style(theme.border_focus()),
    );
    f.render_widget(t, r);
}
