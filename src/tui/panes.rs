//! Drawing of each pane's view model. Layout and styling only: every
//! number shown was computed by the pane's view function.

use super::image_cache::ImageCache;
use super::theme::Theme;
use super::widgets::{
    ChartFrame, bars_lines, block, draw_chart, draw_chart_with, format_value, kv_line, message,
    text_block, trunc, trunc_left,
};
use crate::panes::PaneView;
use crate::panes::methods::MethodsView;
use crate::panes::model::ModelView;
use crate::panes::overlay::OverlayView;
use crate::panes::session_pane::SessionView;
use crate::panes::signals::{SIDE_COLS, SignalsView};
use crate::panes::study::StudyView;
use crate::panes::vision::VisionView;
use crate::panes::yields::YieldView;
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Cell, Paragraph, Row, Table, TableState, Wrap};

/// Draws a pane's view into `area`.
pub fn draw_pane(f: &mut Frame, area: Rect, view: &PaneView, theme: &Theme, img: &mut ImageCache) {
    match view {
        PaneView::Session(v) => session(f, area, v, theme),
        PaneView::Signals(v) => signals(f, area, v, theme),
        PaneView::Overlay(v) => overlay(f, area, v, theme),
        PaneView::Model(v) => model(f, area, v, theme),
        PaneView::Study(v) => study(f, area, v, theme),
        PaneView::Vision(v) => vision(f, area, v, theme, img),
        PaneView::Yield(v) => yields(f, area, v, theme),
        PaneView::Methods(v) => methods(f, area, v, theme),
    }
}

fn fmt_s(t: f64) -> String {
    format!("{t:.4} s")
}

fn opt(x: Option<f64>) -> String {
    x.map(format_value).unwrap_or_else(|| "–".into())
}

// ---------------------------------------------------------------- Session

