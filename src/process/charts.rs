//! Control charts as PNG, as an SPC package prints them: the location chart
//! (X̄, titled `X-bar` since the chart font has no combining bar, or individuals) with its centre line and control limits, the points
//! that complete a Western Electric pattern marked, and the specification
//! limits on an individuals chart (an X̄ chart's points are means, not
//! parts, so the specification does not belong on it); below it the range
//! chart (R or moving range) with its limits.

use super::monitor::Characteristic;
use super::run::MonitorRun;
use crate::plot::{LineChart, Panel, PlotError, Series, SeriesStyle, render_png};
use rayon::prelude::*;

/// Chart size, pixels.
pub const WIDTH: u32 = 1200;
pub const HEIGHT: u32 = 800;

fn hline(label: &str, y: f64, n: usize, color: usize) -> Series {
    Series::line(label, vec![(1.0, y), (n.max(2) as f64, y)])
        .with_style(SeriesStyle::Dashed)
        .with_color(color)
}

/// The two panels of a characteristic's chart, or None when it has no
/// chart (fewer than two values).
pub fn chart_panels(c: &Characteristic) -> Option<Vec<Panel>> {
    let ch = c.chart.as_ref()?;
    let n = ch.points.len();
    let individuals = ch.kind == "i_mr";
    let (loc, spread) = if individuals {
        ("I", "MR")
    } else {
        ("X-bar", "R")
    };
    let pts: Vec<(f64, f64)> = ch
        .points
        .iter()
        .enumerate()
        .map(|(i, &y)| ((i + 1) as f64, y))
        .collect();
    let mut series = vec![
        Series::line(format!("{loc} ({} per point)", ch.subgroup), pts.clone())
            .with_style(SeriesStyle::LinePoints)
            .with_color(0),
        hline(
            &format!("CL {}", crate::plot::tick_label(ch.cl)),
            ch.cl,
            n,
            2,
        ),
        hline("UCL", ch.ucl, n, 3),
        hline("LCL", ch.lcl, n, 3),
    ];
    if individuals && let Some(k) = &c.capability {
        for (label, lim) in [("LSL", k.lsl), ("USL", k.usl)] {
            if let Some(y) = lim {
                series.push(hline(label, y, n, 1));
            }
        }
    }
    let alarms: Vec<(f64, f64)> = ch
        .alarms
        .iter()
        .filter_map(|a| pts.get(a.point).copied())
        .collect();
    if !alarms.is_empty() {
        let rules: std::collections::BTreeSet<u8> = ch.alarms.iter().map(|a| a.rule).collect();
        let rules: Vec<String> = rules.iter().map(u8::to_string).collect();
        series.push(
            Series::line(format!("run rule {} broken", rules.join(", ")), alarms)
                .with_style(SeriesStyle::Points)
                .with_color(1),
        );
    }
    let cpk = c
        .capability
        .as_ref()
        .and_then(|k| k.cpk)
        .map_or(String::new(), |v| format!(", Cpk {v:.2}"));
    let location = LineChart {
        title: format!("{} — {loc} chart{cpk}", c.name),
        x_label: if individuals { "cycle" } else { "subgroup" }.into(),
        y_label: c.unit.into(),
        series,
        ..LineChart::default()
    };
    // Moving ranges start at the second individual.
    let first = if individuals { 2 } else { 1 };
    let ranges: Vec<(f64, f64)> = ch
        .ranges
        .iter()
        .enumerate()
        .map(|(i, &r)| ((i + first) as f64, r))
        .collect();
    let range = LineChart {
        title: format!("{spread} chart"),
        x_label: location.x_label.clone(),
        y_label: c.unit.into(),
        series: vec![
            Series::line(spread, ranges)
                .with_style(SeriesStyle::LinePoints)
                .with_color(0),
            hline("CL", ch.r_cl, n, 2),
            hline("UCL", ch.r_ucl, n, 3),
            hline("LCL", ch.r_lcl, n, 3),
        ],
        ..LineChart::default()
    };
    Some(vec![Panel::Line(location), Panel::Line(range)])
}

/// A file name for a characteristic's chart: `chart-` and its name in
/// lower case with every run of other characters as one `-`.
pub fn chart_file_name(name: &str) -> String {
    let mut slug = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            slug.push(ch.to_ascii_lowercase());
        } else if !slug.ends_with('-') {
            slug.push('-');
        }
    }
    format!("chart-{}.png", slug.trim_matches('-'))
}

/// Every characteristic's chart of the run (process values, then the
/// pins'), as (file name, PNG bytes), rendered in parallel.
pub fn chart_files(run: &MonitorRun) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
    let chars: Vec<&Characteristic> = run.spc.iter().chain(&run.pin_spc).collect();
    chars
        .par_iter()
        .filter_map(|c| {
            chart_panels(c).map(|p| {
                render_png(&p, 1, WIDTH, HEIGHT).map(|png| (chart_file_name(&c.name), png))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::process::spc::{capability, control_chart};

    #[test]
    fn file_names_are_plain_and_distinct() {
        assert_eq!(chart_file_name("peak force"), "chart-peak-force.png");
        assert_eq!(
            chart_file_name("pin r1c10 true position"),
            "chart-pin-r1c10-true-position.png"
        );
        assert_eq!(chart_file_name("Depth (µm) @ BDC"), "chart-depth-m-bdc.png");
    }

    #[test]
    fn an_individuals_chart_draws_limits_alarms_and_the_specification() {
        // One point far out: rule 1 at index 7.
        let v = [1.0, 1.1, 0.9, 1.0, 1.05, 0.95, 1.0, 3.0, 1.0, 1.02];
        let c = Characteristic {
            name: "x".into(),
            quantity: "x",
            unit: "mm",
            capability: capability(&v, 1, Some(0.0), Some(2.0)),
            chart: control_chart(&v, 1),
        };
        let p = chart_panels(&c).unwrap();
        let Panel::Line(loc) = &p[0] else { panic!() };
        let labels: Vec<&str> = loc.series.iter().map(|s| s.label.as_str()).collect();
        assert!(
            labels.contains(&"USL") && labels.contains(&"LSL"),
            "{labels:?}"
        );
        let alarm = loc.series.last().unwrap();
        assert!(alarm.label.starts_with("run rule 1"), "{labels:?}");
        assert!(alarm.points.contains(&(8.0, 3.0)));
        let Panel::Line(r) = &p[1] else { panic!() };
        assert_eq!(r.series[0].points.len(), 9);
        assert_eq!(r.series[0].points[0].0, 2.0);
        let png = render_png(&p, 1, 600, 400).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
}
