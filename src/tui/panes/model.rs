//! Drawing of the Model pane: the clearance model run and its figures.

use super::*;

pub(super) fn model(f: &mut Frame, area: Rect, v: &ModelView, theme: &Theme) {
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
