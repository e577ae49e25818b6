//! Drawing of the Yield pane: yield, interval, groups and worst pins.

use super::*;

pub(super) fn yields(f: &mut Frame, area: Rect, v: &YieldView, theme: &Theme) {
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
