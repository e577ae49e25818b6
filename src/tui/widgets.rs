//! Drawing helpers shared by the panes: charts from [`ChartView`]s, bars
//! from [`BarsView`]s, key–value lines. They only lay out and style what
//! the view models hold.

use super::theme::Theme;
use crate::panes::chart::{BarsView, ChartView, MarkerKind, SeriesKind, runs};
use ratatui::Frame;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::Style;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, LegendPosition, Paragraph, Wrap};

/// A bordered block with a title.
pub fn block<'a>(title: impl Into<Line<'a>>, theme: &Theme) -> Block<'a> {
    Block::bordered()
        .border_style(theme.border())
        .title(title.into().style(theme.title()))
}

/// How a chart is framed.
#[derive(Debug, Clone, Copy)]
pub struct ChartFrame {
    /// A full border (else only the title on the top line).
    pub border: bool,
    /// Labels under the x axis.
    pub x_labels: bool,
}

/// Draws a chart in a bordered block with both axes labelled.
pub fn draw_chart(f: &mut Frame, area: Rect, c: &ChartView, theme: &Theme) {
    draw_chart_with(
        f,
        area,
        c,
        theme,
        ChartFrame {
            border: true,
            x_labels: true,
        },
    )
}

/// Draws a chart: every series run as a line dataset (runs split at the
/// view's NaN separators), vertical markers as two-point lines, three
/// labels per axis.
pub fn draw_chart_with(f: &mut Frame, area: Rect, c: &ChartView, theme: &Theme, frame: ChartFrame) {
    if area.height < 3 || area.width < 10 {
        return;
    }
    // Marker segments need owned point pairs that outlive the datasets.
    let [y0, y1] = c.y_bounds;
    let marker_pts: Vec<[(f64, f64); 2]> =
        c.markers.iter().map(|m| [(m.x, y0), (m.x, y1)]).collect();
    let mut datasets = Vec::new();
    for (m, pts) in c.markers.iter().zip(&marker_pts) {
        let style = match m.kind {
            MarkerKind::Cursor => theme.cursor(),
            MarkerKind::Cycle => theme.marker(),
        };
        datasets.push(
            Dataset::default()
                .data(pts)
                .graph_type(GraphType::Line)
                .marker(ratatui::symbols::Marker::Braille)
                .style(style),
        );
    }
    for (i, s) in c.series.iter().enumerate() {
        let style = if s.kind == SeriesKind::Reference {
            theme.series(8)
        } else {
            theme.series(s.color)
        };
        let graph = if s.kind == SeriesKind::Points {
            GraphType::Scatter
        } else {
            GraphType::Line
        };
        for (k, run) in runs(&s.points).enumerate() {
            let mut d = Dataset::default()
                .data(run)
                .graph_type(graph)
                .marker(theme.series_marker(i))
                .style(style);
            if k == 0 && c.series.len() > 1 {
                d = d.name(s.name.clone());
            }
            datasets.push(d);
        }
    }
    let title = if c.y_label.is_empty() {
        c.title.clone()
    } else {
        format!("{} [{}]", c.title, c.y_label)
    };
    let blk = if frame.border {
        block(title, theme)
    } else {
        Block::new()
            .borders(ratatui::widgets::Borders::TOP)
            .border_style(theme.border())
            .title(Line::from(title).style(theme.title()))
    };
    let mut x_axis = Axis::default().bounds(c.x_bounds).style(theme.border());
    if frame.x_labels {
        x_axis = x_axis.labels(
            c.x_ticks
                .iter()
                .map(|t| Span::styled(t.clone(), theme.muted())),
        );
    }
    let chart = Chart::new(datasets)
        .block(blk)
        .x_axis(x_axis)
        .y_axis(
            Axis::default()
                .bounds(c.y_bounds)
                .labels(
                    c.y_ticks
                        .iter()
                        .map(|t| Span::styled(t.clone(), theme.muted())),
                )
                .style(theme.border()),
        )
        .legend_position(Some(LegendPosition::TopRight))
        .hidden_legend_constraints((Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)));
    f.render_widget(chart, area);
}

/// Horizontal bars, one line per (category, series), scaled to the largest value.
pub fn bars_lines<'a>(b: &BarsView, width: u16, theme: &Theme) -> Vec<Line<'a>> {
    let max = b.max();
    let label_w = b
        .categories
        .iter()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(0)
        .min(18);
    let value_w = 10usize;
    let bar_w = (width as usize)
        .saturating_sub(label_w + value_w + 3)
        .max(4);
    let mut lines = Vec::new();
    for (ci, cat) in b.categories.iter().enumerate() {
        for (si, (_, vals)) in b.series.iter().enumerate() {
            let v = vals.get(ci).copied().unwrap_or(f64::NAN);
            let label: String = if si == 0 {
                cat.chars().take(label_w).collect()
            } else {
                String::new()
            };
            let (bar, text) = if v.is_finite() && max > 0.0 {
                let eighths = ((v / max).clamp(0.0, 1.0) * (bar_w * 8) as f64).round() as usize;
                let full = eighths / 8;
                let rem = eighths % 8;
                let mut s = "█".repeat(full);
                if rem > 0 {
                    s.push([' ', '▏', '▎', '▍', '▌', '▋', '▊', '▉'][rem]);
                }
                (s, format_value(v))
            } else {
                (String::new(), "–".to_string())
            };
            lines.push(Line::from(vec![
                Span::raw(format!("{label:<label_w$} ")),
                Span::styled(format!("{bar:<bar_w$}"), theme.series(si)),
                Span::raw(format!(" {text:>value_w$}")),
            ]));
        }
    }
    lines
}

/// A value with 3–4 significant digits.
pub fn format_value(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else if a >= 100.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.5}")
    }
}

/// `key: value` lines with the key muted.
pub fn kv_line<'a>(k: &str, v: impl Into<String>, theme: &Theme) -> Line<'a> {
    Line::from(vec![
        Span::styled(format!("{k}: "), theme.muted()),
        Span::raw(v.into()),
    ])
}

/// A wrapped paragraph of lines in a titled block.
pub fn text_block(f: &mut Frame, area: Rect, title: &str, lines: Vec<Line>, theme: &Theme) {
    if area.height == 0 || area.width == 0 {
        return;
    }
    f.render_widget(
        Paragraph::new(lines)
            .block(block(title.to_string(), theme))
            .wrap(Wrap { trim: false }),
        area,
    );
}

/// A centred message in a block (a pane with nothing to show says why).
pub fn message(f: &mut Frame, area: Rect, title: &str, msg: &str, style: Style, theme: &Theme) {
    f.render_widget(
        Paragraph::new(vec![Line::raw(""), Line::styled(msg.to_string(), style)])
            .block(block(title.to_string(), theme))
            .centered()
            .wrap(Wrap { trim: true }),
        area,
    );
}

/// Truncates to `n` characters with an ellipsis.
pub fn trunc(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else if n <= 1 {
        s.chars().take(n).collect()
    } else {
        let mut t: String = s.chars().take(n - 1).collect();
        t.push('…');
        t
    }
}

/// Keeps the end of a path that does not fit (`…/dir/file.mcap`).
pub fn trunc_left(s: &str, n: usize) -> String {
    let c = s.chars().count();
    if c <= n {
        s.to_string()
    } else if n <= 1 {
        s.chars().skip(c - n).collect()
    } else {
        let mut t = String::from("…");
        t.extend(s.chars().skip(c - (n - 1)));
        t
    }
}
