//! Drawing of the Vision pane: one image, its annotated picture, verdict, notes and pins.

use super::*;

pub(super) fn vision(
    f: &mut Frame,
    area: Rect,
    v: &VisionView,
    theme: &Theme,
    img: &mut ImageCache,
) {
    if v.images == 0 {
        message(
            f,
            area,
            "Vision",
            v.message.as_deref().unwrap_or(""),
            theme.muted(),
            theme,
        );
        return;
    }
    let [left, side] =
        Layout::horizontal([Constraint::Percentage(55), Constraint::Percentage(45)]).areas(area);
    let title = format!(
        "{} ({}/{})",
        v.name.clone().unwrap_or_default(),
        v.index + 1,
        v.images
    );
    let b = block(
        trunc_left(&title, left.width.saturating_sub(4) as usize),
        theme,
    );
    let inner = b.inner(left);
    f.render_widget(b, left);
    img.draw(f, inner, v.image.as_ref(), theme);
    let mut lines = Vec::new();
    if let Some(vd) = &v.verdict {
        lines.push(Line::from(vec![
            Span::styled("verdict: ", theme.muted()),
            Span::styled(
                vd.to_uppercase(),
                theme.status(vd).add_modifier(Modifier::BOLD),
            ),
            Span::raw(match (&v.counts, v.extras) {
                (Some(c), 0) => format!("  {c}"),
                (Some(c), x) => format!("  {c}, {x} extra"),
                _ => String::new(),
            }),
        ]));
    }
    if let Some(e) = &v.error {
        lines.push(Line::styled(e.clone(), theme.error()));
    }
    for w in &v.failed_because {
        lines.push(Line::styled(format!("✗ {w}"), theme.error()));
    }
    if let Some((w, h)) = v.size {
        lines.push(kv_line("image", format!("{w}×{h} px"), theme));
    }
    if let Some(r) = &v.recipe {
        lines.push(kv_line("recipe", r.clone(), theme));
    }
    if let Some(g) = &v.grid {
        lines.push(kv_line("grid", g.clone(), theme));
    }
    for w in &v.warnings {
        lines.push(Line::styled(format!("! {w}"), theme.warn()));
    }
    if let Some(m) = &v.message {
        lines.push(Line::styled(m.clone(), theme.warn()));
    }
    // Rows the lines take once wrapped (a long note wraps onto several).
    let inner_w = side.width.saturating_sub(2).max(1) as usize;
    let rows: usize = lines
        .iter()
        .map(|l| l.width().div_ceil(inner_w).max(1))
        .sum();
    let info_h = (rows as u16 + 2).min(side.height / 2).max(3);
    let [info, table_area] =
        Layout::vertical([Constraint::Length(info_h), Constraint::Min(3)]).areas(side);
    let p = Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(block("Inspection", theme));
    f.render_widget(p, info);
    if !v.pins.is_empty() {
        let side_view = v.pins.iter().any(|p| p.height_mm.is_some());
        let rows: Vec<Row> = v
            .pins
            .iter()
            .map(|p| {
                Row::new(vec![
                    Cell::from(format!("{},{}", p.row, p.col)),
                    Cell::from(Span::styled(p.status.clone(), theme.status(&p.status))),
                    Cell::from(opt3(p.dx_mm)),
                    Cell::from(opt3(p.dy_mm)),
                    Cell::from(if side_view {
                        p.height_mm
                            .filter(|x| x.is_finite())
                            .map_or("–".into(), |x| format!("{x:.3}"))
                    } else {
                        p.area_ratio
                            .filter(|x| x.is_finite())
                            .map_or("–".into(), |x| format!("{x:.3}"))
                    }),
                ])
            })
            .collect();
        let t = Table::new(
            rows,
            [
                Constraint::Length(5),
                Constraint::Length(8),
                Constraint::Length(7),
                Constraint::Length(7),
                Constraint::Min(5),
            ],
        )
        .header(
            Row::new(vec![
                "pin",
                "status",
                "dx mm",
                "dy mm",
                if side_view { "h mm" } else { "area" },
            ])
            .style(theme.header()),
        )
        .row_highlight_style(theme.selected())
        .block(block(format!("Pins ({})", v.pins.len()), theme));
        let mut st = TableState::default().with_selected(Some(v.selected));
        f.render_stateful_widget(t, table_area, &mut st);
    }
}