fn session(f: &mut Frame, area: Rect, v: &SessionView, theme: &Theme) {
    let err_h = if v.errors.is_empty() {
        0
    } else {
        (v.errors.len() as u16 + 2).min(area.height / 3).max(3)
    };
    let [head, main, errs] = Layout::vertical([
        Constraint::Length(5),
        Constraint::Min(4),
        Constraint::Length(err_h),
    ])
    .areas(area);
    let head_lines = vec![
        Line::from(Span::styled(v.title.clone(), theme.header())),
        kv_line(
            "parameters",
            if v.params_source.starts_with("preset ") {
                format!("{}, level {}", v.params_source, v.level)
            } else {
                format!(
                    "{} (preset {}), level {}",
                    v.params_source, v.preset, v.level
                )
            },
            theme,
        ),
        kv_line(
            "in force",
            v.params
                .iter()
                .map(|(k, x)| format!("{k} {x}"))
                .collect::<Vec<_>>()
                .join(", "),
            theme,
        ),
    ];
    let mut head_lines = head_lines;
    head_lines.push(Line::styled(
        v.model_status.clone(),
        if v.model_status.contains("failed") {
            theme.error()
        } else {
            theme.base()
        },
    ));
    f.render_widget(Paragraph::new(head_lines).wrap(Wrap { trim: false }), head);
    let wide = main.width >= 100;
    let [files_area, detail_area] = if wide {
        Layout::horizontal([Constraint::Percentage(60), Constraint::Percentage(40)]).areas(main)
    } else {
        Layout::vertical([Constraint::Percentage(55), Constraint::Percentage(45)]).areas(main)
    };
    // Files table.
    if v.files.is_empty() {
        message(
            f,
            files_area,
            "Files",
            "no files opened (o opens logs, images, recipes, parameter files)",
            theme.muted(),
            theme,
        );
    } else {
        let path_w = (files_area.width as usize).saturating_sub(24).max(12);
        let rows: Vec<Row> = v
            .files
            .iter()
            .map(|r| {
                let what = if r.message.is_empty() {
                    r.detail.clone()
                } else {
                    r.message.clone()
                };
                Row::new(vec![
                    Cell::from(Span::styled(r.status.clone(), theme.status(&r.status))),
                    Cell::from(r.kind.clone()),
                    Cell::from(Line::from(vec![
                        Span::raw(trunc_left(&r.path, path_w)),
                        Span::styled(format!("  {what}"), theme.muted()),
                    ])),
                ])
            })
            .collect();
        let table = Table::new(
            rows,
            [
                Constraint::Length(7),
                Constraint::Length(10),
                Constraint::Min(10),
            ],
        )
        .header(Row::new(vec!["status", "kind", "file"]).style(theme.header()))
        .row_highlight_style(theme.selected())
        .block(block(format!("Files ({})", v.files.len()), theme));
        let mut st = TableState::default().with_selected(Some(v.selected));
        f.render_stateful_widget(table, files_area, &mut st);
    }
    // Details: display, the selected file's findings, logs' metadata,
    // recipes, images.
    let mut lines = Vec::new();
    if let Some(d) = &v.display {
        lines.push(kv_line("display", d.clone(), theme));
    }
    lines.push(kv_line(
        "images",
        format!("{}, recipes {}", v.images, v.recipes.len()),
        theme,
    ));
    if let Some(sel) = v.files.get(v.selected) {
        if !sel.message.is_empty() {
            // One line per finding (the selected file's warnings or error).
            let w = detail_area.width.saturating_sub(4) as usize;
            lines.push(Line::from(vec![
                Span::styled(format!("{} ", sel.status), theme.status(&sel.status)),
                Span::raw(trunc_left(&sel.path, w.saturating_sub(8))),
            ]));
            for m in sel.message.split(crate::panes::session::FINDING_SEP) {
                lines.push(Line::styled(format!("  {}", trunc(m, w)), theme.muted()));
            }
        }
    }
    for l in &v.logs {
        lines.push(Line::styled(trunc_left(&l.path, 60), theme.header()));
        lines.push(kv_line(
            "duration",
            format!("{:.3} s, {} cycles", l.duration_s, l.cycles),
            theme,
        ));
        for (k, x) in &l.meta {
            lines.push(kv_line(k, x.clone(), theme));
        }
        lines.push(kv_line("channels", l.channels.join(", "), theme));
    }
    if !v.recipes.is_empty() {
        lines.push(Line::styled("recipes", theme.header()));
        for r in &v.recipes {
            lines.push(Line::raw(format!("  {r}")));
        }
    }
    text_block(f, detail_area, "Metadata", lines, theme);
    if err_h > 0 {
        let lines: Vec<Line> = v
            .errors
            .iter()
            .map(|(file, msg)| {
                Line::from(vec![
                    Span::styled(format!("{file}: "), theme.error()),
                    Span::raw(msg.clone()),
                ])
            })
            .collect();
        f.render_widget(
            Paragraph::new(lines)
                .block(block(format!("Load errors ({})", v.errors.len()), theme))
                .wrap(Wrap { trim: false }),
            errs,
        );
    }
}

// ---------------------------------------------------------------- Signals

