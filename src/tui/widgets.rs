//! Drawing helpers shared by the panes: charts from [`ChartView`]s, bars
//! from [`BarsView`]s, key–value lines. They only lay out and style what
//! the view models hold.

use super::fit;
pub use super::fit::{fit as trunc, fit_path as trunc_left};
use super::theme::Theme;
use crate::panes::chart::{BarsView, ChartView, MarkerKind, SeriesKind, runs};
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Paragraph, Wrap};

/// A bordered block with a title.
pub fn block<'a>(title: impl Into<Line<'a>>, theme: &Theme) -> Block<'a> {
    Block::bordered()
        .border_style(theme.border())
        .title(title.into().style(theme.title()))
}

/// How a chart is framed.
#[derive(Debug, Clone, Copy)]
pub struct ChartFrame {
    /// A full border (else only the top line: charts stacked in one block).
    pub border: bool,
    /// Labels under the x axis (and, in a full border, the x axis title).
    pub x_labels: bool,
}

/// A legend entry: the series drawn alike (same colour and kind in a
/// row: `measured min`, `measured max`) under one label.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendEntry {
    pub label: String,
    /// The series (indexes into the chart's series) it stands for.
    pub series: Vec<usize>,
    pub style: Style,
    pub marker: Marker,
}

/// The symbol a legend shows for a marker.
pub fn marker_symbol(m: Marker) -> &'static str {
    match m {
        Marker::Dot => "•",
        Marker::Block | Marker::HalfBlock | Marker::Bar => "█",
        _ => "⣿",
    }
}

/// The label of series drawn alike: their common leading words and the
/// rest joined (`measured min` + `measured max` → `measured min–max`), or
/// their common trailing words (`+2σ noise` + `−2σ noise` → `+2σ/−2σ noise`).
fn group_label(names: &[&str]) -> String {
    let names: Vec<&str> = names.iter().copied().filter(|n| !n.is_empty()).collect();
    match names.len() {
        0 => String::new(),
        _ if names.iter().all(|n| *n == names[0]) => names[0].to_string(),
        _ => {
            let words: Vec<Vec<&str>> = names.iter().map(|n| n.split(' ').collect()).collect();
            let shortest = words.iter().map(Vec::len).min().unwrap_or(0);
            let lead = (0..shortest)
                .take_while(|&i| words.iter().all(|w| w[i] == words[0][i]))
                .count();
            let trail = (0..shortest - lead)
                .take_while(|&i| {
                    let a = words[0][words[0].len() - 1 - i];
                    words.iter().all(|w| w[w.len() - 1 - i] == a)
                })
                .count();
            let rests: Vec<String> = words
                .iter()
                .map(|w| w[lead..w.len() - trail].join(" "))
                .collect();
            if lead > 0 {
                format!("{} {}", words[0][..lead].join(" "), rests.join("–"))
            } else if trail > 0 {
                format!(
                    "{} {}",
                    rests.join("/"),
                    words[0][words[0].len() - trail..].join(" ")
                )
            } else {
                names.join(", ")
            }
        }
    }
}

/// The style a series is drawn with: its palette colour; a reference
/// curve in its colour dimmed (slot 8, the ideal mechanism: muted).
fn series_style(s: &crate::panes::chart::SeriesView, theme: &Theme) -> Style {
    match s.kind {
        SeriesKind::Reference if s.color == 8 => theme.series(8),
        SeriesKind::Reference => theme.series(s.color).add_modifier(Modifier::DIM),
        _ => theme.series(s.color),
    }
}

