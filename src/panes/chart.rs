//! Chart view models shared by the panes: series already reduced to what a
//! terminal column can show, at most three labels per axis, vertical
//! markers (cursor, cycle starts). The TUI draws them with ratatui's `Chart`
//! (which draws every point it is given, pitfalls.md), batch mode turns them
//! into [`crate::plot`] panels for PNG.

use crate::engine::signals::scan;
pub use crate::engine::signals::{BLOCK, MinMaxBlocks};
use crate::plot::{LineChart, Panel, Series, SeriesStyle};
use serde::Serialize;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SeriesKind {
    #[default]
    Line,
    /// A reference curve (ideal mechanism, prediction): dashed in PNG, dim in the terminal.
    Reference,
    Points,
}

/// One curve of a chart. `points` may hold `(NaN, NaN)` separators where the
/// curve has a gap (a sensor dropout, an angle wrapping from 360° to 0°).
#[derive(Debug, Clone, Serialize)]
pub struct SeriesView {
    pub name: String,
    /// Palette slot (the theme maps it to one of the 16 ANSI colours).
    pub color: usize,
    pub kind: SeriesKind,
    pub points: Vec<(f64, f64)>,
}

/// What a vertical marker shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MarkerKind {
    Cursor,
    Cycle,
}

/// A vertical line at `x`.
#[derive(Debug, Clone, Serialize)]
pub struct VMarker {
    pub x: f64,
    pub kind: MarkerKind,
    pub label: String,
}

/// A chart ready to draw.
#[derive(Debug, Clone, Serialize)]
pub struct ChartView {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_bounds: [f64; 2],
    pub y_bounds: [f64; 2],
    /// At most three labels per axis (more misbehave in ratatui, pitfalls.md).
    pub x_ticks: Vec<String>,
    pub y_ticks: Vec<String>,
    pub series: Vec<SeriesView>,
    pub markers: Vec<VMarker>,
    /// The x / y values are log10 of the data (ticks show powers of ten).
    #[serde(default)]
    pub log_x: bool,
    #[serde(default)]
    pub log_y: bool,
}

impl ChartView {
    /// A chart over the given series; bounds fit the finite data (x bounds
    /// may be fixed), ticks are min, middle and max.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        series: Vec<SeriesView>,
        x_fixed: Option<[f64; 2]>,
    ) -> Self {
        let xb = x_fixed.unwrap_or_else(|| {
            finite_bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)))
        });
        let yb = pad_bounds(finite_bounds(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        ));
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_bounds: xb,
            y_bounds: yb,
            x_ticks: ticks(xb),
            y_ticks: ticks(yb),
            series,
            markers: Vec::new(),
            log_x: false,
            log_y: false,
        }
    }

    /// Marks the axes as log10 and relabels their ticks as powers of ten.
    fn with_log(mut self, log_x: bool, log_y: bool) -> Self {
        self.log_x = log_x;
        self.log_y = log_y;
        let pow = |b: [f64; 2]| -> Vec<String> {
            let mid = 0.5 * (b[0] + b[1]);
            [b[0], mid, b[1]]
                .iter()
                .map(|v| format!("1e{:.1}", v).replace(".0", ""))
                .collect()
        };
        if log_x {
            self.x_ticks = pow(self.x_bounds);
        }
        if log_y {
            self.y_ticks = pow(self.y_bounds);
        }
        self
    }

    /// Whether any series has a finite point.
    pub fn has_data(&self) -> bool {
        self.series
            .iter()
            .any(|s| s.points.iter().any(|p| p.0.is_finite() && p.1.is_finite()))
    }

    /// The chart as a [`crate::plot`] panel (for PNG export).
    pub fn to_panel(&self) -> Panel {
        let unlog = |v: f64, log: bool| if log { 10f64.powf(v) } else { v };
        let series = self
            .series
            .iter()
            .map(|s| {
                let points = s
                    .points
                    .iter()
                    .map(|p| (unlog(p.0, self.log_x), unlog(p.1, self.log_y)))
                    .collect();
                let style = match s.kind {
                    SeriesKind::Line => SeriesStyle::Line,
                    SeriesKind::Reference => SeriesStyle::Dashed,
                    SeriesKind::Points => SeriesStyle::Points,
                };
                Series::line(s.name.clone(), points)
                    .with_style(style)
                    .with_color(s.color)
            })
            .collect();
        Panel::Line(LineChart {
            title: self.title.clone(),
            x_label: self.x_label.clone(),
            y_label: self.y_label.clone(),
            series,
            x_range: Some((
                unlog(self.x_bounds[0], self.log_x),
                unlog(self.x_bounds[1], self.log_x),
            )),
            y_range: Some((
                unlog(self.y_bounds[0], self.log_y),
                unlog(self.y_bounds[1], self.log_y),
            )),
            log_x: self.log_x,
            log_y: self.log_y,
            ..Default::default()
        })
    }
}

