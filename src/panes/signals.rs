//! The Signals pane: a log's channels over time with zoom, pan, a cursor
//! with readouts, cycle markers and channel toggles.
//!
//! Every channel is reduced to at most two points (min and max) per braille
//! column of the chart before drawing ([`super::chart::decimate_minmax`]),
//! so a 10⁶-sample channel draws as fast as a short one and no spike is
//! lost. Without a rig log the pane shows the model's prediction over time,
//! and says so.

use super::chart::{
    ChartView, MarkerKind, SeriesKind, SeriesView, VMarker, decimate_minmax_with, value_at,
};
use super::session::Session;
use super::{PaneState, csv_table, fmt_opt, parse_f64, parse_usize};
use serde::Serialize;
use std::collections::BTreeSet;

/// Width of the pane's left column (channel list and readouts), cells.
pub const SIDE_COLS: u16 = 30;

/// UI state of the Signals pane.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SignalsUi {
    /// Visible window (s from the log's start); None: the whole log.
    pub window: Option<[f64; 2]>,
    /// Cursor time; None: the window's middle.
    pub cursor: Option<f64>,
    /// Selected channel (for toggling).
    pub selected: usize,
    /// Channels switched off, by name.
    pub hidden: BTreeSet<String>,
    /// Which loaded log.
    pub log: usize,
}

impl SignalsUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "t0" => {
                let t0 = parse_f64(v)?;
                let t1 = self.window.map(|w| w[1]).unwrap_or(f64::INFINITY);
                self.window = Some([t0, t1]);
            }
            "t1" => {
                let t1 = parse_f64(v)?;
                let t0 = self.window.map(|w| w[0]).unwrap_or(f64::NEG_INFINITY);
                self.window = Some([t0, t1]);
            }
            "cursor" => self.cursor = Some(parse_f64(v)?),
            "hide" => {
                for name in v.split(',').filter(|s| !s.trim().is_empty()) {
                    self.hidden.insert(name.trim().to_string());
                }
            }
            "channel" => self.selected = parse_usize(v)?,
            "log" => self.log = parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }

    /// The window clamped to the data range `full` (at least 1e-9 s wide).
    pub fn window_in(&self, full: [f64; 2]) -> [f64; 2] {
        let [a, b] = self.window.unwrap_or(full);
        let a = if a.is_finite() {
            a.max(full[0])
        } else {
            full[0]
        };
        let b = if b.is_finite() {
            b.min(full[1])
        } else {
            full[1]
        };
        if b - a > 1e-9 { [a, b] } else { full }
    }

    /// Zooms about the cursor by `factor` (< 1 zooms in).
    pub fn zoom(&mut self, factor: f64, full: [f64; 2]) {
        let [a, b] = self.window_in(full);
        let c = self
            .cursor
            .filter(|c| *c >= a && *c <= b)
            .unwrap_or(0.5 * (a + b));
        let span_full = full[1] - full[0];
        let span = ((b - a) * factor).clamp(span_full * 1e-6, span_full);
        let frac = if b > a { (c - a) / (b - a) } else { 0.5 };
        let mut na = c - frac * span;
        let mut nb = na + span;
        if na < full[0] {
            na = full[0];
            nb = na + span;
        }
        if nb > full[1] {
            nb = full[1];
            na = nb - span;
        }
        self.window = Some([na, nb]);
        self.cursor = Some(c);
    }

    /// Pans by `frac` of the window's width.
    pub fn pan(&mut self, frac: f64, full: [f64; 2]) {
        let [a, b] = self.window_in(full);
        let span = b - a;
        let shift = (frac * span).max(full[0] - a).min(full[1] - b);
        self.window = Some([a + shift, b + shift]);
        if let Some(c) = self.cursor.as_mut() {
            *c += shift;
        }
    }

    /// Moves the cursor by `frac` of the window (panning when it leaves it).
    pub fn move_cursor(&mut self, frac: f64, full: [f64; 2]) {
        let [a, b] = self.window_in(full);
        let c = self.cursor.unwrap_or(0.5 * (a + b));
        let nc = (c + frac * (b - a)).clamp(full[0], full[1]);
        self.cursor = Some(nc);
        if nc < a {
            self.pan((nc - a) / (b - a), full);
            self.cursor = Some(nc);
        } else if nc > b {
            self.pan((nc - b) / (b - a), full);
            self.cursor = Some(nc);
        }
    }

    /// Moves the cursor to the previous/next cycle start.
    pub fn jump_cycle(&mut self, forward: bool, cycles: &[(f64, u64)], full: [f64; 2]) {
        let [a, b] = self.window_in(full);
        let c = self.cursor.unwrap_or(0.5 * (a + b));
        let target = if forward {
            cycles.iter().map(|x| x.0).find(|&t| t > c + 1e-12)
        } else {
            cycles.iter().map(|x| x.0).rev().find(|&t| t < c - 1e-12)
        };
        if let Some(t) = target {
            self.move_cursor((t - c) / (b - a), full);
        }
    }

    pub fn reset(&mut self) {
        self.window = None;
        self.cursor = None;
    }
}

