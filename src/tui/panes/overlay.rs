//! Drawing of the Overlay pane: measured against predicted, cycle by cycle.

use super::*;
use crate::tui::widgets::text_table;

pub(super) fn overlay(f: &mut Frame, area: Rect, v: &OverlayView, theme: &Theme) {
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
        // The charts share the crank angle: only the last one labels it.
        let n = charts.len() as u32;
        let rows = Layout::vertical(charts.iter().map(|_| Constraint::Ratio(1, n))).split(left);
        for (i, (c, r)) in charts.iter().zip(rows.iter()).enumerate() {
            draw_chart_with(
                f,
                *r,
                c,
                theme,
                ChartFrame {
                    border: true,
                    x_labels: i + 1 == charts.len(),
                },
            );
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
    // The calibration (once run, key C) between the figures and the cycles.
    let calibration: Vec<Line> = match &v.calibration {
        None => Vec::new(),
        Some(c) => c
            .rows
            .iter()
            .map(|(k, x)| kv_line(k, x.clone(), theme))
            .chain(
                c.error
                    .iter()
                    .map(|e| Line::styled(format!("not calibrated: {e}"), theme.warn())),
            )
            .collect(),
    };
    let calib_h = if calibration.is_empty() {
        0
    } else {
        (calibration.len() as u16 + 2).min(side.height / 2)
    };
    let table_h = if v.cycles.is_empty() {
        0
    } else {
        (v.cycles.len() as u16 + 3).min((side.height - calib_h) / 2)
    };
    let [info, calib_area, table_area] = Layout::vertical([
        Constraint::Min(4),
        Constraint::Length(calib_h),
        Constraint::Length(table_h),
    ])
    .areas(side);
    text_block(f, info, "Fidelity and figures", lines, theme);
    if calib_h > 0 {
        text_block(f, calib_area, "Calibration (C)", calibration, theme);
    }
    if table_h > 0 {
        let header = ["cycle", "RMS s mm", "RMS F N", "note"];
        let cells: Vec<Vec<String>> = v
            .cycles
            .iter()
            .map(|c| {
                vec![
                    c.index.to_string(),
                    opt(c.stroke_rms_mm),
                    opt(c.force_rms_n),
                    c.note.clone(),
                ]
            })
            .collect();
        let t = text_table(
            table_area.width,
            &header,
            &cells,
            &[
                Col::Auto(5, 6),
                Col::Auto(7, 9),
                Col::Auto(7, 9),
                Col::Fill(4),
            ],
            theme,
        )
        .row_highlight_style(theme.selected())
        .block(block("Cycles", theme));
        let mut st = TableState::default().with_selected(v.selected);
        f.render_stateful_widget(t, table_area, &mut st);
    }
}

// ---------------------------------------------------------------- Model
