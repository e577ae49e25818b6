//! The wear trend's result and its forms: JSON (serde), CSV (one row per
//! calibrated log), Markdown (what a maintenance planner reads) and a PNG
//! chart per head (clearance ± U95 against the abscissa, the fitted line
//! with its confidence band, the limit and the forecast crossing).

use super::archard::ArchardFit;
use super::fit::{LineFit, t_quantile};
use super::forecast::Forecast;
use super::history::{Abscissa, HistoryPoint};
use super::limit::ClearanceLimit;
use crate::plot::{Band, LineChart, Panel, Series, SeriesStyle};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The degradation model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum WearModel {
    /// Clearance linear in cumulative cycles (or days).
    #[default]
    Linear,
    /// Archard: dc/dn = k·W(c), W the simulated sliding work per cycle
    /// ([`super::archard`]); needs the head's cycle counter.
    Archard,
}

impl WearModel {
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "linear" => Ok(WearModel::Linear),
            "archard" => Ok(WearModel::Archard),
            _ => Err(format!("--model '{s}': expected linear or archard")),
        }
    }
}

/// A log that could not be part of the trend, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ItemError {
    pub file: String,
    pub error: String,
}

/// One head's trend.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HeadTrend {
    pub rig: String,
    /// Ordered by start time, then cycles.
    pub points: Vec<HistoryPoint>,
    pub abscissa: Option<Abscissa>,
    /// The abscissa of each point (cycles or days).
    pub x: Vec<f64>,
    /// The straight line fitted: the clearance against x (linear model), or
    /// G(c) = ∫dc/W against cycles (Archard: the slope is k).
    pub fit: Result<LineFit, String>,
    /// The Archard fit's k, W(c) and the wear rate now (`--model archard`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub archard: Option<ArchardFit>,
    pub cycles_per_day: Option<f64>,
    pub limit: Option<ClearanceLimit>,
    pub forecast: Result<Forecast, String>,
    /// One sentence: the answer.
    pub verdict: String,
    pub notes: Vec<String>,
}

/// The trend over all logs given.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrendReport {
    pub model: WearModel,
    /// The forecast interval's level.
    pub level: f64,
    /// Logs found, calibrated now, taken from the cache.
    pub logs: usize,
    pub calibrated: usize,
    pub cached: usize,
    pub errors: Vec<ItemError>,
    pub heads: Vec<HeadTrend>,
    pub assumptions: Vec<String>,
    pub wall_ms: f64,
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or("-".into(), |v| format!("{v:.digits$}"))
}

fn number(x: f64) -> String {
    if x.abs() >= 1e4 || (x != 0.0 && x.abs() < 1e-3) {
        format!("{x:.4e}")
    } else {
        format!("{x:.4}")
    }
}

impl HeadTrend {
    /// The fitted clearance (mm) at abscissa x: the line, or G⁻¹ of it (Archard).
    pub fn fitted_mm(&self, x: f64) -> Option<f64> {
        let f = self.fit.as_ref().ok()?;
        Some(match &self.archard {
            Some(a) => a.work.g_inv(f.at(x)),
            None => f.at(x),
        })
    }

    /// The fit's confidence band (mm) at x for the t factor `t`.
    pub fn band_mm(&self, x: f64, t: f64) -> Option<(f64, f64)> {
        let f = self.fit.as_ref().ok()?;
        let (lo, hi) = (f.at(x) - t * f.se_at(x), f.at(x) + t * f.se_at(x));
        Some(match &self.archard {
            Some(a) => (a.work.g_inv(lo), a.work.g_inv(hi)),
            None => (lo, hi),
        })
    }

    /// The wear rate as one line: the slope (linear), or k and the rate at
    /// the last log (Archard).
    pub fn rate_text(&self) -> String {
        let unit = self.abscissa.map_or("", |a| a.unit()).trim_end_matches('s');
        let f = match &self.fit {
            Ok(f) => f,
            Err(e) => return format!("no fit: {e}"),
        };
        let gof = format!("R² {:.3}, χ²/ν {:.2} (ν = {})", f.r2, f.chi2_red, f.dof);
        match &self.archard {
            Some(a) => format!(
                "Archard k {} mm/J (95 % [{}, {}]); wear now {} mm per {unit} [{}, {}] at {:.3} mm ({:.3e} J/cycle sliding work); {gof}",
                number(a.k_mm_per_j),
                number(a.k_lo95),
                number(a.k_hi95),
                number(a.rate_now),
                number(a.rate_now_lo95),
                number(a.rate_now_hi95),
                a.clearance_now_mm,
                a.work.work_at(a.clearance_now_mm)
            ),
            None => format!(
                "wear rate {} mm per {unit} (95 % [{}, {}]), clearance at 0: {:.4} mm; {gof}",
                number(f.slope),
                number(f.slope_lo95),
                number(f.slope_hi95),
                f.intercept
            ),
        }
    }

