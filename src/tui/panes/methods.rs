//! Drawing of the Methods pane: the numerical and vision labs.

use super::*;

pub(super) fn methods(f: &mut Frame, area: Rect, v: &MethodsView, theme: &Theme) {
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