impl ChartView {
    /// A [`crate::plot::LineChart`] decimated to `cols` columns.
    pub fn from_line_chart(c: &LineChart, cols: usize) -> Self {
        // Log axes: the chart is drawn over log10 of the values (non-positive
        // values become gaps).
        let tx = |v: f64| {
            if c.log_x {
                if v > 0.0 { v.log10() } else { f64::NAN }
            } else {
                v
            }
        };
        let ty = |v: f64| {
            if c.log_y {
                if v > 0.0 { v.log10() } else { f64::NAN }
            } else {
                v
            }
        };
        let series_pts: Vec<Vec<(f64, f64)>> = c
            .series
            .iter()
            .map(|s| {
                let mut pts: Vec<(f64, f64)> =
                    s.points.iter().map(|p| (tx(p.0), ty(p.1))).collect();
                // Points may come in any x order (work–precision curves):
                // sort each run so decimation can bisect it.
                if s.style == SeriesStyle::Points {
                    pts.retain(|p| p.0.is_finite() && p.1.is_finite());
                    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                }
                pts
            })
            .collect();
        let xb = c.x_range.map(|(a, b)| [tx(a), tx(b)]).unwrap_or_else(|| {
            finite_bounds(series_pts.iter().flat_map(|s| s.iter().map(|p| p.0)))
        });
        let series = c
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| SeriesView {
                name: s.label.clone(),
                color: s.color.unwrap_or(i),
                kind: match s.style {
                    SeriesStyle::Dashed => SeriesKind::Reference,
                    SeriesStyle::Points => SeriesKind::Points,
                    _ => SeriesKind::Line,
                },
                points: {
                    let pts = &series_pts[i];
                    let ascending = runs(pts).all(|r| r.windows(2).all(|w| w[0].0 <= w[1].0));
                    if ascending {
                        decimate_points(pts, xb[0], xb[1], cols)
                    } else {
                        // A curve that turns back in x (a work–precision
                        // curve): few points, kept as they are.
                        pts.clone()
                    }
                },
            })
            .collect();
        Self::new(
            c.title.clone(),
            c.x_label.clone(),
            c.y_label.clone(),
            series,
            Some(xb),
        )
        .with_log(c.log_x, c.log_y)
    }
}

/// A grouped bar chart ready to draw (one group per category).
#[derive(Debug, Clone, Serialize)]
pub struct BarsView {
    pub title: String,
    pub y_label: String,
    pub categories: Vec<String>,
    /// (series name, one value per category; NaN = no bar).
    pub series: Vec<(String, Vec<f64>)>,
}

impl BarsView {
    pub fn from_bar_chart(c: &crate::plot::BarChart) -> Self {
        Self {
            title: c.title.clone(),
            y_label: c.y_label.clone(),
            categories: c.categories.clone(),
            series: c.series.clone(),
        }
    }

    pub fn to_panel(&self) -> Panel {
        Panel::Bar(crate::plot::BarChart {
            title: self.title.clone(),
            x_label: String::new(),
            y_label: self.y_label.clone(),
            categories: self.categories.clone(),
            series: self.series.clone(),
            errors: None,
        })
    }

    /// Largest finite value (the bars' scale).
    pub fn max(&self) -> f64 {
        self.series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    }
}

/// Smallest and largest finite value ([0, 1] when there is none; widened
/// when they coincide).
pub fn finite_bounds(values: impl Iterator<Item = f64>) -> [f64; 2] {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return [0.0, 1.0];
    }
    if hi - lo <= f64::EPSILON * lo.abs().max(1.0) {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.05 };
        return [lo - d, hi + d];
    }
    [lo, hi]
}

/// Bounds with 5 % head room on each side (so a curve does not run along the frame).
pub fn pad_bounds(b: [f64; 2]) -> [f64; 2] {
    let d = (b[1] - b[0]) * 0.05;
    [b[0] - d, b[1] + d]
}

/// Three tick labels: low, middle, high, with as many decimals as the span needs.
pub fn ticks(b: [f64; 2]) -> Vec<String> {
    let mid = 0.5 * (b[0] + b[1]);
    let span = (b[1] - b[0]).abs();
    vec![
        fmt_tick(b[0], span),
        fmt_tick(mid, span),
        fmt_tick(b[1], span),
    ]
}

