//! The Model pane: every parameter with its unit, range and meaning,
//! editable in place with validation; the preset and the fidelity level;
//! the latest run's summary figures and the fidelity assessment.
//!
//! Edits go through [`apply_edit`] (the same key registry and checks as
//! `--set key=value` and parameter files): an invalid value leaves the
//! parameters unchanged and the error is shown in the pane.

use super::chart::{ChartView, SeriesKind, SeriesView, decimate_minmax};
use super::session::Session;
use super::{PaneState, csv_table, fmt_opt, parse_usize};
use crate::model::params::{PARAM_SPECS, Params};
use crate::sim::summary::Summary;
use crate::sim::{Level, LevelChoice};
use serde::Serialize;

/// UI state of the Model pane.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ModelUi {
    /// Selected row (0 = preset, 1 = level, then the parameters).
    pub selected: usize,
    /// Text being typed for the selected row, while editing.
    pub editing: Option<String>,
    /// The last edit's error (shown until the next edit).
    pub error: Option<String>,
    /// The last edit's confirmation.
    pub notice: Option<String>,
}

impl ModelUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "selected" => {
                self.selected = match parse_usize(v) {
                    Ok(i) => i,
                    Err(_) => row_of_key(v).ok_or_else(|| format!("no parameter `{v}`"))?,
                }
            }
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// Rows before the parameters.
pub const PRESET_ROW: usize = 0;
pub const LEVEL_ROW: usize = 1;
pub const FIRST_PARAM_ROW: usize = 2;

/// Number of rows in the table.
pub fn row_count() -> usize {
    FIRST_PARAM_ROW + PARAM_SPECS.len()
}

/// The key edited by a row.
pub fn row_key(row: usize) -> &'static str {
    match row {
        PRESET_ROW => "preset",
        LEVEL_ROW => "level",
        r => PARAM_SPECS
            .get(r - FIRST_PARAM_ROW)
            .map(|s| s.key)
            .unwrap_or(""),
    }
}

/// The row of a key.
pub fn row_of_key(key: &str) -> Option<usize> {
    match key {
        "preset" => Some(PRESET_ROW),
        "level" => Some(LEVEL_ROW),
        k => PARAM_SPECS
            .iter()
            .position(|s| s.key == k)
            .map(|i| i + FIRST_PARAM_ROW),
    }
}

/// What an accepted edit changes.
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    Params(Box<Params>),
    Level(LevelChoice),
}

/// Applies `text` to `key` (`preset`, `level` or a parameter key): the new
/// parameters or level, or an error naming the key and the allowed values.
pub fn apply_edit(params: &Params, key: &str, text: &str) -> Result<Edit, String> {
    let text = text.trim();
    match key {
        "preset" => Params::preset(text)
            .map(|p| Edit::Params(Box::new(p)))
            .map_err(|e| e.to_string()),
        "level" => LevelChoice::parse(text).map(Edit::Level).ok_or_else(|| {
            format!(
                "invalid value for `level`: {text} (allowed: auto, kinematic, ideal, clearance, motor)"
            )
        }),
        _ => {
            if text.is_empty() {
                return Err(format!("`{key}`: type a value (Esc cancels)"));
            }
            let mut p = params.clone();
            p.set_str(key, text).map_err(|e| e.to_string())?;
            p.validate().map_err(|e| e.to_string())?;
            Ok(Edit::Params(Box::new(p)))
        }
    }
}

/// The current text of a row (what editing starts from).
pub fn row_value(s: &Session, row: usize) -> String {
    match row {
        PRESET_ROW => s.params.preset.clone(),
        LEVEL_ROW => level_name(s.level),
        r => s
            .params
            .get(row_key(r))
            .map(|v| v.to_string())
            .unwrap_or_default(),
    }
}

fn level_name(c: LevelChoice) -> String {
    match c {
        LevelChoice::Auto => "auto".into(),
        LevelChoice::Fixed(l) => l.name().into(),
    }
}