fn signals(f: &mut Frame, area: Rect, v: &SignalsView, theme: &Theme) {
    if let (Some(msg), true) = (&v.message, v.channels.is_empty()) {
        message(f, area, "Signals", msg, theme.muted(), theme);
        return;
    }
    let side_w = SIDE_COLS.min(area.width / 2);
    let [side, charts] =
        Layout::horizontal([Constraint::Length(side_w), Constraint::Min(10)]).areas(area);
    let w = side_w.saturating_sub(2) as usize;
    let mut lines = vec![
        Line::styled(trunc(&v.source, w), theme.muted()),
        kv_line(
            "window",
            format!("{:.3}–{:.3} s", v.window[0], v.window[1]),
            theme,
        ),
        kv_line("cursor", fmt_s(v.cursor), theme),
        kv_line(
            "cycle",
            match v.cycle_at_cursor {
                Some(k) => format!("{k} ({}/{} in view)", v.cycles_in_view, v.cycles_total),
                None => format!("– ({} starts)", v.cycles_total),
            },
            theme,
        ),
        Line::raw(""),
    ];
    for c in &v.channels {
        let check = if c.visible { "[x]" } else { "[ ]" };
        let style = if c.selected {
            theme.selected()
        } else if c.visible {
            theme.base()
        } else {
            theme.muted()
        };
        lines.push(Line::from(vec![Span::styled(
            trunc(&format!("{check} {} ({})", c.name, c.unit), w),
            style,
        )]));
        lines.push(Line::styled(
            trunc(
                &format!("    {} [{} … {}]", opt(c.at_cursor), opt(c.min), opt(c.max)),
                w,
            ),
            theme.muted(),
        ));
    }
    text_block(f, side, "Channels", lines, theme);
    if v.charts.is_empty() {
        message(
            f,
            charts,
            "Signals",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    }
    // Stacked charts share the time axis: only the last one labels it.
    let n = v.charts.len() as u32;
    let b = block("", theme);
    let inner = b.inner(charts);
    f.render_widget(b, charts);
    let rows = Layout::vertical(v.charts.iter().map(|_| Constraint::Ratio(1, n))).split(inner);
    for (i, (c, r)) in v.charts.iter().zip(rows.iter()).enumerate() {
        draw_chart_with(
            f,
            *r,
            c,
            theme,
            ChartFrame {
                border: false,
                x_labels: i + 1 == v.charts.len(),
            },
        );
    }
}

// ---------------------------------------------------------------- Overlay

fn overlay(f: &mut Frame, area: Rect, v: &OverlayView, theme: &Theme) {
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(62), Constraint::Percentage(38)]).areas(area);
    let charts = v.charts();
    if charts.is_empty() {
        message(
            f,
            left,
            "Overlay",
            v.message.as_deref().unwrap_or("nothing to show"),
            theme.muted(),
            theme,
        );
    } else {
        let n = charts.len() as u32;
        let rows = Layout::vertical(charts.iter().map(|_| Constraint::Ratio(1, n))).split(left);
        for (c, r) in charts.iter().zip(rows.iter()) {
            draw_chart(f, *r, c, theme);
        }
    }
    let mut lines = Vec::new();
    if let Some(s) = &v.source {
        lines.push(kv_line("log", s.clone(), theme));
    }
    lines.push(kv_line("showing", v.showing.clone(), theme));
    lines.push(kv_line(
        "level",
        v.level.clone().unwrap_or_else(|| "–".into()),
        theme,
    ));
    if let Some(r) = &v.level_reason {
        lines.push(Line::styled(format!("  why: {r}"), theme.muted()));
    }
    for (k, x) in &v.figures {
        let shown = if x.fract() == 0.0 && x.abs() < 1e9 {
            format!("{x:.0}")
        } else {
            format_value(*x)
        };
        lines.push(kv_line(k, shown, theme));
    }
    if let Some(m) = &v.message {
        lines.push(Line::raw(""));
        lines.push(Line::styled(m.clone(), theme.warn()));
    }
    let table_h = if v.cycles.is_empty() {
        0
    } else {
        (v.cycles.len() as u16 + 3).min(side.height / 2)
    };
    let [info, table_area] =
        Layout::vertical([Constraint::Min(4), Constraint::Length(table_h)]).areas(side);
    text_block(f, info, "Fidelity and figures", lines, theme);
    if table_h > 0 {
        let rows: Vec<Row> = v
            .cycles
            .iter()
            .map(|c| {
                Row::new(vec![
                    c.index.to_string(),
                    opt(c.stroke_rms_mm),
                    opt(c.force_rms_n),
                    c.note.clone(),
                ])
            })
            .collect();
        let t = Table::new(
            rows,
            [
                Constraint::Length(6),
                Constraint::Length(9),
                Constraint::Length(9),
                Constraint::Min(4),
            ],
        )
        .header(Row::new(vec!["cycle", "RMS s mm", "RMS F N", "note"]).style(theme.header()))
        .row_highlight_style(theme.selected())
        .block(block("Cycles", theme));
        let mut st = TableState::default().with_selected(v.selected);
        f.render_stateful_widget(t, table_area, &mut st);
    }
}

