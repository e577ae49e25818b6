//! Drawing of the Session pane: files, parameters, findings.

use super::*;

pub(super) fn session(f: &mut Frame, area: Rect, v: &SessionView, theme: &Theme) {
    let err_h = if v.errors.is_empty() {
        0
    } else {
        (v.errors.len() as u16 + 2).min(area.height / 3).max(3)
    };
    let live_h = match &v.live {
        Some(l) => (l.events.len() as u16 + 3).min(area.height / 3).max(4),
        None => 0,
    };
    let [head, main, live_area, errs] = Layout::vertical([
        Constraint::Length(5),
        Constraint::Min(4),
        Constraint::Length(live_h),
        Constraint::Length(err_h),
    ])
    .areas(area);
    if let Some(l) = &v.live {
        let mut lines = vec![Line::styled(
            format!(
                "{} {}",
                if l.following { "following:" } else { "paused:" },
                l.status
            ),
            theme.header(),
        )];
        if !l.alarms.is_empty() {
            lines.push(Line::styled(
                format!(
                    "ALARM {}{}",
                    l.alarms.join(", "),
                    l.last_alarm
                        .as_ref()
                        .map(|a| format!(" — {a}"))
                        .unwrap_or_default()
                ),
                theme.error(),
            ));
        }
        for e in &l.events {
            let style = if e.starts_with("ALARM") {
                theme.error()
            } else {
                theme.base()
            };
            lines.push(Line::styled(e.clone(), style));
        }
        f.render_widget(
            Paragraph::new(lines).block(block("Live".to_string(), theme)),
            live_area,
        );
    }
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
    if let Some(sel) = v.files.get(v.selected)
        && !sel.message.is_empty()
    {
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