/// A number shown with a precision suited to `span` (the axis range).
pub fn fmt_tick(v: f64, span: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs().max(span);
    if a != 0.0 && !(1e-3..1e6).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = if span > 0.0 {
        (2.0 - span.log10().floor()).clamp(0.0, 6.0) as usize
    } else {
        2
    };
    let s = format!("{v:.decimals$}");
    if s == "-0" || s.starts_with("-0.") && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// Reduces a curve sampled at ascending `xs` to at most two points per
/// column (its minimum and maximum, in x order) over `cols` equal columns of
/// `[x0, x1]`, so a chart of any length draws in time proportional to its
/// width and no spike is lost. Points just outside the window are kept so
/// lines run to the edges. Non-finite values break the line: a column with
/// no finite value after one with data yields a `(NaN, NaN)` separator.
///
/// Cost: two binary searches and one pass over the samples in the window.
pub fn decimate_minmax(xs: &[f64], ys: &[f64], x0: f64, x1: f64, cols: usize) -> Vec<(f64, f64)> {
    decimate_minmax_with(xs, ys, None, x0, x1, cols)
}

/// [`decimate_minmax`] using precomputed block extremes of `ys` when given.
pub fn decimate_minmax_with(
    xs: &[f64],
    ys: &[f64],
    blocks: Option<&MinMaxBlocks>,
    x0: f64,
    x1: f64,
    cols: usize,
) -> Vec<(f64, f64)> {
    let n = xs.len().min(ys.len());
    if n == 0 || cols == 0 || !(x1 > x0) {
        return Vec::new();
    }
    let xs = &xs[..n];
    let lo = xs.partition_point(|&x| x < x0).saturating_sub(1);
    let hi = (xs.partition_point(|&x| x <= x1) + 1).min(n);
    if hi <= lo {
        return Vec::new();
    }
    // Few enough points: keep them all (with breaks at non-finite values).
    if hi - lo <= 2 * cols {
        let mut out = Vec::with_capacity(hi - lo);
        let mut broken = false;
        for i in lo..hi {
            if xs[i].is_finite() && ys[i].is_finite() {
                out.push((xs[i], ys[i]));
                broken = false;
            } else if !broken && !out.is_empty() {
                out.push((f64::NAN, f64::NAN));
                broken = true;
            }
        }
        return out;
    }
    // Column boundaries by bisection, then one tight min/max scan per
    // column (no per-sample division or branching on the column).
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(2 * cols + 8);
    let width = (x1 - x0) / cols as f64;
    let mut bounds = Vec::with_capacity(cols + 3);
    bounds.push(lo);
    let mut from = lo;
    for j in 0..=cols {
        let edge = x0 + j as f64 * width;
        let k = from + xs[from..hi].partition_point(|&x| x < edge);
        bounds.push(k);
        from = k;
    }
    bounds.push(hi);
    let mut gap_pending = false;
    for w in bounds.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a >= b {
            continue;
        }
        let seg = &ys[a..b];
        let (mn, imn, mx, imx) = match blocks {
            Some(bl) => {
                let (mn, imn, mx, imx) = bl.extremes(ys, a, b);
                (mn, imn.wrapping_sub(a), mx, imx.wrapping_sub(a))
            }
            None => scan(seg),
        };
        if imn == usize::MAX || imn >= seg.len() || !mn.is_finite() || !mx.is_finite() {
            // No finite value in this column: the line breaks here.
            gap_pending = true;
            continue;
        }
        if (gap_pending || !seg[0].is_finite()) && !out.is_empty() {
            out.push((f64::NAN, f64::NAN));
        }
        gap_pending = !seg[seg.len() - 1].is_finite();
        let pmn = (xs[a + imn], mn);
        let pmx = (xs[a + imx], mx);
        if imn == imx {
            out.push(pmn);
        } else if imn < imx {
            out.push(pmn);
            out.push(pmx);
        } else {
            out.push(pmx);
            out.push(pmn);
        }
    }
    out
}

/// [`decimate_minmax`] over a point list made of runs separated by
/// non-finite points (each run ascending in x), keeping the separators.
pub fn decimate_points(points: &[(f64, f64)], x0: f64, x1: f64, cols: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for run in runs(points) {
        let xs: Vec<f64> = run.iter().map(|p| p.0).collect();
        let ys: Vec<f64> = run.iter().map(|p| p.1).collect();
        let d = decimate_minmax(&xs, &ys, x0, x1, cols);
        if d.is_empty() {
            continue;
        }
        if !out.is_empty() {
            out.push((f64::NAN, f64::NAN));
        }
        out.extend(d);
    }
    out
}