// ---------------------------------------------------------------- Model

fn model(f: &mut Frame, area: Rect, v: &ModelView, theme: &Theme) {
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(58), Constraint::Percentage(42)]).areas(area);
    let [table_area, edit_area] =
        Layout::vertical([Constraint::Min(5), Constraint::Length(4)]).areas(left);
    let key_w = 22u16.min(table_area.width / 3);
    let val_w = 16u16.min(table_area.width / 4);
    let rows: Vec<Row> = v
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let value = if i == v.selected {
                match &v.editing {
                    Some(t) => format!("{t}▏"),
                    None => r.value.clone(),
                }
            } else {
                r.value.clone()
            };
            let vstyle = if r.changed {
                theme.warn()
            } else {
                theme.base()
            };
            Row::new(vec![
                Cell::from(r.key.clone()),
                Cell::from(Span::styled(value, vstyle)),
                Cell::from(Span::styled(r.range.clone(), theme.muted())),
            ])
        })
        .collect();
    let title = format!("Parameters — preset {} ({})", v.preset, v.params_source);
    let t = Table::new(
        rows,
        [
            Constraint::Length(key_w),
            Constraint::Length(val_w),
            Constraint::Min(6),
        ],
    )
    .header(Row::new(vec!["key", "value", "allowed"]).style(theme.header()))
    .row_highlight_style(theme.selected())
    .block(block(title, theme));
    let mut st = TableState::default().with_selected(Some(v.selected));
    f.render_stateful_widget(t, table_area, &mut st);
    // Edit line: what is being edited, the error of the last edit, or help.
    let sel = v.rows.get(v.selected);
    let mut lines = Vec::new();
    if let Some(e) = &v.error {
        lines.push(Line::styled(format!("✗ {e}"), theme.error()));
    } else if let Some(n) = &v.notice {
        lines.push(Line::styled(n.clone(), theme.ok()));
    }
    if let Some(r) = sel {
        lines.push(Line::from(vec![
            Span::styled(format!("{}: ", r.key), theme.key()),
            Span::raw(format!("{} [{}]", r.help, r.range)),
        ]));
    }
    let edit_title = if v.editing.is_some() {
        "Editing — Enter applies, Esc cancels"
    } else {
        "Enter edits the selected value"
    };
    f.render_widget(
        Paragraph::new(lines)
            .block(block(edit_title, theme))
            .wrap(Wrap { trim: false }),
        edit_area,
    );
    // Side: level, figures, fidelity, chart.
    let mut lines = Vec::new();
    let state = if let Some(e) = &v.run_error {
        Span::styled(format!("run failed: {e}"), theme.error())
    } else if v.summary.is_none() {
        Span::styled("not run yet", theme.muted())
    } else if v.up_to_date {
        Span::styled("up to date", theme.ok())
    } else {
        Span::styled("re-run pending (r)", theme.warn())
    };
    lines.push(Line::from(vec![
        Span::styled("run: ", theme.muted()),
        state,
    ]));
    lines.push(kv_line(
        "level",
        format!(
            "{} (asked: {})",
            v.level.clone().unwrap_or_else(|| "–".into()),
            v.level_choice
        ),
        theme,
    ));
    if let Some(r) = &v.level_reason {
        lines.push(Line::styled(format!("  why: {r}"), theme.muted()));
    }
    if let Some(fv) = &v.fidelity {
        lines.push(kv_line(
            "scene needs",
            format!("{} — {}", fv.recommended, fv.reason),
            theme,
        ));
    }
    for n in &v.notes {
        lines.push(Line::styled(format!("note: {n}"), theme.muted()));
    }
    let fig_h = if v.figures.is_empty() {
        0
    } else {
        v.figures.len() as u16 + 3
    };
    let side_chart = v.chart.is_some() && side.height >= fig_h + 20;
    let chart_h = if side_chart { side.height / 3 } else { 0 };
    let [info, figs, chart_area] = Layout::vertical([
        Constraint::Min(4),
        Constraint::Length(fig_h),
        Constraint::Length(chart_h),
    ])
    .areas(side);
    text_block(f, info, "Run", lines, theme);
    if fig_h > 0 {
        let rows: Vec<Row> = v
            .figures
            .iter()
            .map(|r| Row::new(vec![r.figure.clone(), r.value.clone(), r.ideal.clone()]))
            .collect();
        let t = Table::new(
            rows,
            [
                Constraint::Min(12),
                Constraint::Length(10),
                Constraint::Length(8),
            ],
        )
        .header(Row::new(vec!["figure", "value", "ideal"]).style(theme.header()))
        .block(block("Summary (reported revolutions)", theme));
        f.render_widget(t, figs);
    }
    if let (true, Some(c)) = (side_chart, &v.chart) {
        draw_chart(f, chart_area, c, theme);
    }
}

