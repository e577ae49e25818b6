//! PNG charts, drawn with `plotters` into an RGB buffer and encoded with
//! `image`, with an embedded font (DejaVu Sans) so the output is the same on
//! every machine and needs no system fonts (pitfalls.md: plotters' default
//! font stack needs fontconfig).
//!
//! The chart descriptions ([`LineChart`], [`BarChart`]) are plain data, so a
//! pane's view model can be turned into a chart without the pane knowing
//! about plotters.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Once;

/// The font used for every chart.
/// The one embedded font (DejaVu Sans), shared by the charts and the
/// annotated vision overlays.
pub static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
const FONT_NAME: &str = "pinsight-sans";

/// Errors from drawing or writing a chart.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("chart '{title}': {msg}")]
    Draw { title: String, msg: String },
    #[error("writing chart {path}: {msg}")]
    Write { path: String, msg: String },
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; failure here would be a build defect.
        let _ = plotters::style::register_font(FONT_NAME, FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SeriesStyle {
    #[default]
    Line,
    Dashed,
    Points,
    /// Line with a point marker at every sample (for sparse data such as work–precision curves).
    LinePoints,
}

/// One named curve.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    #[serde(default)]
    pub style: SeriesStyle,
    /// Palette index; `None` takes the series' position.
    #[serde(default)]
    pub color: Option<usize>,
}

impl Series {
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::Line,
            color: None,
        }
    }
    pub fn with_style(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }
    pub fn with_color(mut self, color: usize) -> Self {
        self.color = Some(color);
        self
    }
}

/// A shaded band between `lower` and `upper` sampled at the same x values.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Band {
    pub label: String,
    pub x: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    #[serde(default)]
    pub color: Option<usize>,
}

/// A line chart: curves and bands over a common x axis.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
pub struct LineChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    #[serde(default)]
    pub bands: Vec<Band>,
    #[serde(default)]
    pub log_x: bool,
    #[serde(default)]
    pub log_y: bool,
    /// Fixed x range; `None` fits the data.
    #[serde(default)]
    pub x_range: Option<(f64, f64)>,
    #[serde(default)]
    pub y_range: Option<(f64, f64)>,
}

/// A grouped bar chart: one group per category, one bar per series in it.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
pub struct BarChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub categories: Vec<String>,
    /// (series label, one value per category; NaN = no bar).
    pub series: Vec<(String, Vec<f64>)>,
    /// Optional error bars (same shape as `series` values): half-widths.
    #[serde(default)]
    pub errors: Option<Vec<Vec<f64>>>,
}

/// A compact tick label: up to three significant digits, scientific
/// notation outside 1e-3 … 1e5 (so log axes read `1e-5`, not
/// `9.999999999e-6`).
pub fn tick_label(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let exp = a.log10().floor();
        let mut mant = v / 10f64.powf(exp);
        let mut exp = exp as i32;
        if (mant.abs() - 10.0).abs() < 1e-6 {
            mant /= 10.0;
            exp += 1;
        }
        let m = format!("{mant:.2}");
        let m = m.trim_end_matches('0').trim_end_matches('.');
        if m == "1" {
            format!("1e{exp}")
        } else if m == "-1" {
            format!("-1e{exp}")
        } else {
            format!("{m}e{exp}")
        }
    } else {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        let t = format!("{v:.digits$}");
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    }
}

/// A linear axis's tick at zero comes out of the tick arithmetic as a
/// rounding residue (`-1.39e-17` on an axis from -0.1 to 0.1): snap a tick
/// closer to zero than a billionth of the axis span to zero.
fn axis_tick(v: f64, log: bool, span: f64) -> f64 {
    if !log && v.abs() < 1e-9 * span {
        0.0
    } else {
        v
    }
}

fn x_span(c: &LineChart) -> f64 {
    let ((a, b), _) = c.ranges();
    (b - a).abs()
}

fn y_span(c: &LineChart) -> f64 {
    let (_, (a, b)) = c.ranges();
    (b - a).abs()
}

/// Colour palette, chosen to stay distinct on white and in grey print.
pub fn palette(i: usize) -> RGBColor {
    const P: [RGBColor; 10] = [
        RGBColor(0, 90, 181),
        RGBColor(220, 50, 32),
        RGBColor(0, 150, 80),
        RGBColor(230, 140, 0),
        RGBColor(120, 60, 170),
        RGBColor(0, 170, 190),
        RGBColor(150, 90, 40),
        RGBColor(230, 80, 160),
        RGBColor(90, 90, 90),
        RGBColor(170, 170, 0),
    ];
    P[i % P.len()]
}

