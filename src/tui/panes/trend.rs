//! Drawing of the Trend pane: the clearance history chart (each log ± U95,
//! the fitted wear with its band, the limit), the verdict and the facts,
//! and the history table (newest first). Below 100 columns (80×24) the
//! chart spans the width above, the facts and the history share the lower
//! half; wider, the chart takes the left 60 % and the text the right.

use super::*;
use crate::panes::trend::TrendView;

pub(super) fn trend(f: &mut Frame, area: Rect, v: &TrendView, theme: &Theme) {
    let Some(chart) = &v.chart else {
        let mut lines = vec![Line::styled(
            v.message
                .clone()
                .unwrap_or_else(|| "nothing to show".into()),
            theme.muted(),
        )];
        for e in v.left_out.iter().take(6) {
            lines.push(Line::styled(e.clone(), theme.error()));
        }
        text_block(f, area, "Trend", lines, theme);
        return;
    };
    let narrow = area.width < 100;
    let (chart_area, info, list) = if narrow {
        let chart_h = (area.height / 2).max(6).min(area.height);
        let [top, bottom] =
            Layout::vertical([Constraint::Length(chart_h), Constraint::Min(3)]).areas(area);
        let [info, list] =
            Layout::horizontal([Constraint::Percentage(58), Constraint::Percentage(42)])
                .areas(bottom);
        (top, info, list)
    } else {
        let [left, side] =
            Layout::horizontal([Constraint::Percentage(60), Constraint::Percentage(40)])
                .areas(area);
        let info_h = (side.height / 2 + 2).min(side.height);
        let [info, list] =
            Layout::vertical([Constraint::Length(info_h), Constraint::Min(3)]).areas(side);
        (left, info, list)
    };
    draw_chart(f, chart_area, chart, theme);
    let mut lines = Vec::new();
    if v.heads.len() > 1 {
        lines.push(kv_line(
            "head",
            format!(
                "{} ({} of {}, j/k)",
                v.rig.as_deref().unwrap_or("–"),
                v.head + 1,
                v.heads.len()
            ),
            theme,
        ));
    }
    if let Some(verdict) = &v.verdict {
        lines.push(Line::styled(verdict.clone(), theme.header()));
    }
    for fact in &v.facts {
        lines.push(Line::raw(fact.clone()));
    }
    for e in v.left_out.iter().take(2) {
        lines.push(Line::styled(e.clone(), theme.error()));
    }
    if v.left_out.len() > 2 {
        lines.push(Line::styled(
            format!("… {} more logs left out", v.left_out.len() - 2),
            theme.muted(),
        ));
    }
    f.render_widget(
        Paragraph::new(lines).wrap(Wrap { trim: true }).block(block(
            format!("Wear and forecast · {}", v.rig.as_deref().unwrap_or("–")),
            theme,
        )),
        info,
    );
    let rows: Vec<Row> = v
        .history
        .iter()
        .rev()
        .map(|r| {
            Row::new(vec![
                Cell::from(r.start.clone()),
                Cell::from(format!("{:.4}", r.clearance_mm)),
                Cell::from(format!("{:.4}", r.u95_mm)),
            ])
        })
        .collect();
    let t = Table::new(
        rows,
        [
            Constraint::Length(10),
            Constraint::Length(7),
            Constraint::Min(6),
        ],
    )
    .header(Row::new(vec!["start", "c mm", "U95"]).style(theme.header()))
    .block(block("History (newest first)", theme));
    f.render_widget(t, list);
}