/// The chart's legend: one entry per run of series drawn alike; the
/// marker of entry `i` is the theme's marker `i` (without colour, the
/// marker tells the series apart, so the legend shows it).
pub fn legend(c: &ChartView, theme: &Theme) -> Vec<LegendEntry> {
    let mut out: Vec<LegendEntry> = Vec::new();
    let mut prev: Option<(usize, SeriesKind)> = None;
    let mut names: Vec<Vec<&str>> = Vec::new();
    for (i, s) in c.series.iter().enumerate() {
        let key = (s.color, s.kind);
        if prev == Some(key)
            && let Some(e) = out.last_mut()
        {
            e.series.push(i);
            if let Some(n) = names.last_mut() {
                n.push(&s.name);
            }
            continue;
        }
        prev = Some(key);
        out.push(LegendEntry {
            label: String::new(),
            series: vec![i],
            style: series_style(s, theme),
            marker: theme.series_marker(out.len()),
        });
        names.push(vec![&s.name]);
    }
    for (e, n) in out.iter_mut().zip(&names) {
        e.label = group_label(n);
    }
    out
}

/// The legend on one line of at most `w` cells (`⣿ ideal  ⣿ measured`),
/// with the labels in full or abbreviated; None when it does not fit.
fn legend_spans<'a>(entries: &[LegendEntry], w: usize) -> Option<Vec<Span<'a>>> {
    let shown: Vec<&LegendEntry> = entries.iter().filter(|e| !e.label.is_empty()).collect();
    // Full labels, then abbreviated, then compact (no space after the
    // symbol, one between entries).
    for (short, compact) in [(false, false), (true, false), (true, true)] {
        let labels: Vec<String> = shown
            .iter()
            .map(|e| {
                if short {
                    fit::abbreviate(&e.label)
                } else {
                    e.label.clone()
                }
            })
            .collect();
        let (gap, sep) = if compact { ("", " ") } else { (" ", "  ") };
        let total: usize = labels
            .iter()
            .map(|l| fit::width(l) + 1 + gap.len())
            .sum::<usize>()
            + sep.len() * labels.len().saturating_sub(1);
        if total <= w {
            let mut spans = Vec::new();
            for (i, (e, l)) in shown.iter().zip(labels).enumerate() {
                if i > 0 {
                    spans.push(Span::raw(sep));
                }
                spans.push(Span::styled(marker_symbol(e.marker), e.style));
                spans.push(Span::raw(format!("{gap}{l}")));
            }
            return Some(spans);
        }
    }
    None
}

/// The legend wrapped over as many lines of `w` cells as it needs.
fn legend_lines<'a>(entries: &[LegendEntry], w: usize) -> Vec<Line<'a>> {
    let mut lines = Vec::new();
    let mut cur: Vec<Span> = Vec::new();
    let mut used = 0usize;
    for e in entries.iter().filter(|e| !e.label.is_empty()) {
        let label = fit::fit(&e.label, w.saturating_sub(2).max(1));
        let ew = fit::width(&label) + 2;
        if used > 0 && used + 2 + ew > w {
            lines.push(Line::from(std::mem::take(&mut cur)));
            used = 0;
        }
        if used > 0 {
            cur.push(Span::raw("  "));
            used += 2;
        }
        cur.push(Span::styled(marker_symbol(e.marker), e.style));
        cur.push(Span::raw(format!(" {label}")));
        used += ew;
    }
    if !cur.is_empty() {
        lines.push(Line::from(cur));
    }
    lines
}

/// The text of a chart's top line: the y axis title (with its unit) and
/// the chart's title. When the title starts with the quantity the y axis
/// names (`stroke — envelope …` over `stroke (mm)`), the two merge
/// (`stroke (mm) — envelope …`); else the title follows after ` · `.
/// The y axis title is kept whole as long as it fits.
pub fn chart_heading(c: &ChartView, w: usize) -> (String, String) {
    let y = c.y_label.trim();
    if y.is_empty() {
        return (String::new(), fit::fit(&c.title, w));
    }
    let (quantity, unit) = match y.rsplit_once(" (") {
        Some((q, u)) => (q, format!("({u}")),
        None => (y, String::new()),
    };
    match c.title.strip_prefix(quantity) {
        // Merged: fitted as one text (its asides go before the unit does),
        // split after the unit for the styles.
        Some(r) if r.starts_with(' ') || r.is_empty() => {
            let text = fit::fit(&format!("{y}{r}"), w);
            match text.find(&unit).filter(|_| !unit.is_empty()) {
                Some(i) => {
                    let end = i + unit.len();
                    (text[..end].to_string(), text[end..].to_string())
                }
                None => (text, String::new()),
            }
        }
        _ => {
            let y_fit = fit::fit_axis(y, w);
            let room = w.saturating_sub(fit::width(&y_fit) + 3);
            if c.title.is_empty() || room < 6 {
                return (y_fit, String::new());
            }
            let t = fit::fit(&c.title, room);
            if t == "…" || t.is_empty() {
                (y_fit, String::new())
            } else {
                (y_fit, format!(" · {t}"))
            }
        }
    }
}

