//! The screen: tab bar, the active pane, the status line (hints, messages,
//! or the gauge of the running background work), the `?` help overlay and
//! the open-file prompt. The TUI and `pinsight render` both draw through
//! [`draw_screen`], so headless output is exactly what the terminal shows.

pub use super::image_cache::{ImageCache, ImageMode, QUERY_TIMEOUT_MS};
use super::keys::KEYS;
use super::panes::draw_pane;
use super::theme::Theme;
use super::widgets::{block, trunc};
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
pub fn tabs(width: u16) -> Vec<(PaneId, String, u16, u16)> {
    // "9 Methods ": the title, its number and two spaces (nine panes fit
    // 80 columns in full).
    let full: u16 = PaneId::ALL.iter().map(|p| p.title().len() as u16 + 3).sum();
    let short = full > width;
    let mut x = 0u16;
    let mut out = Vec::new();
    for (i, p) in PaneId::ALL.iter().enumerate() {
        let name = if short {
            p.title().chars().take(3).collect::<String>()
        } else {
            p.title().to_string()
        };
        // Panes 1–9 by their digit, the tenth (Trend) by T.
        let key = if i < 9 {
            (i + 1).to_string()
        } else {
            "T".into()
        };
        let label = format!("{key} {name} ");
        let w = label.chars().count() as u16;
        out.push((*p, label, x, x + w));
        x += w;
    }
    out
}

/// Key hints per pane.
fn hints(pane: PaneId) -> &'static str {
    match pane {
        PaneId::Session => "j/k select  o open",
        PaneId::Signals => "h/l cursor  H/L pan  +/- zoom  [ ] cycle  space channel  0 all",
        PaneId::Overlay => "n/p cycle  a envelope",
        PaneId::Model => "j/k select  Enter edit  r re-run",
        PaneId::Study => "r run  f factor  h/l quantity",
        PaneId::Vision => "n/p image  j/k pin",
        PaneId::Yield => "j/k select",
        PaneId::Methods => "j/k chart  r re-run",
        PaneId::Line => "j/k cycle  r re-run",
        PaneId::Trend => "j/k head  r re-run",
    }
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
    for (p, label, _, _) in tabs(area.width) {
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
            let w = (text.chars().count() as u16).min(bottom.width);
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
            let h = hints(chrome.pane);
            let line = Line::from(vec![
                Span::styled("?", theme.key()),
                Span::styled(" help  ", theme.muted()),
                Span::styled("q", theme.key()),
                Span::styled(" quit  ", theme.muted()),
                Span::styled("Tab", theme.key()),
                Span::styled(" pane  ", theme.muted()),
                Span::styled(h, theme.muted()),
            ]);
            f.render_widget(Paragraph::new(line), bottom);
        }
        Status::Message { text, error } => {
            let style = if *error { theme.error() } else { theme.ok() };
            f.render_widget(
                Paragraph::new(Line::styled(trunc(text, area.width as usize), style)),
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
    let visible = r.height.saturating_sub(3) as usize;
    let scroll = scroll.min(KEYS.len().saturating_sub(visible));
    let mut last = "";
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
            Row::new(vec![
                Span::styled(c.to_string(), theme.header()),
                Span::styled(keys.to_string(), theme.key()),
                Span::raw(what.to_string()),
            ])
        })
        .skip(scroll)
        .collect();
    let more = if scroll + visible < KEYS.len() {
        " — j/k scroll"
    } else {
        ""
    };
    let t = Table::new(
        rows,
        [
            Constraint::Length(11),
            Constraint::Length(15),
            Constraint::Min(10),
        ],
    )
    .block(
        block(format!("Help — every key (? or Esc closes){more}"), theme)
            .border_style(theme.border_focus()),
    );
    f.render_widget(t, r);
}