fn finite_range(values: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values {
        if v.is_finite() && (!log || v > 0.0) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo > hi {
        return None;
    }
    if log {
        if hi / lo < 1.0001 {
            lo /= 2.0;
            hi *= 2.0;
        }
        Some((lo / 1.2, hi * 1.2))
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            0.05 * span
        } else {
            (0.05 * hi.abs()).max(1e-12)
        };
        Some((lo - pad, hi + pad))
    }
}

impl LineChart {
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .chain(self.bands.iter().flat_map(|b| b.x.iter().copied()));
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(
                self.bands
                    .iter()
                    .flat_map(|b| b.lower.iter().chain(b.upper.iter()).copied()),
            );
        let xr = self
            .x_range
            .or_else(|| finite_range(xs, self.log_x))
            .unwrap_or(if self.log_x { (0.1, 10.0) } else { (0.0, 1.0) });
        let yr = self
            .y_range
            .or_else(|| finite_range(ys, self.log_y))
            .unwrap_or(if self.log_y { (0.1, 10.0) } else { (0.0, 1.0) });
        (xr, yr)
    }
}

fn draw_err<E: std::fmt::Debug>(title: &str) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError::Draw {
        title: title.to_string(),
        msg: format!("{e:?}"),
    }
}

macro_rules! draw_line_chart_body {
    ($chart:expr, $c:expr, $title:expr) => {{
        let chart = $chart;
        let mut c = $c;
        let (xs, ys) = (x_span(chart), y_span(chart));
        let fx = |v: &f64| tick_label(axis_tick(*v, chart.log_x, xs));
        let fy = |v: &f64| tick_label(axis_tick(*v, chart.log_y, ys));
        let mut mesh = c.configure_mesh();
        mesh.x_desc(chart.x_label.as_str())
            .y_desc(chart.y_label.as_str())
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_labels(8)
            .y_labels(8)
            .label_style((FONT_NAME, 13))
            .axis_desc_style((FONT_NAME, 14))
            .light_line_style(RGBColor(235, 235, 235));
        mesh.draw().map_err(draw_err($title))?;
        for (i, b) in chart.bands.iter().enumerate() {
            let col = palette(b.color.unwrap_or(i)).mix(0.18);
            let mut poly: Vec<(f64, f64)> = Vec::with_capacity(2 * b.x.len());
            for (j, x) in b.x.iter().enumerate() {
                if let Some(u) = b.upper.get(j) {
                    if x.is_finite() && u.is_finite() {
                        poly.push((*x, *u));
                    }
                }
            }
            for (j, x) in b.x.iter().enumerate().rev() {
                if let Some(l) = b.lower.get(j) {
                    if x.is_finite() && l.is_finite() {
                        poly.push((*x, *l));
                    }
                }
            }
            if poly.len() >= 3 {
                c.draw_series(std::iter::once(Polygon::new(poly, col.filled())))
                    .map_err(draw_err($title))?
                    .label(b.label.as_str())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 18, y + 5)], col.filled())
                    });
            }
        }
        for (i, s) in chart.series.iter().enumerate() {
            let col = palette(s.color.unwrap_or(i));
            let style = ShapeStyle::from(&col).stroke_width(2);
            // A non-finite point breaks the line into separate segments.
            let ok = |(x, y): &(f64, f64)| {
                x.is_finite()
                    && y.is_finite()
                    && (!chart.log_x || *x > 0.0)
                    && (!chart.log_y || *y > 0.0)
            };
            let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for p in &s.points {
                if ok(p) {
                    if let Some(last) = segments.last_mut() {
                        last.push(*p);
                    }
                } else if segments.last().is_some_and(|l| !l.is_empty()) {
                    segments.push(Vec::new());
                }
            }
            segments.retain(|seg| !seg.is_empty());
            if segments.is_empty() {
                segments.push(Vec::new());
            }
            let rest: Vec<Vec<(f64, f64)>> = segments.split_off(1);
            let pts = segments.pop().unwrap_or_default();
            for seg in rest {
                match s.style {
                    SeriesStyle::Line | SeriesStyle::LinePoints => {
                        c.draw_series(LineSeries::new(seg.clone(), style))
                            .map_err(draw_err($title))?;
                    }
                    SeriesStyle::Dashed => {
                        c.draw_series(DashedLineSeries::new(seg.clone(), 8, 5, style))
                            .map_err(draw_err($title))?;
                    }
                    SeriesStyle::Points => {}
                }
                if matches!(s.style, SeriesStyle::Points | SeriesStyle::LinePoints) {
                    c.draw_series(
                        seg.into_iter()
                            .map(move |p| Circle::new(p, 3, col.filled())),
                    )
                    .map_err(draw_err($title))?;
                }
            }
            let anno = match s.style {
                SeriesStyle::Line => c.draw_series(LineSeries::new(pts, style)),
                SeriesStyle::Dashed => c.draw_series(DashedLineSeries::new(pts, 8, 5, style)),
                SeriesStyle::Points => c.draw_series(
                    pts.into_iter()
                        .map(move |p| Circle::new(p, 3, col.filled())),
                ),
                SeriesStyle::LinePoints => {
                    c.draw_series(LineSeries::new(pts.clone(), style))
                        .map_err(draw_err($title))?;
                    c.draw_series(
                        pts.into_iter()
                            .map(move |p| Circle::new(p, 3, col.filled())),
                    )
                }
            }
            .map_err(draw_err($title))?;
            anno.label(s.label.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], col.stroke_width(2))
            });
        }
        if chart.series.len() + chart.bands.len() > 1 {
            c.configure_series_labels()
                .label_font((FONT_NAME, 12))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(draw_err($title))?;
        }
        Ok(())
    }};
}

