//! Drawing of the Signals pane: channels over time and their side table.

use super::*;

pub(super) fn signals(f: &mut Frame, area: Rect, v: &SignalsView, theme: &Theme) {
    if let (Some(msg), true) = (&v.message, v.channels.is_empty()) {
        message(f, area, "Signals", msg, theme.muted(), theme);
        return;
    }
    let side_w = SIDE_COLS.min(area.width / 2);
    let [side, charts] =
        Layout::horizontal([Constraint::Length(side_w), Constraint::Min(10)]).areas(area);
    let w = side_w.saturating_sub(2) as usize;
    let mut lines = vec![
        Line::styled(trunc(&v.source, w), theme.muted()),
        kv_line(
            "window",
            format!("{:.3}–{:.3} s", v.window[0], v.window[1]),
            theme,
        ),
        kv_line("cursor", fmt_s(v.cursor), theme),
        kv_line(
            "cycle",
            match v.cycle_at_cursor {
                Some(k) => format!("{k} ({}/{} in view)", v.cycles_in_view, v.cycles_total),
                None => format!("– ({} starts)", v.cycles_total),
            },
            theme,
        ),
        Line::raw(""),
    ];
    for c in &v.channels {
        let check = if c.visible { "[x]" } else { "[ ]" };
        let style = if c.selected {
            theme.selected()
        } else if c.visible {
            theme.base()
        } else {
            theme.muted()
        };
        lines.push(Line::from(vec![Span::styled(
            trunc(&format!("{check} {} ({})", c.name, c.unit), w),
            style,
        )]));
        lines.push(Line::styled(
            trunc(
                &format!("    {} [{} … {}]", opt(c.at_cursor), opt(c.min), opt(c.max)),
                w,
            ),
            theme.muted(),
        ));
    }
    text_block(f, side, "Channels", lines, theme);
    if v.charts.is_empty() {
        message(
            f,
            charts,
            "Signals",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    }
    // Stacked charts share the time axis: only the last one labels it.
    let n = v.charts.len() as u32;
    let b = block("", theme);
    let inner = b.inner(charts);
    f.render_widget(b, charts);
    let rows = Layout::vertical(v.charts.iter().map(|_| Constraint::Ratio(1, n))).split(inner);
    for (i, (c, r)) in v.charts.iter().zip(rows.iter()).enumerate() {
        draw_chart_with(
            f,
            *r,
            c,
            theme,
            ChartFrame {
                border: false,
                x_labels: i + 1 == v.charts.len(),
            },
        );
    }
}

// ---------------------------------------------------------------- Overlay
