//! The Trend pane: a head's clearance history (each log ± U95), the fitted
//! wear line, the limit and the forecast in a maintenance planner's words.
//!
//! The trend itself ([`crate::engine::trend::trend_session`]) runs on the
//! TUI's worker or in a batch `run trend` step; this view only reads its
//! result from the session.

use super::PaneState;
use super::chart::{ChartView, SeriesKind, SeriesView, finite_bounds, pad_bounds, ticks};
use super::session::Session;
use crate::wear::TrendReport;
use serde::Serialize;
use std::sync::Arc;

/// UI state of the Trend pane: the head shown.
#[derive(Debug, Clone, Default, Serialize)]
pub struct TrendUi {
    pub head: usize,
}

impl TrendUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "head" => self.head = super::parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One log of the history table.
#[derive(Debug, Clone, Serialize)]
pub struct HistoryRow {
    pub start: String,
    pub x: f64,
    pub clearance_mm: f64,
    pub u95_mm: f64,
}

/// The Trend pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct TrendView {
    pub heads: Vec<String>,
    pub head: usize,
    pub rig: Option<String>,
    pub verdict: Option<String>,
    /// Wear rate, limit and forecast as lines of text.
    pub facts: Vec<String>,
    pub history: Vec<HistoryRow>,
    pub chart: Option<ChartView>,
    /// Logs left out, with why.
    pub left_out: Vec<String>,
    /// Days to the limit (point), for batch checks (`trend.days_to_limit`).
    pub days_to_limit: Option<f64>,
    pub pending: bool,
    pub message: Option<String>,
    /// The whole result (what `pinsight trend --json` prints).
    pub report: Option<Arc<TrendReport>>,
}

impl TrendView {
    /// One row per log of the head shown.
    pub fn to_csv(&self) -> String {
        let rows: Vec<Vec<String>> = self
            .history
            .iter()
            .map(|r| {
                vec![
                    r.start.clone(),
                    format!("{}", r.x),
                    format!("{:.6}", r.clearance_mm),
                    format!("{:.6}", r.u95_mm),
                ]
            })
            .collect();
        super::csv_table(&["start_utc", "x", "clearance_mm", "u95_mm"], &rows)
    }
}

/// Short numbers for a narrow column.
fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "–".into()
    }
}

/// The wear rate, the fit's quality, the limit and the forecast in short
/// lines (each fits a 38-column box at 80×24; the report's sentences are
/// in `trend.md` and the JSON).
fn compact_facts(h: &crate::wear::HeadTrend) -> Vec<String> {
    let unit = h.abscissa.map_or("", |a| a.unit()).trim_end_matches('s');
    let mut out = Vec::new();
    match (&h.fit, &h.archard) {
        (Ok(f), Some(a)) => {
            out.push(format!(
                "wear {} [{}, {}] mm/{unit}",
                sci(a.rate_now),
                sci(a.rate_now_lo95),
                sci(a.rate_now_hi95)
            ));
            out.push(format!(
                "Archard k {} mm/J, R² {:.3}, χ²/ν {:.2}",
                sci(a.k_mm_per_j),
                f.r2,
                f.chi2_red
            ));
        }
        (Ok(f), None) => {
            out.push(format!(
                "wear {} [{}, {}] mm/{unit}",
                sci(f.slope),
                sci(f.slope_lo95),
                sci(f.slope_hi95)
            ));
            out.push(format!(
                "R² {:.3}, χ²/ν {:.2} (ν = {}), 95 %",
                f.r2, f.chi2_red, f.dof
            ));
        }
        (Err(e), _) => out.push(format!("no fit: {e}")),
    }
    if let Some(l) = &h.limit {
        out.push(match (l.limit_mm, l.tolerance_mm) {
            (Some(x), Some(t)) => format!("limit {x:.3} mm (model, ±{t} mm)"),
            (Some(x), None) => format!("limit {x:.3} mm (given)"),
            (None, _) => "no limit within the ladder".into(),
        });
    }
    match &h.forecast {
        Ok(f) if f.reached => out.push("limit reached at the last log".into()),
        Ok(f) => {
            match f.days {
                Some(d) => out.push(format!("in {} {unit}s ≈ {d:.1} d", sci(f.remaining))),
                None => out.push(format!("in {} {unit}s", sci(f.remaining))),
            }
            let pct = f.level * 100.0;
            match (f.days_lo, f.days_hi, f.days) {
                (Some(lo), hi, Some(_)) => out.push(format!(
                    "  {pct:.0} % [{lo:.1}, {}] days",
                    hi.map_or("∞".into(), |h| format!("{h:.1}"))
                )),
                _ => out.push(format!(
                    "  {pct:.0} % [{}, {}]",
                    sci(f.remaining_lo),
                    f.remaining_hi.map_or("∞".into(), sci)
                )),
            }
        }
        Err(e) => out.push(format!("no forecast: {e}")),
    }
    out
}