/// One row of the parameter table.
#[derive(Debug, Clone, Serialize)]
pub struct ParamRow {
    pub key: String,
    pub value: String,
    pub range: String,
    pub group: String,
    pub help: String,
    /// Differs from the preset's value.
    pub changed: bool,
}

/// One summary figure beside the ideal mechanism's.
#[derive(Debug, Clone, Serialize)]
pub struct FigureRow {
    pub figure: String,
    pub value: String,
    pub ideal: String,
}

/// The fidelity assessment's short form.
#[derive(Debug, Clone, Serialize)]
pub struct FidelityView {
    /// The level the scene needs.
    pub recommended: String,
    pub reason: String,
    /// (from → to, stroke diff mm, force diff N, visible?) per level step.
    pub steps: Vec<FidelityStep>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FidelityStep {
    pub step: String,
    pub stroke_diff_mm: Option<f64>,
    pub force_diff_n: Option<f64>,
    /// Step to `motor`: the crank speed's first harmonic, %.
    pub speed_ripple_pct: Option<f64>,
    pub invisible: bool,
    /// The upper rung's cost: right-hand side evaluations per revolution
    /// (a count, the same on every machine and run; the wall time is in
    /// the fidelity report's costs).
    pub cost_evals_per_rev: Option<f64>,
}

impl FidelityStep {
    /// One line of the ladder: the step, what it changes, whether the
    /// sensors see it, its cost.
    pub fn line(&self) -> String {
        let mut parts = vec![self.step.clone()];
        if self.stroke_diff_mm.is_none()
            && self.force_diff_n.is_none()
            && self.speed_ripple_pct.is_none()
        {
            // The motor rung of a constant-speed head: nothing to weigh.
            parts.push("not weighed (driver = constant_speed)".into());
            return parts.join("  ");
        }
        if let Some(r) = self.speed_ripple_pct {
            parts.push(format!("ripple {r:.3} %"));
        }
        if let Some(s) = self.stroke_diff_mm {
            parts.push(format!("Δs {s:.4} mm"));
        }
        if let Some(f) = self.force_diff_n {
            parts.push(format!("ΔF {f:.3} N"));
        }
        parts.push(if self.invisible { "unseen" } else { "seen" }.into());
        if let Some(c) = self.cost_evals_per_rev {
            parts.push(format!("{c:.0} evals/rev"));
        }
        parts.join("  ")
    }
}

/// The Model pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct ModelView {
    pub rows: Vec<ParamRow>,
    pub selected: usize,
    /// The text being typed, while editing the selected row.
    pub editing: Option<String>,
    pub error: Option<String>,
    pub notice: Option<String>,
    pub preset: String,
    pub params_source: String,
    /// The level asked for (auto or a fixed level).
    pub level_choice: String,
    /// The level of the latest run and why.
    pub level: Option<String>,
    pub level_reason: Option<String>,
    /// Whether the latest run used the parameters shown (false while a re-run is pending).
    pub up_to_date: bool,
    pub run_error: Option<String>,
    pub summary: Option<Summary>,
    pub figures: Vec<FigureRow>,
    pub fidelity: Option<FidelityView>,
    pub notes: Vec<String>,
    /// Stroke deviation from the ideal mechanism over the reported revolutions.
    pub chart: Option<ChartView>,
}

impl ModelView {
    pub fn to_csv(&self) -> String {
        let rows: Vec<Vec<String>> = self
            .rows
            .iter()
            .map(|r| {
                vec![
                    r.key.clone(),
                    r.value.clone(),
                    r.range.clone(),
                    r.group.clone(),
                    r.changed.to_string(),
                ]
            })
            .collect();
        let mut out = csv_table(&["key", "value", "allowed", "group", "changed"], &rows);
        if !self.figures.is_empty() {
            out.push('\n');
            let rows: Vec<Vec<String>> = self
                .figures
                .iter()
                .map(|f| vec![f.figure.clone(), f.value.clone(), f.ideal.clone()])
                .collect();
            out.push_str(&csv_table(&["figure", "value", "ideal"], &rows));
        }
        out
    }
}

