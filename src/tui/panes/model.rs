//! Drawing of the Model pane: the clearance model run and its figures.

use super::*;
use crate::tui::widgets::text_table;

pub(super) fn model(f: &mut Frame, area: Rect, v: &ModelView, theme: &Theme) {
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(58), Constraint::Percentage(42)]).areas(area);
    let [table_area, edit_area] =
        Layout::vertical([Constraint::Min(5), Constraint::Length(4)]).areas(left);
    // The allowed range gets a column when there is room for it; it is
    // always shown in full for the selected row in the box below.
    let inner = table_area.width.saturating_sub(2);
    let with_range = inner >= 60;
    let header: &[&str] = if with_range {
        &["key", "value", "allowed"]
    } else {
        &["key", "value"]
    };
    let cells: Vec<Vec<String>> = v
        .rows
        .iter()
        .map(|r| vec![r.key.clone(), r.value.clone(), String::new()])
        .collect();
    let cols: &[Col] = if with_range {
        &[Col::Auto(12, 27), Col::Auto(8, 20), Col::Fill(12)]
    } else {
        &[Col::Auto(12, 20), Col::Fill(8)]
    };
    let widths = column_widths(inner, cols, &content_widths(header, &cells));
    let rows: Vec<Row> = v
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let value = match (&v.editing, i == v.selected) {
                // The text being typed keeps its end (where the cursor is).
                (Some(t), true) => {
                    let t = format!("{t}▏");
                    let n = t.chars().count();
                    let keep = widths[1] as usize;
                    t.chars().skip(n.saturating_sub(keep)).collect()
                }
                _ => trunc(&r.value, widths[1] as usize),
            };
            let vstyle = if r.changed {
                theme.warn()
            } else {
                theme.base()
            };
            let mut cells = vec![
                Cell::from(trunc(&r.key, widths[0] as usize)),
                Cell::from(Span::styled(value, vstyle)),
            ];
            if with_range {
                cells.push(Cell::from(Span::styled(
                    trunc(&r.range, widths[2] as usize),
                    theme.muted(),
                )));
            }
            Row::new(cells)
        })
        .collect();
    // The source of the parameters, and the preset only when it says more.
    let title = if v.params_source == format!("preset {}", v.preset) {
        format!("Parameters — preset {}", v.preset)
    } else {
        format!("Parameters — {} (preset {})", v.params_source, v.preset)
    };
    let t = Table::new(rows, lengths(&widths))
        .header(header_row(header, &widths, theme))
        .row_highlight_style(theme.selected())
        .block(block_in(table_area, &title, theme));
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
            .block(block_in(edit_area, edit_title, theme))
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
        lines.push(Line::styled("ladder:", theme.muted()));
        for st in &fv.steps {
            let style = if st.invisible {
                theme.muted()
            } else {
                theme.base()
            };
            lines.push(Line::styled(format!("  {}", st.line()), style));
        }
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
        let header = ["figure", "value", "ideal"];
        let cells: Vec<Vec<String>> = v
            .figures
            .iter()
            .map(|r| vec![r.figure.clone(), r.value.clone(), r.ideal.clone()])
            .collect();
        let t = text_table(
            figs.width,
            &header,
            &cells,
            &[Col::Fill(10), Col::Auto(5, 10), Col::Auto(5, 8)],
            theme,
        )
        .block(block_in(figs, "Summary (reported revolutions)", theme));
        f.render_widget(t, figs);
    }
    if let (true, Some(c)) = (side_chart, &v.chart) {
        draw_chart(f, chart_area, c, theme);
    }
}

// ---------------------------------------------------------------- Study