fn empty(message: String, pending: bool) -> TrendView {
    TrendView {
        heads: Vec::new(),
        head: 0,
        rig: None,
        verdict: None,
        facts: Vec::new(),
        history: Vec::new(),
        chart: None,
        left_out: Vec::new(),
        days_to_limit: None,
        pending,
        message: Some(message),
        report: None,
    }
}

/// Computes the Trend pane's view.
pub fn view(s: &Session, ui: &PaneState) -> TrendView {
    if s.logs.is_empty() {
        return empty(
            "no rig log loaded: open the logs of a head (o), a folder of them, and a side-view recipe for the limit".into(),
            false,
        );
    }
    let rep = match &s.trend {
        None => {
            return empty(
                format!("trend over {} log(s) not run yet (r runs it)", s.logs.len()),
                true,
            );
        }
        Some(Err(e)) => return empty(format!("trend: {e}"), false),
        Some(Ok(r)) => r,
    };
    let mut v = empty(String::new(), false);
    v.message = None;
    v.report = Some(Arc::clone(rep));
    // The file's name (not its folder) and why: one line at 80 columns.
    v.left_out = rep
        .errors
        .iter()
        .map(|e| {
            let name = std::path::Path::new(&e.file)
                .file_name()
                .map_or(e.file.clone(), |n| n.to_string_lossy().into_owned());
            format!("left out {name}: {}", e.error)
        })
        .collect();
    v.heads = rep.heads.iter().map(|h| h.rig.clone()).collect();
    let Some(h) = rep
        .heads
        .get(ui.trend.head.min(rep.heads.len().saturating_sub(1)))
    else {
        v.message = Some("no log could be calibrated".into());
        return v;
    };
    v.head = ui.trend.head.min(rep.heads.len() - 1);
    v.rig = Some(h.rig.clone());
    v.verdict = Some(h.verdict.clone());
    v.facts.extend(compact_facts(h));
    v.days_to_limit = h.forecast.as_ref().ok().and_then(|f| f.days);
    v.history = h
        .points
        .iter()
        .zip(&h.x)
        .map(|(p, x)| HistoryRow {
            start: p.start_utc.chars().take(10).collect(),
            x: *x,
            clearance_mm: p.clearance_mm,
            u95_mm: p.u95_mm,
        })
        .collect();
    let chart = crate::wear::report::head_chart(h, rep.level);
    let mut c = ChartView::from_line_chart(&chart, ui.width.max(20) as usize);
    // The fit's confidence band as two reference lines.
    if let Some(b) = chart.bands.get(1) {
        for (name, ys) in [("band", &b.lower), ("", &b.upper)] {
            c.series.push(SeriesView {
                name: name.into(),
                color: 1,
                kind: SeriesKind::Reference,
                points: b.x.iter().copied().zip(ys.iter().copied()).collect(),
            });
        }
    }
    // U95 bars: one short vertical segment per log.
    for (i, (p, x)) in h.points.iter().zip(&h.x).enumerate() {
        c.series.push(SeriesView {
            name: if i == 0 {
                "± U95".into()
            } else {
                String::new()
            },
            color: 0,
            kind: SeriesKind::Reference,
            points: vec![
                (*x, p.clearance_mm - p.u95_mm),
                (*x, p.clearance_mm + p.u95_mm),
            ],
        });
    }
    c.y_bounds = pad_bounds(finite_bounds(
        c.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
    ));
    c.y_ticks = ticks(c.y_bounds);
    v.chart = Some(c);
    v
}
