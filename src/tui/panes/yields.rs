//! Drawing of the Yield pane: yield, interval, groups and worst pins.

use super::*;
use crate::tui::widgets::text_table;

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
    // An interval as one unbreakable range: `4.6–69.9 %`.
    let range = |lo: f64, hi: f64| format!("{:.1}–{:.1} %", 100.0 * lo, 100.0 * hi);
    let mut lines = vec![Line::from(vec![
        Span::styled("yield ", theme.muted()),
        Span::styled(
            r.yield_frac.map(pct).unwrap_or_else(|| "–".into()),
            theme.header(),
        ),
        Span::raw(format!("  95 % CI {} (Wilson)", range(r.ci95.0, r.ci95.1))),
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
        let key_w = gs
            .iter()
            .map(|g| crate::tui::fit::width(&g.key))
            .max()
            .unwrap_or(0)
            .min(14);
        let count_w = gs
            .iter()
            .map(|g| format!("{}/{}", g.passed, g.inspected).len())
            .max()
            .unwrap_or(0);
        for g in gs {
            let key = trunc(&g.key, key_w);
            let pad = key_w.saturating_sub(crate::tui::fit::width(&key));
            let count = format!("{}/{}", g.passed, g.inspected);
            lines.push(Line::raw(format!(
                "{key}{} {count:>count_w$} {:>7} CI {}",
                " ".repeat(pad),
                g.yield_frac.map(pct).unwrap_or_else(|| "–".into()),
                range(g.ci95.0, g.ci95.1)
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
        let header = ["part", "pin", "defects", "max off mm"];
        let cells: Vec<Vec<String>> = worst
            .iter()
            .map(|p| {
                vec![
                    p.part_number.clone(),
                    format!("{},{}", p.row, p.col),
                    format!("{}/{}", p.defects, p.inspected),
                    opt(p.max_offset_mm),
                ]
            })
            .collect();
        let t = text_table(
            wa.width,
            &header,
            &cells,
            &[
                Col::Fill(8),
                Col::Auto(3, 5),
                Col::Auto(5, 7),
                Col::Auto(7, 10),
            ],
            theme,
        )
        .block(block("Worst pins", theme));
        f.render_widget(t, wa);
    }
    // Images by file name (the whole path is in the JSON and what `y` copies).
    let name = |n: &str| n.rsplit(['/', '\\']).next().unwrap_or(n).to_string();
    let header = ["image", "result", "note"];
    let cells: Vec<Vec<String>> = v
        .items
        .iter()
        .map(|it| vec![name(&it.name), it.status.clone(), it.note.clone()])
        .collect();
    let widths = column_widths(
        ia.width.saturating_sub(2),
        &[Col::Auto(8, 24), Col::Auto(6, 7), Col::Fill(8)],
        &content_widths(&header, &cells),
    );
    let rows: Vec<Row> = v
        .items
        .iter()
        .zip(&cells)
        .map(|(it, c)| {
            Row::new(vec![
                Cell::from(trunc(&c[0], widths[0] as usize)),
                Cell::from(Span::styled(it.status.clone(), theme.status(&it.status))),
                Cell::from(trunc(&c[2], widths[2] as usize)),
            ])
        })
        .collect();
    let t = Table::new(rows, lengths(&widths))
        .header(header_row(&header, &widths, theme))
        .row_highlight_style(theme.selected())
        .block(block(format!("Images ({})", v.items.len()), theme));
    let mut st = TableState::default().with_selected(Some(v.selected));
    f.render_stateful_widget(t, ia, &mut st);
}