fn figures(s: &Summary) -> Vec<FigureRow> {
    let f = |name: &str, v: String, ideal: String| FigureRow {
        figure: name.into(),
        value: v,
        ideal,
    };
    vec![
        f("impacts", s.n_impacts.to_string(), "0".into()),
        f(
            "peak |accel| m/s²",
            format!("{:.1}", s.peak_accel_mps2),
            format!("{:.1}", s.ideal_peak_accel_mps2),
        ),
        f(
            "peak contact N",
            format!("{:.1}", s.peak_contact_force_n),
            "–".into(),
        ),
        f(
            "mean |Δs| mm",
            format!("{:.5}", s.disp_dev_mean_mm),
            "0".into(),
        ),
        f(
            "max |Δs| mm",
            format!("{:.5}", s.disp_dev_max_mm),
            "0".into(),
        ),
        f(
            "mean |Δv| m/s",
            format!("{:.4}", s.vel_dev_mean_mps),
            "0".into(),
        ),
        f(
            "peak |M12| N·m",
            fmt_opt(s.peak_torque_nm, 4),
            fmt_opt(s.ideal_peak_torque_nm, 4),
        ),
        f(
            "peak load cell N",
            fmt_opt(s.peak_process_force_n, 3),
            "–".into(),
        ),
        f("steps", s.steps.to_string(), "–".into()),
        f("rhs evaluations", s.rhs_evals.to_string(), "–".into()),
    ]
    .into_iter()
    .chain(s.motor.iter().flat_map(|m| {
        [
            f(
                "crank rpm mean",
                format!("{:.2}", m.mean_crank_rpm),
                format!("{:.2}", m.operating_crank_rpm),
            ),
            f(
                "ripple p-p %",
                format!("{:.3}", m.ripple_p2p_pct),
                "0".into(),
            ),
            f(
                "ripple 1st harm. %",
                fmt_opt(m.ripple_h1_pct, 3),
                "0".into(),
            ),
            f(
                "motor torque pk/RMS",
                format!("{:.3}/{:.3}", m.peak_motor_torque_nm, m.rms_motor_torque_nm),
                "–".into(),
            ),
        ]
    }))
    .chain(s.stick.iter().map(|st| {
        f(
            "held by the part",
            format!("{}× ≤ {} steps", st.held_phases, st.max_steps_per_phase),
            "–".into(),
        )
    }))
    .collect()
}