// ---------------------------------------------------------------- Study

fn study(f: &mut Frame, area: Rect, v: &StudyView, theme: &Theme) {
    let [head, body] = Layout::vertical([Constraint::Length(2), Constraint::Min(4)]).areas(area);
    let mut l1 = vec![
        Span::styled("factor ", theme.muted()),
        Span::styled(v.factor.clone(), theme.key()),
        Span::styled("  quantity ", theme.muted()),
        Span::styled(v.quantity.clone(), theme.key()),
        Span::styled(
            format!(
                "  {} cases{}",
                v.cases_total,
                if v.cases_failed > 0 {
                    format!(", {} failed", v.cases_failed)
                } else {
                    String::new()
                }
            ),
            theme.muted(),
        ),
    ];
    if let Some(n) = &v.nominal {
        l1.push(Span::styled(format!("  {n}"), theme.muted()));
    }
    f.render_widget(
        Paragraph::new(vec![
            Line::from(l1),
            Line::styled(v.setup.clone(), theme.muted()),
        ]),
        head,
    );
    if !v.ran {
        let msg = match &v.error {
            Some(e) => e.clone(),
            None => v.message.clone().unwrap_or_default(),
        };
        message(f, body, "Study", &msg, theme.muted(), theme);
        return;
    }
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(60), Constraint::Percentage(40)]).areas(body);
    match &v.curves {
        Some(c) => draw_chart(f, left, c, theme),
        None => message(f, left, "Curves", "no curves", theme.muted(), theme),
    }
    let n = v.bars.len().max(1) as u32;
    let cells = Layout::vertical(v.bars.iter().map(|_| Constraint::Ratio(1, n))).split(side);
    for (b, r) in v.bars.iter().zip(cells.iter()) {
        let lines = bars_lines(b, r.width.saturating_sub(2), theme);
        text_block(f, *r, &b.title, lines, theme);
    }
}

// ---------------------------------------------------------------- Vision