fn draw_line_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &LineChart,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let title = chart.title.as_str();
    let ((x0, x1), (y0, y1)) = chart.ranges();
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(title, (FONT_NAME, 17))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70);
    match (chart.log_x, chart.log_y) {
        (false, false) => {
            let c = builder
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(draw_err(title))?;
            draw_line_chart_body!(chart, c, title)
        }
        (true, false) => {
            let c = builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(draw_err(title))?;
            draw_line_chart_body!(chart, c, title)
        }
        (false, true) => {
            let c = builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(draw_err(title))?;
            draw_line_chart_body!(chart, c, title)
        }
        (true, true) => {
            let c = builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(draw_err(title))?;
            draw_line_chart_body!(chart, c, title)
        }
    }
}

fn draw_bar_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &BarChart,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let title = chart.title.as_str();
    let ncat = chart.categories.len().max(1);
    let nser = chart.series.len().max(1);
    let mut ymax: f64 = 0.0;
    let mut ymin: f64 = 0.0;
    for (si, (_, vals)) in chart.series.iter().enumerate() {
        for (ci, v) in vals.iter().enumerate() {
            if v.is_finite() {
                let e = chart
                    .errors
                    .as_ref()
                    .and_then(|e| e.get(si))
                    .and_then(|e| e.get(ci))
                    .copied()
                    .filter(|e| e.is_finite())
                    .unwrap_or(0.0);
                ymax = ymax.max(v + e);
                ymin = ymin.min(v - e);
            }
        }
    }
    if ymax <= ymin {
        ymax = ymin + 1.0;
    }
    let pad = 0.08 * (ymax - ymin);
    let mut c = ChartBuilder::on(area)
        .caption(title, (FONT_NAME, 17))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            0f64..ncat as f64,
            (ymin - if ymin < 0.0 { pad } else { 0.0 })..(ymax + pad),
        )
        .map_err(draw_err(title))?;
    let cats = chart.categories.clone();
    c.configure_mesh()
        .disable_x_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .x_labels(ncat * 2 + 1)
        .x_label_formatter(&move |x| {
            let f = x - x.floor();
            if (f - 0.5).abs() < 1e-6 {
                cats.get(x.floor() as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .label_style((FONT_NAME, 13))
        .axis_desc_style((FONT_NAME, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(draw_err(title))?;
    let width = 0.8 / nser as f64;
    for (si, (label, vals)) in chart.series.iter().enumerate() {
        let col = palette(si);
        let bars: Vec<Rectangle<(f64, f64)>> = vals
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(ci, v)| {
                let x0 = ci as f64 + 0.1 + si as f64 * width;
                Rectangle::new([(x0, 0.0), (x0 + width * 0.92, *v)], col.filled())
            })
            .collect();
        c.draw_series(bars)
            .map_err(draw_err(title))?
            .label(label.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], col.filled()));
        if let Some(errs) = chart.errors.as_ref().and_then(|e| e.get(si)) {
            let whiskers: Vec<PathElement<(f64, f64)>> = vals
                .iter()
                .zip(errs)
                .enumerate()
                .filter(|(_, (v, e))| v.is_finite() && e.is_finite())
                .map(|(ci, (v, e))| {
                    let xm = ci as f64 + 0.1 + (si as f64 + 0.46) * width;
                    PathElement::new(vec![(xm, v - e), (xm, v + e)], BLACK.stroke_width(1))
                })
                .collect();
            c.draw_series(whiskers).map_err(draw_err(title))?;
        }
    }
    if chart.series.len() > 1 {
        c.configure_series_labels()
            .label_font((FONT_NAME, 12))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(180, 180, 180))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(draw_err(title))?;
    }
    Ok(())
}

/// One panel of a figure.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Panel {
    Line(LineChart),
    Bar(BarChart),
}

