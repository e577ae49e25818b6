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
        Line::styled(trunc_left(&v.source, w), theme.muted()),
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
        // The value at the cursor and the range in view, with four
        // significant digits so the line fits the side column.
        let (now, lo, hi) = (sig4(c.at_cursor), sig4(c.min), sig4(c.max));
        let mut readout = format!("    {now} [{lo} … {hi}]");
        if crate::tui::fit::width(&readout) > w {
            readout = format!("  {now} [{lo}…{hi}]");
        }
        lines.push(Line::styled(trunc(&readout, w), theme.muted()));
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
    // Stacked charts share the time axis: only the last one labels it,
    // and the block's bottom border names it with its unit.
    let n = v.charts.len() as u32;
    let x_title = v.charts.last().map_or(String::new(), |c| {
        crate::tui::fit::fit_axis(&c.x_label, charts.width.saturating_sub(4) as usize)
    });
    let b = block("", theme).title_bottom(Line::styled(x_title, theme.header()).right_aligned());
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
