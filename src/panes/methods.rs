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

/// One localiser of the vision lab: pin-centre error and cost.
#[derive(Debug, Clone, Serialize)]
pub struct LocaliserLine {
    pub localiser: String,
    /// RMS centre error without noise, px.
    pub rms_px_clean: Option<f64>,
    /// RMS centre error at σ = 8 DN, px.
    pub rms_px_noise8: Option<f64>,
    /// Median time per tip, µs (the noise-free row).
    pub time_us_per_pin: Option<f64>,
}

/// Where the vision pipeline stops giving the right verdicts along one
/// degradation axis: the first level whose verdict accuracy falls below
/// [`VERDICT_OK`] (None: it held over every level tried).
#[derive(Debug, Clone, Serialize)]
pub struct BreakdownLine {
    pub factor: String,
    /// The localisers with these limits ("all" when every one shares them).
    pub localisers: String,
    /// Last level still at or above [`VERDICT_OK`].
    pub holds_to: Option<f64>,
    pub breaks_at: Option<f64>,
}

/// The verdict accuracy a localiser must keep to count as working.
pub const VERDICT_OK: f64 = 0.9;

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
    /// The vision lab's localisers at their lowest noise and at 8 DN.
    pub localisers: Vec<LocaliserLine>,
    /// Where each localiser's pipeline breaks, per degradation factor.
    pub breakdown: Vec<BreakdownLine>,
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
    let Some(labs) = &s.methods else {
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
            localisers: Vec::new(),
            breakdown: Vec::new(),
            panels: Vec::new(),
            message: Some(match &s.methods_error {
                Some(e) => format!("the methods lab failed: {e}"),
                None => "the methods lab has not run yet: it runs in the background when this pane opens (r runs it again)".into(),
            }),
        };
    };
    let lab = &labs.dynamics;
    let mut panels = lab.work_precision_panels();
    panels.extend(lab.stability_panels());
    panels.extend(lab.long_run_panels());
    panels.extend(lab.budget_panels());
    if let Some(v) = &labs.vision {
        panels.extend(crate::vision::lab::lab_panels(v));
    }
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
        localisers: labs
            .vision
            .as_ref()
            .map(localiser_lines)
            .unwrap_or_default(),
        breakdown: labs
            .vision
            .as_ref()
            .map(breakdown_lines)
            .unwrap_or_default(),
        panels,
        message: None,
    }
}

fn localiser_lines(v: &crate::vision::lab::VisionLab) -> Vec<LocaliserLine> {
    crate::vision::measure::Localiser::ALL
        .iter()
        .map(|l| {
            let rows: Vec<_> = v
                .speed_accuracy
                .iter()
                .filter(|r| r.localiser == *l)
                .collect();
            let clean = rows
                .iter()
                .min_by(|a, b| a.noise_dn.total_cmp(&b.noise_dn))
                .copied();
            LocaliserLine {
                localiser: l.name().to_string(),
                rms_px_clean: clean.map(|r| r.rms_px),
                rms_px_noise8: rows.iter().find(|r| r.noise_dn == 8.0).map(|r| r.rms_px),
                time_us_per_pin: clean.map(|r| r.time_us_per_pin),
            }
        })
        .collect()
}

fn breakdown_lines(v: &crate::vision::lab::VisionLab) -> Vec<BreakdownLine> {
    let mut out = Vec::new();
    for factor in ["noise", "blur", "contrast", "rotation"] {
        // (holds_to, breaks_at) per localiser, grouped when equal.
        let mut groups: Vec<(Option<f64>, Option<f64>, Vec<&str>)> = Vec::new();
        for l in crate::vision::measure::Localiser::ALL {
            // Levels run from mild to severe in the lab's order.
            let rows: Vec<_> = v
                .degradation
                .iter()
                .filter(|r| r.factor == factor && r.localiser == l)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let first_bad = rows.iter().position(|r| r.verdict_accuracy < VERDICT_OK);
            let holds_to = match first_bad {
                Some(0) => None,
                Some(k) => Some(rows[k - 1].level),
                None => rows.last().map(|r| r.level),
            };
            let breaks_at = first_bad.map(|k| rows[k].level);
            match groups
                .iter_mut()
                .find(|g| g.0 == holds_to && g.1 == breaks_at)
            {
                Some(g) => g.2.push(l.name()),
                None => groups.push((holds_to, breaks_at, vec![l.name()])),
            }
        }
        let single = groups.len() == 1;
        for (holds_to, breaks_at, names) in groups {
            out.push(BreakdownLine {
                factor: factor.to_string(),
                localisers: if single && names.len() > 1 {
                    "all localisers".into()
                } else {
                    names.join(", ")
                },
                holds_to,
                breaks_at,
            });
        }
    }
    out
}
