//! The Study pane: the paper's sweep (clearance × speed × material) as the
//! curves of one quantity along one factor beside the ideal mechanism, and
//! the mean displacement and speed deviations as bars.
//!
//! The charts are [`crate::sim::sweep::SweepResult::curve_panels`] and
//! `bar_panels` (the same descriptions `pinsight sweep` writes as PNG),
//! decimated to the terminal's width.

use super::chart::{BarsView, ChartView};
use super::session::Session;
use super::{PaneState, fmt_opt, parse_usize};
use crate::plot::Panel;
use crate::sim::sweep::Factor;
use serde::Serialize;

/// The quantities of the curve charts, in `curve_panels` order.
pub const QUANTITIES: [&str; 4] = ["stroke", "speed", "acceleration", "torque"];

/// UI state of the Study pane.
#[derive(Debug, Clone, Serialize)]
pub struct StudyUi {
    pub factor: Factor,
    /// Index into [`QUANTITIES`].
    pub quantity: usize,
}

impl Default for StudyUi {
    fn default() -> Self {
        Self {
            factor: Factor::Clearance,
            quantity: 0,
        }
    }
}

impl StudyUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "factor" => {
                self.factor = Factor::ALL
                    .into_iter()
                    .find(|f| f.name() == v.trim())
                    .ok_or_else(|| format!("factor `{v}` (allowed: clearance, speed, material)"))?
            }
            "quantity" => {
                self.quantity = match QUANTITIES.iter().position(|q| *q == v.trim()) {
                    Some(i) => i,
                    None => {
                        let i = parse_usize(v).map_err(|_| {
                            format!("quantity `{v}` (allowed: {})", QUANTITIES.join(", "))
                        })?;
                        if i >= QUANTITIES.len() {
                            return Err(format!("quantity {i} (allowed: 0–3)"));
                        }
                        i
                    }
                }
            }
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }

    pub fn next_factor(&mut self) {
        let i = Factor::ALL
            .iter()
            .position(|f| *f == self.factor)
            .unwrap_or(0);
        self.factor = Factor::ALL[(i + 1) % Factor::ALL.len()];
    }

    pub fn next_quantity(&mut self, forward: bool) {
        let n = QUANTITIES.len();
        self.quantity = if forward {
            (self.quantity + 1) % n
        } else {
            (self.quantity + n - 1) % n
        };
    }
}

/// One case on the chosen factor's line.
#[derive(Debug, Clone, Serialize)]
pub struct CaseRow {
    pub label: String,
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub material: String,
    pub disp_dev_mean_mm: Option<f64>,
    pub vel_dev_mean_mps: Option<f64>,
    pub impacts: Option<u64>,
    pub error: Option<String>,
}

impl super::table::Cells for CaseRow {
    const HEADER: &'static [&'static str] = &[
        "case",
        "clearance_mm",
        "motor_rpm",
        "material",
        "disp_dev_mean_mm",
        "vel_dev_mean_mps",
        "impacts",
        "error",
    ];
    fn cells(&self, num: &dyn Fn(Option<f64>) -> String) -> Vec<String> {
        vec![
            self.label.clone(),
            self.clearance_mm.to_string(),
            self.motor_rpm.to_string(),
            self.material.clone(),
            num(self.disp_dev_mean_mm),
            num(self.vel_dev_mean_mps),
            self.impacts.map(|n| n.to_string()).unwrap_or_default(),
            self.error.clone().unwrap_or_default(),
        ]
    }
}

/// The Study pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct StudyView {
    pub factor: String,
    pub quantity: String,
    /// The grid and protocol (what `r` runs, or what was run).
    pub setup: String,
    pub cases_total: usize,
    pub cases_failed: usize,
    pub ran: bool,
    /// The nominal point the lines go through.
    pub nominal: Option<String>,
    pub curves: Option<ChartView>,
    pub bars: Vec<BarsView>,
    pub line: Vec<CaseRow>,
    pub error: Option<String>,
    pub message: Option<String>,
}

impl StudyView {
    pub fn to_csv(&self) -> String {
        super::table::csv_of(&self.line, &|x| fmt_opt(x, 6))
    }

    pub fn panels(&self) -> Vec<Panel> {
        let mut p: Vec<Panel> = self.curves.iter().map(|c| c.to_panel()).collect();
        p.extend(self.bars.iter().map(|b| b.to_panel()));
        p
    }
}

fn fmt_list(v: &[f64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn view(s: &Session, ui: &PaneState) -> StudyView {
    let st = &ui.study;
    let f = st.factor;
    let q = st.quantity.min(QUANTITIES.len() - 1);
    let g = &s.study_setup.grid;
    let setup = format!(
        "c ∈ {{{}}} mm × {{{}}} rpm × {} materials; {} + {} revolutions per case",
        fmt_list(&g.clearances_mm),
        fmt_list(&g.speeds_rpm),
        g.materials.len(),
        s.study_setup.warmup,
        s.study_setup.revs
    );
    let Some(r) = &s.study else {
        return StudyView {
            factor: f.name().into(),
            quantity: QUANTITIES[q].into(),
            setup,
            cases_total: g.len(),
            cases_failed: 0,
            ran: false,
            nominal: None,
            curves: None,
            bars: Vec::new(),
            line: Vec::new(),
            error: s.study_error.clone(),
            message: Some(format!(
                "the study has not run yet: press r to run its {} cases in the background",
                g.len()
            )),
        };
    };
    let cols = ui.chart_columns(0.6);
    let curves = r.curve_panels(f).into_iter().nth(q).and_then(|p| match p {
        Panel::Line(c) => Some(ChartView::from_line_chart(&c, cols)),
        Panel::Bar(_) => None,
    });
    let bars = r
        .bar_panels(f)
        .iter()
        .filter_map(|p| match p {
            Panel::Bar(b) => Some(BarsView::from_bar_chart(b)),
            Panel::Line(_) => None,
        })
        .collect();
    let line = r
        .line(f)
        .into_iter()
        .map(|c| CaseRow {
            label: match f {
                Factor::Clearance => format!("c = {} mm", c.clearance_mm),
                Factor::Speed => format!("{} rpm", c.motor_rpm),
                Factor::Material => c.material.clone(),
            },
            clearance_mm: c.clearance_mm,
            motor_rpm: c.motor_rpm,
            material: c.material.clone(),
            disp_dev_mean_mm: c.summary.as_ref().map(|s| s.disp_dev_mean_mm),
            vel_dev_mean_mps: c.summary.as_ref().map(|s| s.vel_dev_mean_mps),
            impacts: c.summary.as_ref().map(|s| s.n_impacts),
            error: c.error.clone(),
        })
        .collect();
    StudyView {
        factor: f.name().into(),
        quantity: QUANTITIES[q].into(),
        setup,
        cases_total: r.cases.len(),
        cases_failed: r.failed,
        ran: true,
        nominal: Some(format!(
            "nominal: c = {} mm, {} rpm, {}",
            crate::fmt::plain(r.nominal.clearance_mm),
            crate::fmt::plain(r.nominal.motor_rpm),
            r.nominal.material
        )),
        curves,
        bars,
        line,
        error: s.study_error.clone(),
        message: None,
    }
}