    /// The forecast as a sentence.
    pub fn forecast_text(&self) -> String {
        let unit = self.abscissa.map_or("", |a| a.unit());
        match &self.forecast {
            Ok(f) => {
                let hi = f
                    .remaining_hi
                    .map_or("∞".to_string(), |h| format!("{h:.0}"));
                let mut s = format!(
                    "limit {:.3} mm reached in {:.0} {unit} ({:.0} % interval [{:.0}, {hi}])",
                    f.limit_mm,
                    f.remaining,
                    f.level * 100.0,
                    f.remaining_lo
                );
                if let (Some(d), Some(lo)) = (f.days, f.days_lo) {
                    let dhi = f.days_hi.map_or("∞".to_string(), |h| format!("{h:.1}"));
                    let _ = write!(s, " ≈ {d:.1} days [{lo:.1}, {dhi}]");
                }
                if f.reached {
                    s.push_str(" — the fitted clearance is already past the limit");
                }
                s
            }
            Err(e) => format!("no forecast: {e}"),
        }
    }
}

impl TrendReport {
    /// One row per calibrated log.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "rig,file,sha256,start_utc,head_cycles,x,abscissa,cycles,motor_rpm,clearance_mm,sigma_mm,u95_mm,fitted_mm\n",
        );
        for h in &self.heads {
            for (p, x) in h.points.iter().zip(&h.x) {
                let fitted = h.fitted_mm(*x);
                let _ = writeln!(
                    s,
                    "{},{},{},{},{},{},{},{},{:.2},{:.6},{:.6},{:.6},{}",
                    csv_field(&h.rig),
                    csv_field(&p.file),
                    p.sha256,
                    p.start_utc,
                    opt(p.head_cycles, 0),
                    x,
                    h.abscissa.map_or("", |a| a.unit()),
                    p.cycles,
                    p.motor_rpm,
                    p.clearance_mm,
                    p.sigma_mm,
                    p.u95_mm,
                    opt(fitted, 6)
                );
            }
        }
        s
    }

    /// What a maintenance planner reads.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# Wear trend\n\n");
        let _ = writeln!(
            s,
            "{} logs: {} calibrated now, {} from the cache, {} left out. Model: {:?}.\n",
            self.logs,
            self.calibrated,
            self.cached,
            self.errors.len(),
            self.model
        );
        for h in &self.heads {
            let _ = writeln!(s, "## Head `{}`\n\n**{}**\n", h.rig, h.verdict);
            let _ = writeln!(s, "- {}", h.rate_text());
            if let Ok(f) = &h.fit
                && f.birge_scaled
            {
                s.push_str("- the scatter exceeds the calibrations' U95: the fit's uncertainty is scaled by χ²/ν\n");
            }
            if let Some(a) = &h.archard {
                s.push_str("\n| clearance mm | sliding work J/cycle | ± s.e. | peak contact force N |\n|---:|---:|---:|---:|\n");
                for p in &a.work.ladder {
                    let _ = writeln!(
                        s,
                        "| {:.3} | {:.4e} | {:.1e} | {:.1} |",
                        p.clearance_mm, p.work_j, p.work_se_j, p.peak_force_n
                    );
                }
                s.push('\n');
                for n in &a.notes {
                    let _ = writeln!(s, "- note: {n}");
                }
            }
            if let Some(l) = &h.limit {
                let _ = writeln!(s, "- limit: {} mm ({})", opt(l.limit_mm, 3), l.criterion);
                if !l.ladder.is_empty() {
                    s.push_str("\n| clearance mm | depth error mm | depth sd mm | used mm | predicted yield |\n|---:|---:|---:|---:|---:|\n");
                    for p in &l.ladder {
                        let _ = writeln!(
                            s,
                            "| {:.3} | {:.4} | {:.4} | {:.4} | {:.3} |",
                            p.clearance_mm,
                            p.depth_error_mm,
                            p.depth_sd_mm,
                            p.used_mm,
                            p.predicted_yield
                        );
                    }
                    s.push('\n');
                }
                for n in &l.notes {
                    let _ = writeln!(s, "- note: {n}");
                }
            }
            let _ = writeln!(s, "- {}", h.forecast_text());
            for n in &h.notes {
                let _ = writeln!(s, "- note: {n}");
            }
            s.push_str("\n| start (UTC) | head cycles | clearance mm | U95 mm | file |\n|---|---:|---:|---:|---|\n");
            for p in &h.points {
                let _ = writeln!(
                    s,
                    "| {} | {} | {:.4} | {:.4} | {} |",
                    p.start_utc,
                    opt(p.head_cycles, 0),
                    p.clearance_mm,
                    p.u95_mm,
                    p.file
                );
            }
            s.push('\n');
        }
        if !self.errors.is_empty() {
            s.push_str("## Left out\n\n");
            for e in &self.errors {
                let _ = writeln!(s, "- `{}`: {}", e.file, e.error);
            }
            s.push('\n');
        }
        s.push_str("## Assumptions\n\n");
        for a in &self.assumptions {
            let _ = writeln!(s, "- {a}");
        }
        s
    }

    /// One chart per head: clearance ± U95, the fit and its band, the limit.
    pub fn panels(&self) -> Vec<Panel> {
        self.heads
            .iter()
            .map(|h| Panel::Line(head_chart(h, self.level)))
            .collect()
    }

    /// The chart as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>, crate::plot::PlotError> {
        let panels = self.panels();
        let n = panels.len().max(1) as u32;
        crate::plot::render_png(&panels, 1, 1000, 520 * n)
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The head's chart (see the module docs).
pub fn head_chart(h: &HeadTrend, level: f64) -> LineChart {
    let unit = h.abscissa.map_or("log", |a| a.unit());
    let pts: Vec<(f64, f64)> =
        h.x.iter()
            .zip(&h.points)
            .map(|(x, p)| (*x, p.clearance_mm))
            .collect();
    let mut chart = LineChart {
        title: format!("head {}: clearance ± U95", h.rig),
        x_label: unit.to_string(),
        y_label: "clearance (mm)".into(),
        ..LineChart::default()
    };
    chart.bands.push(Band {
        label: "± U95 of each log".into(),
        x: h.x.clone(),
        lower: h.points.iter().map(|p| p.clearance_mm - p.u95_mm).collect(),
        upper: h.points.iter().map(|p| p.clearance_mm + p.u95_mm).collect(),
        color: Some(0),
    });
    chart.series.push(
        Series::line("calibrated", pts)
            .with_style(SeriesStyle::Points)
            .with_color(0),
    );
    let x_last = h.x.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let x_first = h.x.iter().cloned().fold(f64::INFINITY, f64::min);
    if let Ok(f) = &h.fit {
        let x_end = match &h.forecast {
            Ok(fc) => fc.at_hi.unwrap_or(fc.at).max(fc.at).max(x_last),
            Err(_) => x_last,
        };
        let x_end = if x_end.is_finite() { x_end } else { x_last };
        let t = t_quantile(0.5 + level / 2.0, f.dof as f64);
        let xs: Vec<f64> = (0..=60)
            .map(|i| x_first + (x_end - x_first) * i as f64 / 60.0)
            .collect();
        let band: Vec<(f64, f64)> = xs
            .iter()
            .map(|x| h.band_mm(*x, t).unwrap_or((f64::NAN, f64::NAN)))
            .collect();
        chart.bands.push(Band {
            label: format!("fit {:.0} % band", level * 100.0),
            x: xs.clone(),
            lower: band.iter().map(|b| b.0).collect(),
            upper: band.iter().map(|b| b.1).collect(),
            color: Some(1),
        });
        let name = if h.archard.is_some() {
            "Archard fit"
        } else {
            "linear fit"
        };
        chart.series.push(
            Series::line(
                name,
                xs.iter()
                    .map(|x| (*x, h.fitted_mm(*x).unwrap_or(f64::NAN)))
                    .collect(),
            )
            .with_color(1),
        );
        if let Some(l) = h.limit.as_ref().and_then(|l| l.limit_mm) {
            chart.series.push(
                Series::line("limit", vec![(x_first, l), (x_end, l)])
                    .with_style(SeriesStyle::Dashed)
                    .with_color(3),
            );
        }
    }
    chart
}
