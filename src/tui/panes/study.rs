//! Drawing of the Study pane: sweeps over clearance, speed and material.

use super::*;

pub(super) fn study(f: &mut Frame, area: Rect, v: &StudyView, theme: &Theme) {
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