/// Renders panels stacked in a grid (`cols` columns) into an RGB buffer.
pub fn render_rgb(
    panels: &[Panel],
    cols: usize,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, PlotError> {
    register_font();
    let mut buf = vec![255u8; (width as usize) * (height as usize) * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err("figure"))?;
        let cols = cols.max(1);
        let rows = panels.len().div_ceil(cols).max(1);
        let areas = root.split_evenly((rows, cols));
        for (panel, area) in panels.iter().zip(areas.iter()) {
            match panel {
                Panel::Line(c) => draw_line_chart(area, c)?,
                Panel::Bar(c) => draw_bar_chart(area, c)?,
            }
        }
        root.present().map_err(draw_err("figure"))?;
    }
    Ok(buf)
}

/// Renders panels and encodes them as PNG bytes.
pub fn render_png(
    panels: &[Panel],
    cols: usize,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, PlotError> {
    let buf = render_rgb(panels, cols, width, height)?;
    let img = image::RgbImage::from_raw(width, height, buf).ok_or_else(|| PlotError::Draw {
        title: "figure".into(),
        msg: "buffer size mismatch".into(),
    })?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| PlotError::Draw {
            title: "figure".into(),
            msg: e.to_string(),
        })?;
    Ok(out.into_inner())
}

/// Renders panels into a PNG file.
pub fn write_png(
    path: &Path,
    panels: &[Panel],
    cols: usize,
    width: u32,
    height: u32,
) -> Result<(), PlotError> {
    let bytes = render_png(panels, cols, width, height)?;
    crate::output::write_file(path, &bytes).map_err(|e| PlotError::Write {
        path: path.display().to_string(),
        msg: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_bar_charts_render_nonblank_png() {
        let sine: Vec<(f64, f64)> = (0..200)
            .map(|i| (i as f64, (i as f64 / 20.0).sin()))
            .collect();
        let chart = LineChart {
            title: "sine".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![
                Series::line("sin", sine.clone()),
                Series::line("dashed", sine.iter().map(|(x, y)| (*x, y * 0.5)).collect())
                    .with_style(SeriesStyle::Dashed),
            ],
            bands: vec![Band {
                label: "band".into(),
                x: sine.iter().map(|p| p.0).collect(),
                lower: sine.iter().map(|p| p.1 - 0.2).collect(),
                upper: sine.iter().map(|p| p.1 + 0.2).collect(),
                color: None,
            }],
            ..Default::default()
        };
        let bars = BarChart {
            title: "bars".into(),
            categories: vec!["a".into(), "b".into()],
            series: vec![
                ("s1".into(), vec![1.0, 2.0]),
                ("s2".into(), vec![1.5, f64::NAN]),
            ],
            errors: Some(vec![vec![0.1, 0.2], vec![0.1, 0.1]]),
            ..Default::default()
        };
        let loglog = LineChart {
            title: "loglog".into(),
            series: vec![
                Series::line("p", vec![(1e-3, 1e-9), (1e-2, 1e-5), (0.1, 1e-1)])
                    .with_style(SeriesStyle::LinePoints),
            ],
            log_x: true,
            log_y: true,
            ..Default::default()
        };
        let rgb = render_rgb(
            &[Panel::Line(chart), Panel::Bar(bars), Panel::Line(loglog)],
            2,
            800,
            600,
        )
        .unwrap();
        // Something other than white was drawn (axes, text, curves).
        let non_white = rgb.chunks(3).filter(|p| p != &[255, 255, 255]).count();
        assert!(non_white > 10_000, "only {non_white} drawn pixels");
        let png = render_png(&[], 1, 100, 50).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick_label(9.999_999_999_999e-6), "1e-5");
        assert_eq!(tick_label(2.5e-7), "2.5e-7");
        assert_eq!(tick_label(0.0001), "1e-4");
        assert_eq!(tick_label(123.456), "123");
        assert_eq!(tick_label(1.5), "1.5");
        assert_eq!(tick_label(0.0123), "0.0123");
        assert_eq!(tick_label(axis_tick(-1.39e-17, false, 0.2)), "0");
        assert_eq!(tick_label(axis_tick(1e-16, true, 1.0)), "1e-16");
        assert_eq!(tick_label(-2.0e6), "-2e6");
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(16.0), "16");
    }

    #[test]
    fn empty_and_nonfinite_data_do_not_fail() {
        let chart = LineChart {
            title: "empty".into(),
            series: vec![Series::line(
                "nan",
                vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)],
            )],
            log_y: true,
            ..Default::default()
        };
        assert!(render_rgb(&[Panel::Line(chart)], 1, 300, 200).is_ok());
    }
}