/// One channel's row in the side list.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelRow {
    pub name: String,
    pub unit: String,
    pub visible: bool,
    pub selected: bool,
    /// Value at the cursor (interpolated; None in a gap or outside the channel).
    pub at_cursor: Option<f64>,
    /// Extremes inside the window.
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub samples: usize,
    pub samples_in_view: usize,
}

/// The Signals pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct SignalsView {
    /// Where the signals come from (a log file, or the model prediction).
    pub source: String,
    pub full: [f64; 2],
    pub window: [f64; 2],
    pub cursor: f64,
    /// The cycle the cursor is in (index), if the log has cycle marks.
    pub cycle_at_cursor: Option<u64>,
    pub cycles_total: usize,
    pub cycles_in_view: usize,
    pub channels: Vec<ChannelRow>,
    /// One chart per visible channel, decimated to the chart's width.
    pub charts: Vec<ChartView>,
    /// Points drawn over all charts (≤ 2 per column per chart).
    pub points_drawn: usize,
    /// Why there is nothing to show, when there isn't.
    pub message: Option<String>,
}

impl SignalsView {
    pub fn to_csv(&self) -> String {
        let rows: Vec<Vec<String>> = self
            .channels
            .iter()
            .map(|c| {
                vec![
                    c.name.clone(),
                    c.unit.clone(),
                    c.visible.to_string(),
                    fmt_opt(c.at_cursor, 6),
                    fmt_opt(c.min, 6),
                    fmt_opt(c.max, 6),
                    c.samples.to_string(),
                    c.samples_in_view.to_string(),
                ]
            })
            .collect();
        csv_table(
            &[
                "channel",
                "unit",
                "visible",
                "at_cursor",
                "min_in_view",
                "max_in_view",
                "samples",
                "samples_in_view",
            ],
            &rows,
        )
    }
}

/// At most this many cycle markers are drawn in a chart (more would fill it).
fn max_markers(cols: usize) -> usize {
    (cols / 8).max(2)
}

