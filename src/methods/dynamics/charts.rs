//! The dynamics lab's charts: work–precision, stability, long run, step
//! budget panels.

use super::*;
use crate::plot::{BarChart, LineChart, Panel, Series, SeriesStyle};

pub(super) fn method_color(m: &str) -> usize {
    match m {
        "dop853" => 0,
        "dopri5" => 1,
        "radau5" => 2,
        "rk4" => 3,
        _ => 4,
    }
}

impl DynamicsLab {
    /// Log–log work–precision panels per scene: stroke error against
    /// right-hand-side evaluations (one series per method).
    pub fn work_precision_panels(&self) -> Vec<Panel> {
        let mut scenes: Vec<&str> = self
            .work_precision
            .iter()
            .map(|p| p.scene.as_str())
            .collect();
        scenes.dedup();
        scenes
            .iter()
            .map(|sc| {
                let mut series = Vec::new();
                for m in ["dop853", "dopri5", "radau5", "rk4"] {
                    let pts: Vec<(f64, f64)> = self
                        .work_precision
                        .iter()
                        .filter(|p| p.scene == *sc && p.method == m && p.failed.is_none())
                        .map(|p| {
                            (
                                (p.rhs_evals + p.aux_evals) as f64,
                                p.stroke_err_mm.max(1e-16),
                            )
                        })
                        .collect();
                    if !pts.is_empty() {
                        series.push(
                            Series::line(m, pts)
                                .with_style(SeriesStyle::LinePoints)
                                .with_color(method_color(m)),
                        );
                    }
                }
                Panel::Line(LineChart {
                    title: format!("work–precision: {sc}"),
                    x_label: "rhs + aux evaluations (count)".into(),
                    y_label: "max stroke error (mm)".into(),
                    series,
                    log_x: true,
                    log_y: true,
                    ..Default::default()
                })
            })
            .collect()
    }

    /// Stability: measured stable and accurate steps against the prediction.
    pub fn stability_panels(&self) -> Vec<Panel> {
        let mut series = Vec::new();
        for m in ["rk4", "dopri5", "dop853"] {
            let rows: Vec<&StabilityRow> =
                self.stability.iter().filter(|r| r.method == m).collect();
            let pred: Vec<(f64, f64)> = rows
                .iter()
                .map(|r| (r.omega_contact, r.predicted_stable_step_s))
                .collect();
            let meas: Vec<(f64, f64)> = rows
                .iter()
                .filter_map(|r| r.measured_stable_step_s.map(|h| (r.omega_contact, h)))
                .collect();
            let acc: Vec<(f64, f64)> = rows
                .iter()
                .filter_map(|r| r.measured_accurate_step_s.map(|h| (r.omega_contact, h)))
                .collect();
            let c = method_color(m);
            series.push(
                Series::line(format!("{m} predicted"), pred)
                    .with_style(SeriesStyle::Dashed)
                    .with_color(c),
            );
            series.push(
                Series::line(format!("{m} stable"), meas)
                    .with_style(SeriesStyle::Points)
                    .with_color(c),
            );
            series.push(
                Series::line(format!("{m} accurate"), acc)
                    .with_style(SeriesStyle::LinePoints)
                    .with_color(c),
            );
        }
        vec![Panel::Line(LineChart {
            title: "fixed-step limits against contact frequency".into(),
            x_label: "contact frequency ω (rad/s)".into(),
            y_label: "step (s)".into(),
            series,
            log_x: true,
            log_y: true,
            ..Default::default()
        })]
    }

    /// Horizon and statistics against tolerance.
    pub fn long_run_panels(&self) -> Vec<Panel> {
        let rows = &self.long_run.rows;
        let horizon: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| r.horizon_revs.map(|h| (r.rtol, h)))
            .collect();
        let tol_h: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| r.tolerance_horizon_revs.map(|h| (r.rtol, h)))
            .collect();
        let mut panels = vec![Panel::Line(LineChart {
            title: "prediction horizon against tolerance".into(),
            x_label: "rtol (–)".into(),
            y_label: "revolutions until c/10 apart (rev)".into(),
            series: vec![
                Series::line("realisations 1 nm apart", horizon)
                    .with_style(SeriesStyle::LinePoints),
                Series::line("vs tightest tolerance", tol_h).with_style(SeriesStyle::LinePoints),
            ],
            log_x: true,
            ..Default::default()
        })];
        let cats: Vec<String> = rows.iter().map(|r| format!("{:.0e}", r.rtol)).collect();
        let mean: Vec<f64> = rows
            .iter()
            .map(|r| {
                r.figures
                    .iter()
                    .find(|f| f.0 == "disp_dev_mean_mm")
                    .map_or(f64::NAN, |f| f.1)
            })
            .collect();
        let std: Vec<f64> = rows
            .iter()
            .map(|r| {
                r.figures
                    .iter()
                    .find(|f| f.0 == "disp_dev_mean_mm")
                    .map_or(f64::NAN, |f| f.2)
            })
            .collect();
        panels.push(Panel::Bar(BarChart {
            title: format!(
                "ensemble mean |Δs| against tolerance ({} realisations, ±1 std)",
                self.long_run.realisations
            ),
            x_label: "rtol (–)".into(),
            y_label: "mean |Δs| (mm)".into(),
            categories: cats,
            series: vec![("mean |Δs|".into(), mean)],
            errors: Some(vec![std]),
        }));
        panels
    }

    /// Where the steps go, per scene and method.
    pub fn budget_panels(&self) -> Vec<Panel> {
        let cats: Vec<String> = self
            .step_budgets
            .iter()
            .map(|b| {
                format!(
                    "{} {}",
                    b.method,
                    b.scene
                        .split_whitespace()
                        .take(2)
                        .collect::<Vec<_>>()
                        .join(" ")
                )
            })
            .collect();
        vec![Panel::Bar(BarChart {
            title: "where the steps go (rtol 1e-8, deterministic window)".into(),
            x_label: "method, scene".into(),
            y_label: "steps (count)".into(),
            categories: cats,
            series: vec![
                (
                    "contact".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.contact_steps as f64)
                        .collect(),
                ),
                (
                    "free flight".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.free_steps as f64)
                        .collect(),
                ),
                (
                    "rejected".into(),
                    self.step_budgets
                        .iter()
                        .map(|b| b.rejected as f64)
                        .collect(),
                ),
            ],
            errors: None,
        })]
    }

    /// The figure names used for the long-run table.
    pub fn long_run_figures() -> &'static [&'static str] {
        &LONG_RUN_FIGURES
    }
}
