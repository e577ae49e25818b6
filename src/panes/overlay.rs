//! The Overlay pane: measured against predicted stroke and force for the
//! chosen cycle (or the envelope of all cycles), the residual beneath, the
//! per-cycle figures, and the fidelity level in use and why.
//!
//! Measured data needs a rig log and the `pinsight::overlay` module; until
//! both are in the session the pane shows the prediction alone and says
//! what is missing.

use super::chart::{ChartView, SeriesKind, SeriesView, decimate_points};
use super::session::Session;
use super::{PaneState, csv_table, parse_usize};
use serde::Serialize;

/// UI state: which log and which cycle (None = envelope of all cycles).
#[derive(Debug, Clone, Default, Serialize)]
pub struct OverlayUi {
    pub log: usize,
    pub cycle: Option<usize>,
}

impl OverlayUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "cycle" => {
                self.cycle = if v.trim() == "envelope" || v.trim() == "all" {
                    None
                } else {
                    Some(parse_usize(v)?)
                }
            }
            "log" => self.log = parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One cycle's figures.
#[derive(Debug, Clone, Serialize)]
pub struct CycleRow {
    pub index: u64,
    pub stroke_rms_mm: Option<f64>,
    pub force_rms_n: Option<f64>,
    pub stroke_max_mm: Option<f64>,
    pub force_max_n: Option<f64>,
    pub note: String,
}

/// The Overlay pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayView {
    /// The measured log, when there is one.
    pub source: Option<String>,
    /// "cycle k" or "envelope".
    pub showing: String,
    pub stroke: Option<ChartView>,
    pub force: Option<ChartView>,
    pub residual: Option<ChartView>,
    pub cycles: Vec<CycleRow>,
    pub selected: Option<usize>,
    /// Figures over every cycle (RMS of residuals …).
    pub figures: Vec<(String, f64)>,
    pub level: Option<String>,
    pub level_reason: Option<String>,
    pub message: Option<String>,
}

impl OverlayView {
    pub fn charts(&self) -> Vec<&ChartView> {
        [&self.stroke, &self.force, &self.residual]
            .into_iter()
            .flatten()
            .collect()
    }

    pub fn to_csv(&self) -> String {
        let f = |x: Option<f64>| x.map(|v| format!("{v:.6}")).unwrap_or_default();
        let rows: Vec<Vec<String>> = self
            .cycles
            .iter()
            .map(|c| {
                vec![
                    c.index.to_string(),
                    f(c.stroke_rms_mm),
                    f(c.force_rms_n),
                    f(c.stroke_max_mm),
                    f(c.force_max_n),
                    c.note.clone(),
                ]
            })
            .collect();
        csv_table(
            &[
                "cycle",
                "stroke_rms_mm",
                "force_rms_n",
                "stroke_max_abs_mm",
                "force_max_abs_n",
                "note",
            ],
            &rows,
        )
    }
}

pub fn view(s: &Session, ui: &PaneState) -> OverlayView {
    let cols = ui.chart_columns(0.6);
    let run = s.model.as_ref();
    let mut v = OverlayView {
        source: None,
        showing: "prediction only".into(),
        stroke: None,
        force: None,
        residual: None,
        cycles: Vec::new(),
        selected: None,
        figures: Vec::new(),
        level: run.map(|r| r.level.name().to_string()),
        level_reason: run.map(|r| r.level_reason.clone()),
        message: None,
    };
    let mut missing = Vec::new();
    if s.logs.is_empty() {
        missing.push("no rig log loaded (open a .mcap log with o)");
    }
    missing.push("measured-vs-predicted comparison needs the overlay module (not on main yet)");
    v.message = Some(format!("prediction only: {}", missing.join("; ")));
    if let Some(r) = run {
        if let Some(c) = &r.result.curves {
            // The last reported revolution against crank angle.
            let n = c.len();
            let per_rev = (360.0 / r.options.grid_deg.unwrap_or(0.5)).round() as usize + 1;
            let start = n.saturating_sub(per_rev);
            let pts = |y: &Vec<f64>| -> Vec<(f64, f64)> {
                let mut out = Vec::new();
                for i in start..n {
                    if i > start && c.crank_deg[i] < c.crank_deg[i - 1] {
                        out.push((f64::NAN, f64::NAN));
                    }
                    out.push((c.crank_deg[i], y[i]));
                }
                decimate_points(&out, 0.0, 360.0, cols)
            };
            let series = |name: &str, y: &Vec<f64>, color: usize, kind| SeriesView {
                name: name.into(),
                color,
                kind,
                points: pts(y),
            };
            v.stroke = Some(ChartView::new(
                "stroke — last reported revolution",
                "crank angle θ2 (°)",
                "mm",
                vec![
                    series("predicted", &c.stroke_mm, 1, SeriesKind::Line),
                    series("ideal", &c.ideal_stroke_mm, 8, SeriesKind::Reference),
                ],
                Some([0.0, 360.0]),
            ));
            if c.process_force_n.iter().any(|x| x.is_finite()) {
                v.force = Some(ChartView::new(
                    "load-cell force — last reported revolution",
                    "crank angle θ2 (°)",
                    "N",
                    vec![series("predicted", &c.process_force_n, 1, SeriesKind::Line)],
                    Some([0.0, 360.0]),
                ));
            }
        }
    } else if s.model_error.is_none() {
        v.message = Some("the model has not run yet".into());
    }
    v
}