fn vision(f: &mut Frame, area: Rect, v: &VisionView, theme: &Theme, img: &mut ImageCache) {
    if v.images == 0 {
        message(
            f,
            area,
            "Vision",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    }
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(55), Constraint::Percentage(45)]).areas(area);
    let title = format!(
        "{} ({}/{})",
        v.name.clone().unwrap_or_default(),
        v.index + 1,
        v.images
    );
    let b = block(
        trunc_left(&title, left.width.saturating_sub(4) as usize),
        theme,
    );
    let inner = b.inner(left);
    f.render_widget(b, left);
    img.draw(f, inner, v.image.as_ref(), theme);
    let mut lines = Vec::new();
    if let Some(vd) = &v.verdict {
        lines.push(Line::from(vec![
            Span::styled("verdict: ", theme.muted()),
            Span::styled(
                vd.to_uppercase(),
                theme.status(vd).add_modifier(Modifier::BOLD),
            ),
            Span::raw(match (&v.counts, v.extras) {
                (Some(c), 0) => format!("  {c}"),
                (Some(c), x) => format!("  {c}, {x} extra"),
                _ => String::new(),
            }),
        ]));
    }
    if let Some(e) = &v.error {
        lines.push(Line::styled(e.clone(), theme.error()));
    }
    if let Some((w, h)) = v.size {
        lines.push(kv_line("image", format!("{w}×{h} px"), theme));
    }
    if let Some(r) = &v.recipe {
        lines.push(kv_line("recipe", r.clone(), theme));
    }
    if let Some(g) = &v.grid {
        lines.push(kv_line("grid", g.clone(), theme));
    }
    for w in &v.warnings {
        lines.push(Line::styled(format!("! {w}"), theme.warn()));
    }
    if let Some(m) = &v.message {
        lines.push(Line::styled(m.clone(), theme.warn()));
    }
    // Rows the lines take once wrapped (a long note wraps onto several).
    let inner_w = side.width.saturating_sub(2).max(1) as usize;
    let rows: usize = lines
        .iter()
        .map(|l| l.width().div_ceil(inner_w).max(1))
        .sum();
    let info_h = (rows as u16 + 2).min(side.height / 2).max(3);
    let [info, table_area] =
        Layout::vertical([Constraint::Length(info_h), Constraint::Min(3)]).areas(side);
    let p = Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(block("Inspection", theme));
    f.render_widget(p, info);
    if !v.pins.is_empty() {
        let side_view = v.pins.iter().any(|p| p.height_mm.is_some());
        let rows: Vec<Row> = v
            .pins
            .iter()
            .map(|p| {
                Row::new(vec![
                    Cell::from(format!("{},{}", p.row, p.col)),
                    Cell::from(Span::styled(p.status.clone(), theme.status(&p.status))),
                    Cell::from(opt3(p.dx_mm)),
                    Cell::from(opt3(p.dy_mm)),
                    Cell::from(if side_view {
                        p.height_mm
                            .filter(|x| x.is_finite())
                            .map_or("–".into(), |x| format!("{x:.3}"))
                    } else {
                        p.area_ratio
                            .filter(|x| x.is_finite())
                            .map_or("–".into(), |x| format!("{x:.3}"))
                    }),
                ])
            })
            .collect();
        let t = Table::new(
            rows,
            [
                Constraint::Length(5),
                Constraint::Length(8),
                Constraint::Length(7),
                Constraint::Length(7),
                Constraint::Min(5),
            ],
        )
        .header(
            Row::new(vec![
                "pin",
                "status",
                "dx mm",
                "dy mm",
                if side_view { "h mm" } else { "area" },
            ])
            .style(theme.header()),
        )
        .row_highlight_style(theme.selected())
        .block(block(format!("Pins ({})", v.pins.len()), theme));
        let mut st = TableState::default().with_selected(Some(v.selected));
        f.render_stateful_widget(t, table_area, &mut st);
    }
}

fn opt3(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:+.3}"),
        _ => "–".into(),
    }
}

// ---------------------------------------------------------------- Yield, Methods