pub fn view(s: &Session, ui: &PaneState) -> SignalsView {
    let st = &ui.signals;
    let Some(set) = s.signal_set(st.log) else {
        return SignalsView {
            source: "none".into(),
            full: [0.0, 1.0],
            window: [0.0, 1.0],
            cursor: 0.5,
            cycle_at_cursor: None,
            cycles_total: 0,
            cycles_in_view: 0,
            channels: Vec::new(),
            charts: Vec::new(),
            points_drawn: 0,
            message: Some(if s.model_error.is_some() {
                "no rig log loaded, and the model run failed (see the Model pane)".into()
            } else {
                "no rig log loaded and no model run yet: open a .mcap log (o) or wait for the model"
                    .into()
            }),
        };
    };
    let full = set.t_range();
    let window = st.window_in(full);
    let cursor = st
        .cursor
        .unwrap_or(0.5 * (window[0] + window[1]))
        .clamp(full[0], full[1]);
    // One column per terminal cell: at most two points (min, max) per cell.
    let cols = ui.width.saturating_sub(SIDE_COLS + 10).max(8) as usize;
    let cycle_at_cursor = set
        .cycles
        .iter()
        .rev()
        .find(|(t, _)| *t <= cursor + 1e-12)
        .map(|c| c.1);
    let in_view: Vec<&(f64, u64)> = set
        .cycles
        .iter()
        .filter(|(t, _)| *t >= window[0] && *t <= window[1])
        .collect();
    let mut channels = Vec::new();
    let mut charts = Vec::new();
    let mut points_drawn = 0;
    let n_ch = set.channels.len();
    for (i, c) in set.channels.iter().enumerate() {
        let visible = !st.hidden.contains(&c.name);
        let pts = decimate_minmax_with(&c.t_s, &c.values, c.blocks(), window[0], window[1], cols);
        let lo = c.t_s.partition_point(|&t| t < window[0]);
        let hi = c.t_s.partition_point(|&t| t <= window[1]);
        let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in pts.iter().filter(|p| p.0 >= window[0] && p.0 <= window[1]) {
            if p.1.is_finite() {
                mn = mn.min(p.1);
                mx = mx.max(p.1);
            }
        }
        channels.push(ChannelRow {
            name: c.name.clone(),
            unit: c.unit.clone(),
            visible,
            selected: i == st.selected.min(n_ch.saturating_sub(1)),
            at_cursor: value_at(&c.t_s, &c.values, cursor),
            min: mn.is_finite().then_some(mn),
            max: mx.is_finite().then_some(mx),
            samples: c.t_s.len(),
            samples_in_view: hi.saturating_sub(lo),
        });
        if !visible {
            continue;
        }
        points_drawn += pts.len();
        let mut chart = ChartView::new(
            c.name.clone(),
            "time (s)",
            axis_title(&c.name, &c.unit),
            vec![SeriesView {
                name: c.name.clone(),
                color: i,
                kind: SeriesKind::Line,
                points: pts,
            }],
            Some(window),
        );
        if in_view.len() <= max_markers(cols) {
            chart.markers.extend(in_view.iter().map(|(t, k)| VMarker {
                x: *t,
                kind: MarkerKind::Cycle,
                label: k.to_string(),
            }));
        }
        chart.markers.push(VMarker {
            x: cursor,
            kind: MarkerKind::Cursor,
            label: String::new(),
        });
        charts.push(chart);
    }
    let message = if set.channels.is_empty() {
        Some("the log holds no signal channels".into())
    } else if charts.is_empty() {
        Some("every channel is switched off (space toggles the selected one)".into())
    } else {
        None
    };
    SignalsView {
        source: set.source.clone(),
        full,
        window,
        cursor,
        cycle_at_cursor,
        cycles_total: set.cycles.len(),
        cycles_in_view: in_view.len(),
        channels,
        charts,
        points_drawn,
        message,
    }
}

/// The y axis title of a channel: its name and unit (`angle (rad)`; `(–)`
/// for a channel without a unit).
fn axis_title(name: &str, unit: &str) -> String {
    let unit = if unit.trim().is_empty() {
        "–"
    } else {
        unit.trim()
    };
    format!("{name} ({unit})")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zoom_pan_and_cursor_stay_inside_the_data() {
        let full = [0.0, 10.0];
        let mut u = SignalsUi::default();
        u.zoom(0.5, full);
        let w = u.window_in(full);
        assert!((w[1] - w[0] - 5.0).abs() < 1e-12);
        u.pan(10.0, full);
        let w = u.window_in(full);
        assert!((w[1] - 10.0).abs() < 1e-12 && (w[0] - 5.0).abs() < 1e-12);
        u.move_cursor(-3.0, full);
        let c = u.cursor.unwrap();
        assert!(c >= 0.0 && c <= w[1]);
        let w2 = u.window_in(full);
        assert!(c >= w2[0] && c <= w2[1], "{c} {w2:?}");
        u.zoom(100.0, full);
        assert_eq!(u.window_in(full), full);
        u.jump_cycle(true, &[(1.0, 0), (2.0, 1), (3.0, 2)], full);
        assert!(u.cursor.unwrap() > c);
        u.reset();
        assert_eq!(u.window_in(full), full);
    }
}
