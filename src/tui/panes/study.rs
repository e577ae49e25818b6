//! Drawing of the Study pane: sweeps over clearance, speed and material.

use super::*;

pub(super) fn study(f: &mut Frame, area: Rect, v: &StudyView, theme: &Theme) {
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
    // The nominal case beside the choices when it fits, else on a line
    // of its own; every line wraps at word boundaries.
    let mut head_lines = Vec::new();
    let l1_w: usize = l1.iter().map(|s| s.width()).sum();
    match &v.nominal {
        Some(n) if l1_w + 2 + crate::tui::fit::width(n) <= area.width as usize => {
            l1.push(Span::styled(format!("  {n}"), theme.muted()));
            head_lines.push(Line::from(l1));
        }
        Some(n) => {
            head_lines.push(Line::from(l1));
            head_lines.push(Line::styled(n.clone(), theme.muted()));
        }
        None => head_lines.push(Line::from(l1)),
    }
    head_lines.push(Line::styled(v.setup.clone(), theme.muted()));
    let head_h: usize = head_lines
        .iter()
        .map(|l| {
            crate::tui::fit::wrap(&l.to_string(), area.width.max(1) as usize)
                .len()
                .max(1)
        })
        .sum();
    let [head, body] =
        Layout::vertical([Constraint::Length(head_h as u16), Constraint::Min(4)]).areas(area);
    f.render_widget(Paragraph::new(head_lines).wrap(Wrap { trim: false }), head);
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