pub fn view(s: &Session, ui: &PaneState) -> ModelView {
    let st = &ui.model;
    let base = Params::preset(&s.params.preset).ok();
    let mut rows = vec![
        ParamRow {
            key: "preset".into(),
            value: s.params.preset.clone(),
            range: "paper, flores (resets every parameter)".into(),
            group: "set".into(),
            help: "the preset the parameters start from".into(),
            changed: false,
        },
        ParamRow {
            key: "level".into(),
            value: level_name(s.level),
            range: "auto, kinematic, ideal, clearance, motor".into(),
            group: "set".into(),
            help: "fidelity level (auto: the cheapest the sensors cannot tell from the next)"
                .into(),
            changed: false,
        },
    ];
    for (spec, value) in s.params.listing() {
        let changed = base
            .as_ref()
            .and_then(|b| b.get(spec.key))
            .is_some_and(|b| b != value);
        rows.push(ParamRow {
            key: spec.key.into(),
            value: value.to_string(),
            range: spec.range.into(),
            group: spec.group.into(),
            help: spec.help.into(),
            changed,
        });
    }
    let selected = st.selected.min(rows.len().saturating_sub(1));
    let run = s.model.as_ref();
    let up_to_date = run.is_some_and(|r| {
        r.params == s.params
            && (match s.level {
                LevelChoice::Auto => r.choice == "auto",
                LevelChoice::Fixed(l) => r.level == l && r.choice != "auto",
            })
    });
    let fidelity = run.and_then(|r| r.fidelity.as_ref()).map(|f| FidelityView {
        recommended: f.chosen.name().into(),
        reason: f.reason.clone(),
        steps: f
            .steps
            .iter()
            .map(|st| FidelityStep {
                step: format!("{} → {}", st.from.name(), st.to.name()),
                stroke_diff_mm: st.stroke_diff_mm,
                force_diff_n: st.force_diff_n,
                speed_ripple_pct: st.speed_ripple_pct,
                invisible: st.invisible,
                cost_evals_per_rev: f
                    .costs
                    .iter()
                    .find(|c| c.level == st.to)
                    .map(|c| c.rhs_evals_per_rev),
            })
            .collect(),
    });
    let chart = run.and_then(|r| {
        let c = r.result.curves.as_ref()?;
        if r.level == Level::Kinematic && c.is_empty() {
            return None;
        }
        let t0 = c.t_s.first().copied().unwrap_or(0.0);
        let revs: Vec<f64> = c.t_s.iter().map(|t| (t - t0) / r.params.period()).collect();
        let dev: Vec<f64> = c
            .stroke_mm
            .iter()
            .zip(&c.ideal_stroke_mm)
            .map(|(a, b)| a - b)
            .collect();
        let end = revs.last().copied().unwrap_or(1.0);
        let pts = decimate_minmax(&revs, &dev, 0.0, end, ui.chart_columns(0.45));
        Some(ChartView::new(
            "stroke − ideal stroke",
            "revolutions (rev)",
            "Δs (mm)",
            vec![SeriesView {
                name: "Δs".into(),
                color: 0,
                kind: SeriesKind::Line,
                points: pts,
            }],
            Some([0.0, end.max(1e-9)]),
        ))
    });
    ModelView {
        rows,
        selected,
        editing: st.editing.clone(),
        error: st.error.clone(),
        notice: st.notice.clone(),
        preset: s.params.preset.clone(),
        params_source: s.params_source.clone(),
        level_choice: level_name(s.level),
        level: run.map(|r| r.level.name().to_string()),
        level_reason: run.map(|r| r.level_reason.clone()),
        up_to_date,
        run_error: s.model_error.clone(),
        summary: run.map(|r| r.result.summary.clone()),
        figures: run.map(|r| figures(&r.result.summary)).unwrap_or_default(),
        fidelity,
        notes: run.map(|r| r.result.notes.clone()).unwrap_or_default(),
        chart,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_validate_and_errors_name_the_key() {
        let p = Params::paper();
        match apply_edit(&p, "clearance_mm", "0.3").unwrap() {
            Edit::Params(q) => assert!((q.clearance - 0.3e-3).abs() < 1e-15),
            e => panic!("{e:?}"),
        }
        let e = apply_edit(&p, "clearance_mm", "-2").unwrap_err();
        assert!(e.contains("clearance_mm"), "{e}");
        let e = apply_edit(&p, "clearance_mm", "abc").unwrap_err();
        assert!(e.contains("clearance_mm"), "{e}");
        // A relation between keys is checked too.
        let e = apply_edit(&p, "l_mm", "5").unwrap_err();
        assert!(e.contains("l_mm"), "{e}");
        assert_eq!(
            apply_edit(&p, "level", "auto").unwrap(),
            Edit::Level(LevelChoice::Auto)
        );
        assert!(apply_edit(&p, "level", "quantum").is_err());
        match apply_edit(&p, "preset", "flores").unwrap() {
            Edit::Params(q) => assert_eq!(q.preset, "flores"),
            e => panic!("{e:?}"),
        }
        assert!(apply_edit(&p, "preset", "nope").is_err());
        assert_eq!(row_key(row_of_key("motor_rpm").unwrap()), "motor_rpm");
        assert_eq!(row_count(), PARAM_SPECS.len() + 2);
    }
}
