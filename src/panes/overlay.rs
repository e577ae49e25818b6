//! The Overlay pane: measured against predicted stroke and force for the
//! chosen cycle (or the envelope of all cycles), the residual beneath, the
//! per-cycle figures, and the fidelity level in use and why.
//!
//! With a rig log loaded, the comparison is `pinsight::overlay::compare::
//! overlay` (run on the worker, [`crate::engine::overlay::run_overlay`]): the
//! model at the clearance level with the log's metadata predicts an
//! ensemble of revolutions at the logged speed (the motion in a worn joint
//! is chaotic, so it is compared as bands, not impact for impact). Charts:
//! the ideal stroke, the predicted min–max band and mean, the measured cycle
//! (or the measured envelope of all cycles); the residual (measured −
//! predicted mean) beneath. Without a log the pane shows the model's
//! prediction alone and says so.
//!
//! On request (key `C`, `--ui overlay.calibrate=yes`, batch `run
//! calibrate`) the log is calibrated against the model
//! ([`crate::engine::calibrate`]): the pane adds the fitted clearance,
//! standoff, lags and zeros with their U95 and the residual before → after.

use super::chart::{ChartView, SeriesKind, SeriesView, decimate_points};
use super::session::Session;
use super::{PaneState, csv_num, parse_bool, parse_usize};
use crate::overlay::calibrate::{CalibrationReport, Residuals};
use serde::Serialize;
use std::sync::Arc;

/// UI state: which log and which cycle (None = envelope of all cycles);
/// whether the log's calibration is asked for (headless faces run it
/// first, as the TUI does on its key `C`).
#[derive(Debug, Clone, Default, Serialize)]
pub struct OverlayUi {
    pub log: usize,
    pub cycle: Option<usize>,
    pub calibrate: bool,
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
            "calibrate" => self.calibrate = parse_bool(v)?,
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

impl super::table::Cells for CycleRow {
    const HEADER: &'static [&'static str] = &[
        "cycle",
        "stroke_rms_mm",
        "force_rms_n",
        "stroke_max_abs_mm",
        "force_max_abs_n",
        "note",
    ];
    fn cells(&self, num: &dyn Fn(Option<f64>) -> String) -> Vec<String> {
        vec![
            self.index.to_string(),
            num(self.stroke_rms_mm),
            num(self.force_rms_n),
            num(self.stroke_max_mm),
            num(self.force_max_n),
            self.note.clone(),
        ]
    }
}

/// The Overlay pane's view.
#[derive(Debug, Clone, Default, Serialize)]
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
    /// Where the model parameters came from, laser zero, noise (JSON only).
    pub notes: Vec<String>,
    /// The run's residual figures (the library's `RunResiduals`: stroke and
    /// force RMS residuals, fractions inside the predicted band), for checks.
    pub residuals: Option<crate::overlay::compare::RunResiduals>,
    /// Time the comparison took (JSON only: not drawn, so screens are stable).
    pub wall_ms: Option<f64>,
    /// The job's whole result, exactly as `pinsight overlay --json` prints it
    /// (JSON only; shared, not copied, per frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<std::sync::Arc<crate::overlay::compare::OverlayReport>>,
    /// The log's calibration against the model, once run (key `C`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CalibrationView>,
}

/// The calibration of the Overlay pane's log
/// ([`crate::engine::calibrate::run_calibration`]): the fitted estimates
/// with their U95, the residual before and after.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CalibrationView {
    /// What is drawn: (label, text), e.g. ("clearance", "0.1002 ± 0.0054 mm").
    pub rows: Vec<(String, String)>,
    pub clearance_mm: Option<f64>,
    pub clearance_u95_mm: Option<f64>,
    pub standoff_mm: Option<f64>,
    pub standoff_u95_mm: Option<f64>,
    pub laser_lag_us: Option<f64>,
    pub force_lag_us: Option<f64>,
    pub before: Option<Residuals>,
    pub after: Option<Residuals>,
    /// Why the calibration failed (the same words as `pinsight calibrate`).
    pub error: Option<String>,
    /// Time the calibration took (JSON only: not drawn).
    pub wall_ms: Option<f64>,
    /// The job's whole result, exactly as `pinsight calibrate --json`
    /// prints it (JSON only; shared, not copied, per frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<Arc<CalibrationReport>>,
}

impl OverlayView {
    pub fn charts(&self) -> Vec<&ChartView> {
        [&self.stroke, &self.force, &self.residual]
            .into_iter()
            .flatten()
            .collect()
    }

    pub fn to_csv(&self) -> String {
        super::table::csv_of(&self.cycles, &|x| csv_num(x, 6))
    }
}

pub fn view(s: &Session, ui: &PaneState) -> OverlayView {
    if !s.logs.is_empty() {
        let mut v = measured_view(s, ui);
        let li = ui.overlay.log.min(s.logs.len() - 1);
        v.calibration = s.calibration_of(li).map(calibration_view);
        return v;
    }
    prediction_view(s, ui)
}

