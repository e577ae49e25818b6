//! The Methods pane: the methods lab's charts (work–precision per scene,
//! fixed-step stability limits against the contact frequency, prediction
//! horizon and ensemble statistics against tolerance, where the steps go)
//! and its key tables, from [`crate::methods::dynamics`]. The quick lab
//! (seconds) runs in the background the first time the pane is shown.

use super::chart::{BarsView, ChartView};
use super::session::Session;
use super::{PaneState, csv_table, fmt_opt};
use crate::plot::Panel;
use serde::Serialize;

/// UI state: which chart.
#[derive(Debug, Clone, Default, Serialize)]
pub struct MethodsUi {
    pub chart: usize,
}

impl MethodsUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "chart" => self.chart = super::parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One row of the stability table.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityLine {
    pub method: String,
    pub variant: String,
    pub omega_contact: f64,
    pub predicted_step_s: f64,
    pub stable_step_s: Option<f64>,
    /// Measured over predicted stable step.
    pub ratio: Option<f64>,
}

/// The Methods pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct MethodsView {
    pub available: bool,
    pub effort: Option<String>,
    /// Chart titles, in order (j/k chooses).
    pub chart_titles: Vec<String>,
    pub selected: usize,
    /// The selected chart, for the terminal (a line chart or bars).
    pub chart: Option<ChartView>,
    pub bars: Option<BarsView>,
    pub stability: Vec<StabilityLine>,
    /// Fidelity across the grid: (clearance mm, rpm, level, reason).
    pub fidelity: Vec<(f64, f64, String, String)>,
    /// Failure modes seen: (what, method, outcome).
    pub failures: Vec<(String, String, String)>,
    /// Every chart of the lab (PNG export).
    pub panels: Vec<Panel>,
    pub message: Option<String>,
}

impl MethodsView {
    pub fn to_csv(&self) -> String {
        let rows: Vec<Vec<String>> = self
            .stability
            .iter()
            .map(|r| {
                vec![
                    r.method.clone(),
                    r.variant.clone(),
                    format!("{:.6e}", r.omega_contact),
                    format!("{:.6e}", r.predicted_step_s),
                    r.stable_step_s
                        .map(|x| format!("{x:.6e}"))
                        .unwrap_or_default(),
                    fmt_opt(r.ratio, 3),
                ]
            })
            .collect();
        csv_table(
            &[
                "method",
                "variant",
                "omega_contact_radps",
                "predicted_stable_step_s",
                "measured_stable_step_s",
                "measured_over_predicted",
            ],
            &rows,
        )
    }
}

pub fn view(s: &Session, ui: &PaneState) -> MethodsView {
    let Some(lab) = &s.methods else {
        return MethodsView {
            available: false,
            effort: None,
            chart_titles: Vec::new(),
            selected: 0,
            chart: None,
            bars: None,
            stability: Vec::new(),
            fidelity: Vec::new(),
            failures: Vec::new(),
            panels: Vec::new(),
            message: Some(match &s.methods_error {
                Some(e) => format!("the methods lab failed: {e}"),
                None => "the methods lab has not run yet: it runs in the background when this pane opens (r runs it again)".into(),
            }),
        };
    };
    let mut panels = lab.work_precision_panels();
    panels.extend(lab.stability_panels());
    panels.extend(lab.long_run_panels());
    panels.extend(lab.budget_panels());
    let titles: Vec<String> = panels
        .iter()
        .map(|p| match p {
            Panel::Line(c) => c.title.clone(),
            Panel::Bar(b) => b.title.clone(),
        })
        .collect();
    let selected = ui.methods.chart.min(panels.len().saturating_sub(1));
    let (chart, bars) = match panels.get(selected) {
        Some(Panel::Line(c)) => (
            Some(ChartView::from_line_chart(c, ui.chart_columns(0.6))),
            None,
        ),
        Some(Panel::Bar(b)) => (None, Some(BarsView::from_bar_chart(b))),
        None => (None, None),
    };
    let stability = lab
        .stability
        .iter()
        .map(|r| StabilityLine {
            method: r.method.clone(),
            variant: r.variant.clone(),
            omega_contact: r.omega_contact,
            predicted_step_s: r.predicted_stable_step_s,
            stable_step_s: r.measured_stable_step_s,
            ratio: r
                .measured_stable_step_s
                .map(|h| h / r.predicted_stable_step_s),
        })
        .collect();
    MethodsView {
        available: true,
        effort: Some(format!("{:?}", lab.effort).to_lowercase()),
        chart_titles: titles,
        selected,
        chart,
        bars,
        stability,
        fidelity: lab
            .fidelity
            .iter()
            .map(|f| {
                (
                    f.clearance_mm,
                    f.motor_rpm,
                    f.chosen.name().to_string(),
                    f.reason.clone(),
                )
            })
            .collect(),
        failures: lab
            .failures
            .iter()
            .map(|f| (f.what.clone(), f.method.clone(), f.outcome.clone()))
            .collect(),
        panels,
        message: None,
    }
}
