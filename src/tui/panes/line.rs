//! Drawing of the Line pane: the press curve against its objects, the SPC
//! table with Cpk bands, the verdict counts and the cycles with reasons.

use super::*;
use crate::panes::line::LineView;

/// The Cpk band's style: capable green, adequate yellow, inadequate red.
fn band_style(band: &str, theme: &Theme) -> ratatui::style::Style {
    match band {
        "capable" => theme.ok(),
        "adequate" => theme.warn(),
        "inadequate" => theme.error(),
        _ => theme.muted(),
    }
}

pub(super) fn line(f: &mut Frame, area: Rect, v: &LineView, theme: &Theme) {
    if v.cycles.is_empty() && v.spc.is_empty() {
        message(
            f,
            area,
            "Line",
            v.message.as_deref().unwrap_or("nothing to show"),
            theme.muted(),
            theme,
        );
        return;
    }
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(55), Constraint::Percentage(45)]).areas(area);
    let spc_h = ((v.spc.len() + v.pin_spc.len()) as u16 + 3)
        .min(left.height / 2)
        .max(3);
    let [chart_area, spc_area] =
        Layout::vertical([Constraint::Min(6), Constraint::Length(spc_h)]).areas(left);
    match &v.chart {
        Some(c) => draw_chart(f, chart_area, c, theme),
        None => message(
            f,
            chart_area,
            "Press curve",
            "no curve for this cycle",
            theme.muted(),
            theme,
        ),
    }
    let header = ["characteristic", "n", "Cpk", "band", "WE"];
    let cells: Vec<Vec<String>> = v
        .spc
        .iter()
        .chain(&v.pin_spc)
        .map(|s| {
            vec![
                s.name.clone(),
                s.n.to_string(),
                opt(s.cpk),
                s.band.to_string(),
                s.alarms.to_string(),
            ]
        })
        .collect();
    let widths = column_widths(
        spc_area.width.saturating_sub(2),
        &[
            Col::Fill(8),
            Col::Auto(2, 5),
            Col::Auto(3, 7),
            Col::Auto(4, 10),
            Col::Auto(2, 3),
        ],
        &content_widths(&header, &cells),
    );
    let rows: Vec<Row> = v
        .spc
        .iter()
        .chain(&v.pin_spc)
        .zip(&cells)
        .map(|(s, c)| {
            Row::new(vec![
                Cell::from(trunc(&c[0], widths[0] as usize)),
                Cell::from(c[1].clone()),
                Cell::from(c[2].clone()),
                Cell::from(trunc(&c[3], widths[3] as usize)).style(band_style(s.band, theme)),
                Cell::from(c[4].clone()),
            ])
        })
        .collect();
    // WE: the Western Electric run-rule alarms of the characteristic.
    let t = Table::new(rows, lengths(&widths))
        .header(header_row(&header, &widths, theme))
        .block(block_in(spc_area, "SPC (Cpk ≥ 1.33 capable)", theme));
    f.render_widget(t, spc_area);

    let mut lines = vec![kv_line(
        "part",
        v.part_number.clone().unwrap_or_else(|| "–".into()),
        theme,
    )];
    lines.push(Line::from(vec![
        Span::styled(format!("{} OK", v.ok), theme.ok()),
        Span::raw("  "),
        Span::styled(format!("{} NOK", v.nok), theme.error()),
        Span::raw(format!("  {} not eval.", v.not_evaluated)),
    ]));
    if let Some(x) = v.nok_fraction {
        lines.push(kv_line(
            "NOK",
            format!("{:.2} % of evaluated", 100.0 * x),
            theme,
        ));
    }
    if let Some(c) = &v.connector {
        lines.push(kv_line("connector", c.clone(), theme));
    }
    if let Some(c) = &v.confusion {
        lines.push(Line::styled("process × vision (pass/fail)", theme.header()));
        lines.push(Line::raw(format!(
            " OK  {:>5} / {:<5}",
            c.process_ok_vision_pass, c.process_ok_vision_fail
        )));
        lines.push(Line::raw(format!(
            " NOK {:>5} / {:<5}",
            c.process_nok_vision_pass, c.process_nok_vision_fail
        )));
    }
    if let Some(p) = &v.pin_summary {
        lines.push(Line::styled(p.clone(), theme.muted()));
    }
    for a in v.alarms.iter().take(3) {
        lines.push(Line::styled(a.clone(), theme.warn()));
    }
    if v.alarms.len() > 3 {
        lines.push(Line::styled(
            format!("… {} more run-rule alarms", v.alarms.len() - 3),
            theme.muted(),
        ));
    }
    for n in v.not_monitored.iter().take(2) {
        lines.push(Line::styled(n.clone(), theme.error()));
    }
    if let Some(m) = &v.message {
        lines.push(Line::styled(m.clone(), theme.warn()));
    }
    let info_h = (lines.len() as u16 + 2).min(side.height / 2);
    let [info, list] =
        Layout::vertical([Constraint::Length(info_h), Constraint::Min(3)]).areas(side);
    text_block(f, info, "Process monitor", lines, theme);
    let header = ["cycle", "", "reasons"];
    let widths = column_widths(
        list.width.saturating_sub(2),
        &[Col::Fixed(6), Col::Fixed(4), Col::Fill(4)],
        &[],
    );
    let rows: Vec<Row> = v
        .cycles
        .iter()
        .map(|c| {
            let st = match c.status {
                "ok" => Cell::from("OK").style(theme.ok()),
                "nok" => Cell::from("NOK").style(theme.error()),
                _ => Cell::from("n/e").style(theme.muted()),
            };
            Row::new(vec![
                Cell::from(c.index.to_string()),
                st,
                Cell::from(trunc(&c.reasons.join("; "), widths[2] as usize)),
            ])
        })
        .collect();
    let title_room = list.width.saturating_sub(12) as usize;
    let t = Table::new(rows, lengths(&widths))
        .header(header_row(&header, &widths, theme))
        .row_highlight_style(theme.selected())
        .block(block(
            format!(
                "Cycles of {}",
                trunc_left(v.log.as_deref().unwrap_or("–"), title_room)
            ),
            theme,
        ));
    let mut st = TableState::default().with_selected(v.selected);
    f.render_stateful_widget(t, list, &mut st);
}