/// Draws a chart in a bordered block (y axis title on the top border,
/// x axis title and legend on the bottom border, three labels per axis).
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
/// labels per axis. Titles and legend stay off the data: the y axis title
/// (with its unit) and the chart's title on the top line, the x axis title
/// (with its unit) right on the bottom border, the legend left on the
/// bottom border when it fits there (else on its own lines above the
/// plot; on a top-line-only frame, right on the top line when it fits).
pub fn draw_chart_with(f: &mut Frame, area: Rect, c: &ChartView, theme: &Theme, frame: ChartFrame) {
    if area.height < 3 || area.width < 10 {
        return;
    }
    let w = area.width.saturating_sub(2) as usize;
    let entries = legend(c, theme);
    let show_legend = entries.iter().filter(|e| !e.label.is_empty()).count() > 1;
    let (y_title, rest) = chart_heading(c, w);
    let mut top = vec![Span::styled(y_title.clone(), theme.header())];
    if !rest.is_empty() {
        top.push(Span::styled(rest.clone(), theme.title()));
    }
    let mut legend_inside: Vec<Line> = Vec::new();
    let blk = if frame.border {
        let mut b = Block::bordered()
            .border_style(theme.border())
            .title(Line::from(top));
        let x_title = if frame.x_labels && !c.x_label.is_empty() {
            fit::fit_axis(&c.x_label, w)
        } else {
            String::new()
        };
        let room = w.saturating_sub(fit::width(&x_title) + usize::from(!x_title.is_empty()));
        if !x_title.is_empty() {
            b = b.title_bottom(Line::styled(x_title, theme.header()).right_aligned());
        }
        if show_legend {
            match legend_spans(&entries, room) {
                Some(spans) => b = b.title_bottom(Line::from(spans).left_aligned()),
                None => legend_inside = legend_lines(&entries, w),
            }
        }
        b
    } else {
        let used = fit::width(&y_title) + fit::width(&rest);
        let mut b = Block::new()
            .borders(ratatui::widgets::Borders::TOP)
            .border_style(theme.border())
            .title(Line::from(top));
        if show_legend {
            match legend_spans(&entries, w.saturating_sub(used + 2)) {
                Some(spans) => b = b.title(Line::from(spans).right_aligned()),
                None => legend_inside = legend_lines(&entries, area.width as usize),
            }
        }
        b
    };
    let inner = blk.inner(area);
    f.render_widget(blk, area);
    // Legend lines that did not fit a frame line: above the plot, and only
    // when the plot keeps at least three rows.
    let n_leg = (legend_inside.len() as u16).min(inner.height.saturating_sub(3));
    let [leg_area, plot_area] =
        Layout::vertical([Constraint::Length(n_leg), Constraint::Min(1)]).areas(inner);
    if n_leg > 0 {
        f.render_widget(Paragraph::new(legend_inside), leg_area);
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
                .marker(Marker::Braille)
                .style(style),
        );
    }
    for e in &entries {
        for &i in &e.series {
            let s = &c.series[i];
            let graph = if s.kind == SeriesKind::Points {
                GraphType::Scatter
            } else {
                GraphType::Line
            };
            for run in runs(&s.points) {
                datasets.push(
                    Dataset::default()
                        .data(run)
                        .graph_type(graph)
                        .marker(e.marker)
                        .style(e.style),
                );
            }
        }
    }
    let mut x_axis = Axis::default().bounds(c.x_bounds).style(theme.border());
    if frame.x_labels {
        x_axis = x_axis.labels(
            c.x_ticks
                .iter()
                .map(|t| Span::styled(t.clone(), theme.muted())),
        );
    }
    let chart = Chart::new(datasets)
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
        .legend_position(None);
    f.render_widget(chart, plot_area);
}