/// A value with its expanded uncertainty, to two significant digits of
/// the uncertainty.
fn with_u95(value: f64, u95: f64, unit: &str) -> String {
    let decimals = if u95.is_finite() && u95 > 0.0 {
        (1 - u95.log10().floor() as i32).clamp(0, 8) as usize
    } else {
        4
    };
    format!("{value:.decimals$} ± {u95:.decimals$} {unit}")
}

fn calibration_view(run: &crate::engine::calibrate::CalibrationRun) -> CalibrationView {
    let mut v = CalibrationView {
        wall_ms: Some(run.wall_ms),
        ..Default::default()
    };
    let r = match &run.report {
        Ok(r) => r,
        Err(e) => {
            v.error = Some(e.clone());
            return v;
        }
    };
    v.rows.push((
        "calibrated on".into(),
        format!("{} cycles at {:.0} rpm", r.cycles, r.motor_rpm),
    ));
    for e in &r.estimates {
        let unit = if e.unit == "us" {
            "µs"
        } else {
            e.unit.as_str()
        };
        let mut text = with_u95(e.value, e.u95, unit);
        if let Some(n) = e.nominal {
            text.push_str(&format!(" (was {n})"));
        }
        v.rows.push((e.name.replace('_', " "), text));
        let (value, u95) = (Some(e.value), Some(e.u95));
        match e.name.as_str() {
            "clearance" => (v.clearance_mm, v.clearance_u95_mm) = (value, u95),
            "standoff" => (v.standoff_mm, v.standoff_u95_mm) = (value, u95),
            "laser_lag" => v.laser_lag_us = value,
            "force_lag" => v.force_lag_us = value,
            _ => {}
        }
    }
    let (b, a) = (&r.before, &r.after);
    v.rows.extend([
        (
            "stroke mean RMS".into(),
            format!(
                "{:.4} → {:.4} mm",
                b.stroke_mean_rms_mm, a.stroke_mean_rms_mm
            ),
        ),
        (
            "stroke spread RMS".into(),
            format!(
                "{:.4} → {:.4} mm",
                b.stroke_spread_rms_mm, a.stroke_spread_rms_mm
            ),
        ),
        (
            "force RMS".into(),
            format!("{:.3} → {:.3} N", b.force_rms_n, a.force_rms_n),
        ),
    ]);
    v.before = Some(*b);
    v.after = Some(*a);
    v.report = Some(r.clone());
    v
}

/// Points of a grid curve (degrees) decimated to the chart's columns.
fn grid_points(deg: &[f64], y: &[f64], cols: usize) -> Vec<(f64, f64)> {
    let pts: Vec<(f64, f64)> = deg
        .iter()
        .zip(y)
        .map(|(&x, &v)| {
            if v.is_finite() {
                (x, v)
            } else {
                (f64::NAN, f64::NAN)
            }
        })
        .collect();
    decimate_points(&pts, 0.0, 360.0, cols)
}