/// Splits a point list at its `(NaN, NaN)` separators (and at any
/// non-finite point) into drawable runs.
pub fn runs(points: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> {
    points
        .split(|p| !(p.0.is_finite() && p.1.is_finite()))
        .filter(|r| !r.is_empty())
}

/// Value of a sampled curve at `x` (linear interpolation between the
/// neighbours; None outside the samples or next to a non-finite value).
pub fn value_at(xs: &[f64], ys: &[f64], x: f64) -> Option<f64> {
    let n = xs.len().min(ys.len());
    if n == 0 || !x.is_finite() {
        return None;
    }
    let i = xs[..n].partition_point(|&v| v < x);
    if i == 0 {
        return (xs[0] == x && ys[0].is_finite()).then_some(ys[0]);
    }
    if i == n {
        return None;
    }
    let (xa, xb, ya, yb) = (xs[i - 1], xs[i], ys[i - 1], ys[i]);
    if !(ya.is_finite() && yb.is_finite()) {
        return None;
    }
    if xb <= xa {
        return Some(yb);
    }
    Some(ya + (yb - ya) * (x - xa) / (xb - xa))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_extremes_and_bounds_point_count() {
        let n = 100_000;
        let xs: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut ys: Vec<f64> = xs.iter().map(|x| (x / 1000.0).sin()).collect();
        ys[54_321] = 50.0; // a single-sample spike
        ys[77_777] = -40.0;
        let d = decimate_minmax(&xs, &ys, 0.0, n as f64, 100);
        assert!(d.len() <= 2 * 100 + 2, "{} points", d.len());
        let max = d.iter().map(|p| p.1).fold(f64::MIN, f64::max);
        let min = d.iter().map(|p| p.1).fold(f64::MAX, f64::min);
        assert_eq!(max, 50.0);
        assert_eq!(min, -40.0);
        // x order is preserved.
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn block_extremes_give_the_same_decimation() {
        let n = 200_003;
        let xs: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
        let mut ys: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1013) as f64 + (i as f64 * 1e-4).sin())
            .collect();
        ys[150_000] = 1e4;
        for y in &mut ys[90_000..95_000] {
            *y = f64::NAN;
        }
        let b = MinMaxBlocks::new(&ys);
        for (x0, x1, cols) in [
            (0.0, 200.0, 160),
            (13.3, 77.7, 97),
            (149.9, 150.1, 50),
            (-5.0, 500.0, 3),
        ] {
            let plain = decimate_minmax(&xs, &ys, x0, x1, cols);
            let fast = decimate_minmax_with(&xs, &ys, Some(&b), x0, x1, cols);
            assert_eq!(plain.len(), fast.len(), "{x0} {x1}");
            for (p, q) in plain.iter().zip(&fast) {
                assert!(
                    p.0.to_bits() == q.0.to_bits() && p.1.to_bits() == q.1.to_bits(),
                    "{p:?} {q:?}"
                );
            }
        }
    }

    #[test]
    fn decimation_of_a_window_and_of_gaps() {
        let xs: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let mut ys: Vec<f64> = xs.clone();
        for y in &mut ys[400..500] {
            *y = f64::NAN;
        }
        let d = decimate_minmax(&xs, &ys, 2.0, 8.0, 50);
        // Starts one sample before the window and ends one after.
        assert!((d[0].0 - 1.99).abs() < 1e-9);
        assert!((d.last().unwrap().0 - 8.01).abs() < 1e-9);
        // The gap becomes exactly one separator.
        assert_eq!(d.iter().filter(|p| p.0.is_nan()).count(), 1);
        assert_eq!(runs(&d).count(), 2);
        // Few points: all kept.
        let d = decimate_minmax(&xs[..10], &ys[..10], 0.0, 1.0, 50);
        assert_eq!(d.len(), 10);
        assert!(decimate_minmax(&xs, &ys, 5.0, 5.0, 10).is_empty());
        assert!(decimate_minmax(&[], &[], 0.0, 1.0, 10).is_empty());
    }

    #[test]
    fn interpolation_and_ticks() {
        let xs = [0.0, 1.0, 2.0];
        let ys = [0.0, 10.0, f64::NAN];
        assert_eq!(value_at(&xs, &ys, 0.5), Some(5.0));
        assert_eq!(value_at(&xs, &ys, 0.0), Some(0.0));
        assert_eq!(value_at(&xs, &ys, 1.5), None);
        assert_eq!(value_at(&xs, &ys, 3.0), None);
        assert_eq!(ticks([0.0, 16.0]), vec!["0.0", "8.0", "16.0"]);
        assert_eq!(ticks([-0.001, 0.001])[1], "0.00000");
        assert_eq!(fmt_tick(1.5e7, 1e7), "1.50e7");
        assert_eq!(finite_bounds([f64::NAN].into_iter()), [0.0, 1.0]);
        assert_eq!(finite_bounds([2.0, 2.0].into_iter()), [1.9, 2.1]);
    }
}