/// The unit of an axis title `quantity (unit)` (empty when it has none).
pub fn unit_of(label: &str) -> &str {
    label
        .rsplit_once(" (")
        .and_then(|(_, u)| u.strip_suffix(')'))
        .unwrap_or("")
}

/// Horizontal bars, one line per (category, series), scaled to the
/// largest value; each value followed by the unit of the bars' axis.
pub fn bars_lines<'a>(b: &BarsView, width: u16, theme: &Theme) -> Vec<Line<'a>> {
    let max = b.max();
    let unit = unit_of(&b.y_label);
    let texts: Vec<Vec<String>> = b
        .series
        .iter()
        .map(|(_, vals)| {
            (0..b.categories.len())
                .map(|ci| {
                    let v = vals.get(ci).copied().unwrap_or(f64::NAN);
                    match (v.is_finite(), unit.is_empty()) {
                        (false, _) => "–".to_string(),
                        (true, true) => format_value(v),
                        (true, false) => format!("{} {unit}", format_value(v)),
                    }
                })
                .collect()
        })
        .collect();
    let value_w = texts
        .iter()
        .flatten()
        .map(|t| fit::width(t))
        .max()
        .unwrap_or(1);
    let label_w = b
        .categories
        .iter()
        .map(|c| fit::width(c))
        .max()
        .unwrap_or(0)
        .min(18)
        .min((width as usize).saturating_sub(value_w + 6));
    let bar_w = (width as usize)
        .saturating_sub(label_w + value_w + 2)
        .max(4);
    let mut lines = Vec::new();
    for (ci, cat) in b.categories.iter().enumerate() {
        for (si, (_, vals)) in b.series.iter().enumerate() {
            let v = vals.get(ci).copied().unwrap_or(f64::NAN);
            let label: String = if si == 0 {
                fit::fit(cat, label_w)
            } else {
                String::new()
            };
            let bar = if v.is_finite() && max > 0.0 {
                let eighths = ((v / max).clamp(0.0, 1.0) * (bar_w * 8) as f64).round() as usize;
                let full = eighths / 8;
                let rem = eighths % 8;
                let mut s = "█".repeat(full);
                if rem > 0 {
                    s.push([' ', '▏', '▎', '▍', '▌', '▋', '▊', '▉'][rem]);
                }
                s
            } else {
                String::new()
            };
            let text = &texts[si][ci];
            let pad = label_w.saturating_sub(fit::width(&label));
            let bar_pad = bar_w.saturating_sub(fit::width(&bar));
            lines.push(Line::from(vec![
                Span::raw(format!("{label}{} ", " ".repeat(pad))),
                Span::styled(format!("{bar}{}", " ".repeat(bar_pad)), theme.series(si)),
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

/// A bordered block whose title is fitted to `area` (never cut mid-word).
pub fn block_in<'a>(area: Rect, title: &str, theme: &Theme) -> Block<'a> {
    block(
        fit::fit(title, area.width.saturating_sub(2) as usize),
        theme,
    )
}

/// A wrapped paragraph of lines in a titled block.
pub fn text_block(f: &mut Frame, area: Rect, title: &str, lines: Vec<Line>, theme: &Theme) {
    if area.height == 0 || area.width == 0 {
        return;
    }
    f.render_widget(
        Paragraph::new(lines)
            .block(block_in(area, title, theme))
            .wrap(Wrap { trim: false }),
        area,
    );
}

/// How a table column takes its width ([`column_widths`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Col {
    /// Exactly this many cells.
    Fixed(u16),
    /// As wide as its widest cell (header included), within `min..=max`.
    Auto(u16, u16),
    /// What is left, at least this many cells.
    Fill(u16),
}

/// Widths of table columns (one cell of spacing between columns, as
/// ratatui's `Table` draws) in `inner` cells; `content[i]` is the widest
/// cell of column `i`. When the fill columns would get less than their
/// minimum, the auto columns give way (widest first) down to their minimum.
pub fn column_widths(inner: u16, cols: &[Col], content: &[usize]) -> Vec<u16> {
    let mut w: Vec<u16> = cols
        .iter()
        .enumerate()
        .map(|(i, c)| match *c {
            Col::Fixed(n) => n,
            Col::Auto(lo, hi) => (content.get(i).copied().unwrap_or(0) as u16).clamp(lo, hi),
            Col::Fill(_) => 0,
        })
        .collect();
    let spacing = cols.len().saturating_sub(1) as u16;
    let fill_min: u16 = cols
        .iter()
        .map(|c| if let Col::Fill(m) = c { *m } else { 0 })
        .sum();
    let fixed: u16 = w.iter().sum();
    let mut over = (fixed + spacing + fill_min).saturating_sub(inner);
    while over > 0 {
        // The widest auto column above its minimum gives one cell.
        let Some(i) = (0..cols.len())
            .filter(|&i| matches!(cols[i], Col::Auto(lo, _) if w[i] > lo))
            .max_by_key(|&i| w[i])
        else {
            break;
        };
        w[i] -= 1;
        over -= 1;
    }
    let used: u16 = w.iter().sum::<u16>() + spacing;
    let mut left = inner.saturating_sub(used);
    // Each fill column gets its minimum, the last one the rest.
    let fills: Vec<usize> = (0..cols.len())
        .filter(|&i| matches!(cols[i], Col::Fill(_)))
        .collect();
    for &i in &fills {
        if let Col::Fill(m) = cols[i] {
            w[i] = m.min(left);
            left -= w[i];
        }
    }
    if let Some(&last) = fills.last() {
        w[last] += left;
    }
    w
}

/// The widest cell of each column (header included).
pub fn content_widths(header: &[&str], rows: &[Vec<String>]) -> Vec<usize> {
    (0..header.len())
        .map(|i| {
            rows.iter()
                .filter_map(|r| r.get(i))
                .map(|c| fit::width(c))
                .chain(std::iter::once(fit::width(header[i])))
                .max()
                .unwrap_or(0)
        })
        .collect()
}

/// Widths as table constraints.
pub fn lengths(widths: &[u16]) -> Vec<Constraint> {
    widths.iter().map(|w| Constraint::Length(*w)).collect()
}

/// A table of plain text in a block `area_width` wide: columns sized by
/// `cols` and their content, every cell cut to its column, the header
/// fitted. The caller adds the block (and a highlight when it selects).
pub fn text_table<'a>(
    area_width: u16,
    header: &[&str],
    cells: &[Vec<String>],
    cols: &[Col],
    theme: &Theme,
) -> ratatui::widgets::Table<'a> {
    let widths = column_widths(
        area_width.saturating_sub(2),
        cols,
        &content_widths(header, cells),
    );
    let rows: Vec<ratatui::widgets::Row> = cells
        .iter()
        .map(|r| {
            ratatui::widgets::Row::new(
                r.iter()
                    .zip(&widths)
                    .map(|(c, w)| trunc(c, *w as usize))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    ratatui::widgets::Table::new(rows, lengths(&widths)).header(header_row(header, &widths, theme))
}

/// A header row with every name fitted to its column.
pub fn header_row<'a>(names: &[&str], widths: &[u16], theme: &Theme) -> ratatui::widgets::Row<'a> {
    ratatui::widgets::Row::new(
        names
            .iter()
            .zip(widths)
            .map(|(n, w)| fit::fit(n, *w as usize))
            .collect::<Vec<_>>(),
    )
    .style(theme.header())
}

/// A centred message in a block (a pane with nothing to show says why).
pub fn message(f: &mut Frame, area: Rect, title: &str, msg: &str, style: Style, theme: &Theme) {
    f.render_widget(
        Paragraph::new(vec![Line::raw(""), Line::styled(msg.to_string(), style)])
            .block(block_in(area, title, theme))
            .centered()
            .wrap(Wrap { trim: true }),
        area,
    );
}