fn measured_view(s: &Session, ui: &PaneState) -> OverlayView {
    let cols = ui.chart_columns(0.6);
    let li = ui.overlay.log.min(s.logs.len().saturating_sub(1));
    let log = &s.logs[li];
    let mut v = OverlayView {
        source: Some(log.path.clone()),
        showing: "envelope".into(),
        ..Default::default()
    };
    let Some(run) = s.overlay_of(li) else {
        v.message = Some(format!(
            "comparing {} with the model… (runs in the background)",
            log.path
        ));
        return v;
    };
    let r = match &run.report {
        Ok(r) => r,
        Err(e) => {
            v.message = Some(format!("no comparison: {e}"));
            return v;
        }
    };
    v.level = Some(r.level.clone());
    let revs: usize = r.groups.iter().map(|g| g.prediction.revs).sum();
    v.level_reason = Some(format!(
        "c = {} mm, standoff {} mm (log metadata); chaotic joint motion: {} predicted revolutions form a band ({})",
        r.clearance_mm,
        r.standoff_mm,
        revs,
        r.groups
            .iter()
            .map(|g| format!("{:.0} rpm × {} cycles", g.motor_rpm, g.cycles))
            .collect::<Vec<_>>()
            .join(", "),
    ));
    v.notes = r.params_notes.iter().chain(&r.notes).cloned().collect();
    v.wall_ms = Some(run.wall_ms);
    v.report = Some(r.clone());
    let deg = &r.grid_deg;
    let nc = r.cycles.len();
    let sel = ui.overlay.cycle.map(|c| c.min(nc.saturating_sub(1)));
    v.selected = sel;
    // Measured stroke of the selected cycle (the comparison's laser zero).
    let Some((_, cs)) = &log.rig else {
        v.message = Some("no cycles to compare".into());
        return v;
    };
    let shift = r.laser_zero.applied - cs.offsets.laser_zero_mm.applied;
    let chosen = sel.and_then(|i| r.cycles.get(i));
    let (pred_s, pred_f) = match chosen.and_then(|c| r.groups.get(c.group)) {
        Some(g) => (&g.prediction.stroke, &g.prediction.force),
        None => (&r.predicted_stroke, &r.predicted_force),
    };
    let line = |name: &str, y: &[f64], color: usize, kind| SeriesView {
        name: name.into(),
        color,
        kind,
        points: grid_points(deg, y, cols),
    };
    let mut stroke = vec![
        line("ideal", &r.ideal_stroke_mm, 8, SeriesKind::Reference),
        line("predicted min", &pred_s.min, 4, SeriesKind::Reference),
        line("predicted max", &pred_s.max, 4, SeriesKind::Reference),
        line("predicted mean", &pred_s.mean, 1, SeriesKind::Line),
    ];
    let mut force = vec![
        line("predicted min", &pred_f.min, 4, SeriesKind::Reference),
        line("predicted max", &pred_f.max, 4, SeriesKind::Reference),
        line("predicted mean", &pred_f.mean, 1, SeriesKind::Line),
    ];
    let residual: Vec<f64>;
    match chosen.and_then(|c| cs.cycles.iter().find(|x| x.index == c.index)) {
        Some(c) => {
            v.showing = format!("cycle {}", c.index);
            let ms: Vec<f64> = c.stroke_mm.iter().map(|x| x + shift).collect();
            residual = ms.iter().zip(&pred_s.mean).map(|(a, b)| a - b).collect();
            stroke.push(line("measured", &ms, 3, SeriesKind::Line));
            if !c.force_n.is_empty() {
                force.push(line("measured", &c.force_n, 3, SeriesKind::Line));
            }
        }
        None => {
            v.showing = format!("envelope of {nc} cycles");
            stroke.push(line(
                "measured min",
                &r.measured_stroke.min,
                3,
                SeriesKind::Line,
            ));
            stroke.push(line(
                "measured max",
                &r.measured_stroke.max,
                3,
                SeriesKind::Line,
            ));
            force.push(line(
                "measured min",
                &r.measured_force.min,
                3,
                SeriesKind::Line,
            ));
            force.push(line(
                "measured max",
                &r.measured_force.max,
                3,
                SeriesKind::Line,
            ));
            residual = r.residual_stroke_mm.clone();
        }
    }
    v.stroke = Some(ChartView::new(
        format!("stroke — {}", v.showing),
        "crank angle from TDC (°)",
        "stroke (mm)",
        stroke,
        Some([0.0, 360.0]),
    ));
    if r.measured_force.mean.iter().any(|x| x.is_finite()) {
        v.force = Some(ChartView::new(
            format!("load-cell force — {}", v.showing),
            "crank angle from TDC (°)",
            "load-cell force (N)",
            force,
            Some([0.0, 360.0]),
        ));
    }
    let noise = r.noise_stroke_mm;
    let band: Vec<f64> = deg.iter().map(|_| 2.0 * noise).collect();
    let neg: Vec<f64> = band.iter().map(|x| -x).collect();
    v.residual = Some(ChartView::new(
        format!(
            "stroke residual (measured − predicted mean) — {}",
            v.showing
        ),
        "crank angle from TDC (°)",
        "stroke residual (mm)",
        vec![
            line("+2σ noise", &band, 8, SeriesKind::Reference),
            line("−2σ noise", &neg, 8, SeriesKind::Reference),
            line("residual", &residual, 3, SeriesKind::Line),
        ],
        Some([0.0, 360.0]),
    ));
    v.cycles = r
        .cycles
        .iter()
        .map(|c| CycleRow {
            index: c.index,
            stroke_rms_mm: Some(c.stroke_rms_err_mm).filter(|x| x.is_finite()),
            force_rms_n: Some(c.force_rms_err_n).filter(|x| x.is_finite()),
            stroke_max_mm: Some(c.stroke_max_err_mm).filter(|x| x.is_finite()),
            force_max_n: None,
            note: format!(
                "{:.0}% in band, {:.0} rpm",
                100.0 * c.stroke_in_band,
                c.motor_rpm
            ),
        })
        .collect();
    let run_r = &r.run;
    v.residuals = Some(run_r.clone());
    v.figures = vec![
        ("cycles compared".into(), run_r.cycles as f64),
        ("stroke RMS residual mm".into(), run_r.stroke_rms_err_mm),
        ("mean-curve RMS mm".into(), run_r.stroke_mean_rms_mm),
        ("stroke in band".into(), run_r.stroke_in_band),
        ("force RMS residual N".into(), run_r.force_rms_err_n),
        ("force in band".into(), run_r.force_in_band),
        ("laser noise mm".into(), r.noise_stroke_mm),
    ];
    v.figures.retain(|(_, x)| x.is_finite());
    v
}

fn prediction_view(s: &Session, ui: &PaneState) -> OverlayView {
    let cols = ui.chart_columns(0.6);
    let run = s.model.as_ref();
    let mut v = OverlayView {
        showing: "prediction only".into(),
        level: run.map(|r| r.level.name().to_string()),
        level_reason: run.map(|r| r.level_reason.clone()),
        ..Default::default()
    };
    v.message =
        Some("prediction only: no rig log loaded (open a .mcap log with o to compare)".into());
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
                "stroke (mm)",
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
                    "load-cell force (N)",
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