fn yields(f: &mut Frame, area: Rect, v: &YieldView, theme: &Theme) {
    let Some(r) = &v.report else {
        message(
            f,
            area,
            "Yield",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    };
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(area);
    let pct = |x: f64| format!("{:.1} %", 100.0 * x);
    let mut lines = vec![Line::from(vec![
        Span::styled("yield ", theme.muted()),
        Span::styled(
            r.yield_frac.map(pct).unwrap_or_else(|| "–".into()),
            theme.header(),
        ),
        Span::raw(format!(
            "  95 % CI {}–{} (Wilson)",
            pct(r.ci95.0),
            pct(r.ci95.1)
        )),
    ])];
    lines.push(kv_line(
        "connectors",
        format!(
            "{} inspected: {} pass, {} fail; {} error(s)",
            r.inspected, r.passed, r.failed, r.errors
        ),
        theme,
    ));
    lines.push(kv_line(
        "DPPM",
        match r.dppm {
            Some(d) => format!(
                "{d:.0} ({} of {} pins; CI {:.0}–{:.0})",
                r.defective_pins, r.pins_inspected, r.dppm_ci95.0, r.dppm_ci95.1
            ),
            None => "–".into(),
        },
        theme,
    ));
    if r.extras > 0 {
        lines.push(kv_line(
            "extras",
            format!("{} on {} connector(s)", r.extras, r.connectors_with_extras),
            theme,
        ));
    }
    if let Some(m) = &v.message {
        lines.push(Line::styled(m.clone(), theme.warn()));
    }
    lines.push(Line::styled("Pareto of defects", theme.header()));
    let w = left.width.saturating_sub(24).max(4) as usize;
    let maxc = r.pareto.iter().map(|p| p.count).max().unwrap_or(1).max(1);
    for p in &r.pareto {
        let n = (p.count as usize * w).div_ceil(maxc as usize);
        lines.push(Line::from(vec![
            Span::styled(format!("{:<8}", p.kind), theme.status(&p.kind)),
            Span::raw(format!("{:>4} ", p.count)),
            Span::styled("█".repeat(n), theme.status(&p.kind)),
            Span::styled(format!(" {:.0}%", 100.0 * p.cumulative), theme.muted()),
        ]));
    }
    let groups: Vec<(&str, &Vec<crate::vision::report::GroupYield>)> =
        [("lot", &r.groups), ("speed", &r.by_speed)]
            .into_iter()
            .filter(|(_, g)| !g.is_empty())
            .collect();
    for (what, gs) in groups {
        lines.push(Line::styled(format!("yield by {what}"), theme.header()));
        for g in gs {
            lines.push(Line::raw(format!(
                "{:<14} {:>3}/{:<3} {:>7}  CI {}–{}",
                trunc(&g.key, 14),
                g.passed,
                g.inspected,
                g.yield_frac.map(pct).unwrap_or_else(|| "–".into()),
                pct(g.ci95.0),
                pct(g.ci95.1)
            )));
        }
    }
    text_block(f, left, "Yield", lines, theme);
    let worst: Vec<&crate::vision::report::PositionStats> = r
        .worst_pins
        .iter()
        .filter(|p| p.defects > 0)
        .take(8)
        .collect();
    let worst_h = if worst.is_empty() {
        0
    } else {
        (worst.len() as u16 + 3).min(side.height / 2)
    };
    let [wa, ia] = Layout::vertical([Constraint::Length(worst_h), Constraint::Min(3)]).areas(side);
    if worst_h > 0 {
        let rows: Vec<Row> = worst
            .iter()
            .map(|p| {
                Row::new(vec![
                    trunc(&p.part_number, 14),
                    format!("{},{}", p.row, p.col),
                    format!("{}/{}", p.defects, p.inspected),
                    opt(p.max_offset_mm),
                ])
            })
            .collect();
        let t = Table::new(
            rows,
            [
                Constraint::Length(14),
                Constraint::Length(5),
                Constraint::Length(7),
                Constraint::Min(6),
            ],
        )
        .header(Row::new(vec!["part", "pin", "defects", "max off mm"]).style(theme.header()))
        .block(block("Worst pins", theme));
        f.render_widget(t, wa);
    }
    let nw = ia.width.saturating_sub(30).max(8) as usize;
    let rows: Vec<Row> = v
        .items
        .iter()
        .map(|it| {
            Row::new(vec![
                Cell::from(trunc_left(&it.name, nw)),
                Cell::from(Span::styled(it.status.clone(), theme.status(&it.status))),
                Cell::from(it.note.clone()),
            ])
        })
        .collect();
    let t = Table::new(
        rows,
        [
            Constraint::Length(nw as u16),
            Constraint::Length(6),
            Constraint::Min(8),
        ],
    )
    .header(Row::new(vec!["image", "result", "note"]).style(theme.header()))
    .row_highlight_style(theme.selected())
    .block(block(format!("Images ({})", v.items.len()), theme));
    let mut st = TableState::default().with_selected(Some(v.selected));
    f.render_stateful_widget(t, ia, &mut st);
}

fn methods(f: &mut Frame, area: Rect, v: &MethodsView, theme: &Theme) {
    if !v.available {
        message(
            f,
            area,
            "Methods",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    }
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(60), Constraint::Percentage(40)]).areas(area);
    match (&v.chart, &v.bars) {
        (Some(c), _) => draw_chart(f, left, c, theme),
        (None, Some(b)) => {
            let lines = bars_lines(b, left.width.saturating_sub(2), theme);
            text_block(f, left, &b.title, lines, theme);
        }
        _ => message(f, left, "Methods", "no chart", theme.muted(), theme),
    }
    let list_h = (v.chart_titles.len() as u16 + 2).min(side.height / 2);
    let [list, info] =
        Layout::vertical([Constraint::Length(list_h), Constraint::Min(3)]).areas(side);
    let w = side.width.saturating_sub(4) as usize;
    let rows: Vec<Row> = v
        .chart_titles
        .iter()
        .map(|t| Row::new(vec![trunc(t, w)]))
        .collect();
    let t = Table::new(rows, [Constraint::Min(5)])
        .row_highlight_style(theme.selected())
        .block(block(
            format!(
                "Charts ({}, {} effort)",
                v.chart_titles.len(),
                v.effort.clone().unwrap_or_default()
            ),
            theme,
        ));
    let mut st = TableState::default().with_selected(Some(v.selected));
    f.render_stateful_widget(t, list, &mut st);
    let mut lines = vec![Line::styled(
        "stable step: measured / predicted",
        theme.header(),
    )];
    for r in &v.stability {
        lines.push(Line::raw(trunc(
            &format!(
                "{:<7} ω {:.2e}  {}",
                r.method,
                r.omega_contact,
                r.ratio
                    .map(|x| format!("{x:.2}"))
                    .unwrap_or_else(|| "–".into())
            ),
            w + 2,
        )));
    }
    if !v.fidelity.is_empty() {
        lines.push(Line::styled("fidelity", theme.header()));
        for (c, rpm, level, _) in &v.fidelity {
            lines.push(Line::raw(format!("c {c} mm {rpm} rpm → {level}")));
        }
    }
    if !v.failures.is_empty() {
        lines.push(Line::styled("failure modes", theme.header()));
        for (what, m, o) in &v.failures {
            lines.push(Line::styled(
                trunc(&format!("{m}: {what}: {o}"), w + 2),
                theme.muted(),
            ));
        }
    }
    // Times per tip stay in the view model (JSON) and the speed chart:
    // drawn screens carry no timings, so they diff cleanly.
    if !v.localisers.is_empty() {
        lines.push(Line::styled(
            "vision: centre error px (clean / 8 DN)",
            theme.header(),
        ));
        for l in &v.localisers {
            lines.push(Line::raw(trunc(
                &format!(
                    "{}: {} / {}",
                    l.localiser,
                    crate::panes::fmt_opt(l.rms_px_clean, 3),
                    crate::panes::fmt_opt(l.rms_px_noise8, 3)
                ),
                w + 2,
            )));
        }
    }
    if !v.breakdown.is_empty() {
        lines.push(Line::styled(
            "vision: verdicts ≥ 90 % up to (breaks at)",
            theme.header(),
        ));
        let level = |x: Option<f64>| x.map(|x| x.to_string()).unwrap_or_else(|| "–".into());
        for b in &v.breakdown {
            lines.push(Line::raw(trunc(
                &format!(
                    "{} {} ({}): {}",
                    b.factor,
                    level(b.holds_to),
                    level(b.breaks_at),
                    b.localisers
                ),
                w + 2,
            )));
        }
    }
    text_block(f, info, "Tables", lines, theme);
}
