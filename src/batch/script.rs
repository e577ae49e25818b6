//! Batch scripts: `pinsight batch SCRIPT.toml`.
//!
//! A script is a list of `[[step]]` tables run in order on one session
//! (which starts empty, on the `paper` preset). Every step reports ok or
//! error, every check pass or fail; a failing step does not stop the
//! script. The run fails (non-zero exit) when any step errs or any check
//! fails. Paths to load are relative to the script's folder; exports are
//! written under the output folder (`--out`, default the current folder).
//!
//! ```toml
//! size = "120x40"                    # screen size for views (default 120x40)
//!
//! [[step]]
//! kind = "load"                      # open files (logs, images, recipes, parameter files, folders)
//! paths = ["logs/run.mcap", "images/"]
//! expect_errors = 0                  # files allowed to fail (default 0)
//!
//! [[step]]
//! kind = "set"                       # any of: preset, params, values, level, study
//! preset = "paper"
//! params = "params/worn.toml"
//! values = { clearance_mm = 0.3, motor_rpm = 1500 }
//! level = "auto"
//! study = { clearances_mm = [0.1, 0.5], speeds_rpm = [1200], materials = ["alloy_steel"], warmup = 1, revs = 1 }
//!
//! [[step]]
//! kind = "run"                       # model | study | methods | yield | overlay | calibrate | monitor | trend
//! what = "model"
//!
//! [[step]]
//! kind = "export"                    # a pane's view model or screen
//! pane = "study"
//! format = "png"                     # json | csv | png | text (default: from the extension)
//! path = "study.png"
//! ui = { "study.factor" = "speed" }  # pane UI options (as `render --ui`)
//!
//! [[step]]
//! kind = "check"                     # a figure of a view model against a threshold
//! pane = "model"
//! figure = "summary.disp_dev_mean_mm"
//! op = "<="                          # < <= > >= == != (numbers); == != contains (text)
//! value = 0.1
//! name = "mean stroke deviation"     # optional label
//! ```
//!
//! Panes that show the model (session, signals, overlay, model) run it
//! first when the parameters changed since the last run; the Vision pane
//! inspects its image, the Yield pane runs the batch yield and the Overlay
//! pane compares its log with the model when they have not run yet; the
//! study runs only when asked (it is the expensive one).

pub use super::export_path::export_path;
pub use super::report::{BatchReport, Outcome, StepReport};
use super::{Format, export, figure, parse_size};
use crate::panes::session::{StudySetup, load_path};
use crate::panes::{self, PaneId, PaneState, Session};
use crate::progress::Progress;
use crate::sim::LevelChoice;
use crate::sim::sweep::SweepGrid;
use std::path::{Path, PathBuf};

/// Runs a script file. Err only when the script itself cannot be read or
/// is not a script; everything else is reported per step.
pub fn run_file(path: &Path, out_dir: &Path) -> Result<BatchReport, String> {
    run_file_cancellable(path, out_dir, &Progress::hidden())
}

/// [`run_file`] that stops between steps once `progress` is cancelled
/// (Ctrl-C in `pinsight batch`).
pub fn run_file_cancellable(
    path: &Path,
    out_dir: &Path,
    progress: &Progress,
) -> Result<BatchReport, String> {
    let text = crate::input::read_text(path)
        .map_err(|e| format!("cannot read script {}: {e}", path.display()))?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    run_text_cancellable(&text, &path.display().to_string(), &base, out_dir, progress)
}

/// Runs script text; `base` resolves the paths it loads, `out_dir` the
/// exports.
pub fn run_text(
    text: &str,
    name: &str,
    base: &Path,
    out_dir: &Path,
) -> Result<BatchReport, String> {
    run_text_cancellable(text, name, base, out_dir, &Progress::hidden())
}

/// [`run_text`] that checks `progress` for cancellation before each step.
pub fn run_text_cancellable(
    text: &str,
    name: &str,
    base: &Path,
    out_dir: &Path,
    progress: &Progress,
) -> Result<BatchReport, String> {
    let doc: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("script {name}: not valid TOML: {e}"))?;
    for k in doc.keys() {
        if k != "step" && k != "size" {
            return Err(format!(
                "script {name}: unknown top-level key `{k}` (allowed: size, [[step]])"
            ));
        }
    }
    let size = match doc.get("size") {
        Some(toml::Value::String(s)) => parse_size(s).map_err(|e| format!("script {name}: {e}"))?,
        Some(v) => {
            return Err(format!(
                "script {name}: size = {}: expected \"WxH\"",
                crate::fmt::toml_value(v)
            ));
        }
        None => (120, 40),
    };
    let steps = match doc.get("step") {
        Some(toml::Value::Array(a)) => a.clone(),
        Some(_) => {
            return Err(format!(
                "script {name}: `step` must be an array of tables ([[step]])"
            ));
        }
        None => return Err(format!("script {name}: no [[step]] tables")),
    };
    let mut run = Runner {
        session: Session::new(format!("batch {name}")),
        base: base.to_path_buf(),
        out: out_dir.to_path_buf(),
        size,
        written: Vec::new(),
        progress: progress.child(),
    };
    progress.set_total(steps.len() as u64);
    let mut reports = Vec::new();
    let mut interrupted = false;
    for (i, step) in steps.iter().enumerate() {
        if progress.is_cancelled() {
            interrupted = true;
            break;
        }
        progress.set_done(i as u64);
        let index = i + 1;
        let r = match step {
            toml::Value::Table(t) => run.step(index, t),
            other => StepReport {
                index,
                kind: "?".into(),
                what: other.to_string(),
                outcome: Outcome::Error,
                detail: "a step must be a table ([[step]])".into(),
            },
        };
        reports.push(r);
    }
    let count = |o: Outcome| reports.iter().filter(|r| r.outcome == o).count();
    Ok(BatchReport {
        script: name.to_string(),
        checks_passed: count(Outcome::Pass),
        checks_failed: count(Outcome::Fail),
        step_errors: count(Outcome::Error),
        steps: reports,
        interrupted,
        written: run.written,
    })
}

struct Runner {
    session: Session,
    base: PathBuf,
    out: PathBuf,
    size: (u16, u16),
    /// Files written by export steps, in order.
    written: Vec<String>,
    /// The run's progress: its cancel flag also stops a step's study or
    /// yield (Ctrl-C inside a long step, not only between steps).
    progress: std::sync::Arc<Progress>,
}

/// Allowed keys per step kind.
fn allowed(kind: &str) -> &'static [&'static str] {
    match kind {
        "load" => &["kind", "path", "paths", "expect_errors"],
        "set" => &["kind", "preset", "params", "values", "level", "study"],
        "run" => &["kind", "what"],
        "export" => &["kind", "pane", "format", "path", "size", "ui"],
        "check" => &[
            "kind", "pane", "figure", "op", "value", "size", "ui", "name",
        ],
        _ => &[],
    }
}

fn err(index: usize, kind: &str, what: impl Into<String>, detail: impl Into<String>) -> StepReport {
    StepReport {
        index,
        kind: kind.to_string(),
        what: what.into(),
        outcome: Outcome::Error,
        detail: detail.into(),
    }
}

fn ok(index: usize, kind: &str, what: impl Into<String>, detail: impl Into<String>) -> StepReport {
    StepReport {
        index,
        kind: kind.to_string(),
        what: what.into(),
        outcome: Outcome::Ok,
        detail: detail.into(),
    }
}

fn str_of<'a>(t: &'a toml::Table, k: &str) -> Result<Option<&'a str>, String> {
    match t.get(k) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(s.as_str())),
        Some(v) => Err(format!("`{k}` must be a string, not {v}")),
    }
}

/// Flattens `ui = { study = { factor = "speed" } }` and `ui = { "study.factor" = "speed" }`.
fn ui_options(t: &toml::Table, prefix: &str, out: &mut Vec<(String, String)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) => ui_options(inner, &key, out),
            toml::Value::String(s) => out.push((key, s.clone())),
            other => out.push((key, other.to_string())),
        }
    }
}

impl Runner {
    fn step(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let kind = match str_of(t, "kind") {
            Ok(Some(k)) => k.to_string(),
            Ok(None) => {
                return err(
                    index,
                    "?",
                    "",
                    "a step needs `kind` (load, set, run, export, check)",
                );
            }
            Err(e) => return err(index, "?", "", e),
        };
        let keys = allowed(&kind);
        if keys.is_empty() {
            return err(
                index,
                &kind,
                "",
                format!("unknown step kind `{kind}` (allowed: load, set, run, export, check)"),
            );
        }
        if let Some(bad) = t.keys().find(|k| !keys.contains(&k.as_str())) {
            return err(
                index,
                &kind,
                "",
                format!(
                    "unknown key `{bad}` in a {kind} step (allowed: {})",
                    keys.join(", ")
                ),
            );
        }
        match kind.as_str() {
            "load" => self.load(index, t),
            "set" => self.set(index, t),
            "run" => self.run(index, t),
            "export" => self.export(index, t),
            "check" => self.check(index, t),
            _ => unreachable!("kinds are checked above"),
        }
    }

    fn load(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let mut paths: Vec<String> = Vec::new();
        match (t.get("path"), t.get("paths")) {
            (Some(toml::Value::String(p)), None) => paths.push(p.clone()),
            (None, Some(toml::Value::Array(a))) => {
                for v in a {
                    match v {
                        toml::Value::String(s) => paths.push(s.clone()),
                        other => {
                            return err(
                                index,
                                "load",
                                "",
                                format!("`paths` entry {other} is not a string"),
                            );
                        }
                    }
                }
            }
            _ => {
                return err(
                    index,
                    "load",
                    "",
                    "give `path = \"…\"` or `paths = [\"…\", …]`",
                );
            }
        }
        let expect = match t.get("expect_errors") {
            None => 0,
            Some(toml::Value::Integer(n)) if *n >= 0 => *n as usize,
            Some(v) => {
                return err(
                    index,
                    "load",
                    "",
                    format!(
                        "`expect_errors` = {}: expected a count ≥ 0",
                        crate::fmt::toml_value(v)
                    ),
                );
            }
        };
        let what = format!("{} path(s): {}", paths.len(), paths.join(", "));
        let mut items = Vec::new();
        for p in &paths {
            let full = self.base.join(p);
            items.extend(load_path(&full, &Progress::hidden()));
        }
        let n = items.len();
        let errors: Vec<String> = items
            .iter()
            .filter(|i| i.entry().status.is_error())
            .map(|i| {
                let e = i.entry();
                let msg = match &e.status {
                    crate::panes::session::FileStatus::Error(m) => m.clone(),
                    _ => String::new(),
                };
                format!("{}: {msg}", e.path)
            })
            .collect();
        self.session.absorb(items);
        let detail = if errors.is_empty() {
            format!("{n} file(s) opened")
        } else {
            format!(
                "{n} file(s), {} error(s): {}",
                errors.len(),
                errors.join("; ")
            )
        };
        if errors.len() == expect {
            ok(index, "load", what, detail)
        } else {
            err(
                index,
                "load",
                what,
                format!("expected {expect} error(s) — {detail}"),
            )
        }
    }

    fn set(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let mut s = self.session.clone();
        let mut what = Vec::new();
        let r = (|| -> Result<(), String> {
            if let Some(p) = str_of(t, "preset")? {
                s.params = crate::model::params::Params::preset(p).map_err(|e| e.to_string())?;
                s.params_source = format!("preset {p}");
                what.push(format!("preset {p}"));
            }
            if let Some(f) = str_of(t, "params")? {
                let path = self.base.join(f);
                s.params = crate::model::params::Params::from_toml_file(&path)
                    .map_err(|e| e.to_string())?;
                s.params_source = path.display().to_string();
                what.push(format!("params {f}"));
            }
            if let Some(v) = t.get("values") {
                let tab = v
                    .as_table()
                    .ok_or("`values` must be a table of key = value")?;
                for (k, x) in tab {
                    s.params.set(k, x).map_err(|e| e.to_string())?;
                    what.push(format!("{k}={x}"));
                }
                s.params.validate().map_err(|e| e.to_string())?;
                s.params_source = format!("{} + batch values", s.params_source);
            }
            if let Some(l) = str_of(t, "level")? {
                s.level = LevelChoice::parse(l).ok_or_else(|| {
                    format!("level `{l}` (allowed: auto, kinematic, ideal, clearance)")
                })?;
                what.push(format!("level {l}"));
            }
            if let Some(v) = t.get("study") {
                let tab = v.as_table().ok_or("`study` must be a table")?;
                let mut grid_t = toml::Table::new();
                let mut setup = StudySetup::default();
                for (k, x) in tab {
                    let num = || {
                        x.as_float()
                            .or_else(|| x.as_integer().map(|i| i as f64))
                            .filter(|v| v.is_finite() && *v >= 0.0)
                            .ok_or_else(|| format!("study `{k}` = {x}: expected a number ≥ 0"))
                    };
                    match k.as_str() {
                        "warmup" => setup.warmup = num()?,
                        "revs" => {
                            setup.revs = num()?;
                            if setup.revs <= 0.0 {
                                return Err("study `revs` must be > 0".into());
                            }
                        }
                        _ => {
                            grid_t.insert(k.clone(), x.clone());
                        }
                    }
                }
                setup.grid =
                    SweepGrid::from_toml_str(&toml::to_string(&grid_t).unwrap_or_default())
                        .map_err(|e| format!("study: {e}"))?;
                what.push(format!("study {} cases", setup.grid.len()));
                s.study_setup = setup;
            }
            if what.is_empty() {
                return Err("nothing to set (give preset, params, values, level or study)".into());
            }
            Ok(())
        })();
        let what_s = what.join(", ");
        match r {
            Ok(()) => {
                self.session = s;
                ok(index, "set", what_s, "")
            }
            Err(e) => err(index, "set", what_s, e),
        }
    }

    fn model_is_fresh(&self) -> bool {
        let s = &self.session;
        s.model.as_ref().is_some_and(|m| {
            m.params == s.params
                && match s.level {
                    LevelChoice::Auto => m.choice == "auto",
                    LevelChoice::Fixed(l) => m.choice == l.name(),
                }
        })
    }

    fn run_model(&mut self) -> Result<String, String> {
        self.session.run_model_now();
        match (&self.session.model, &self.session.model_error) {
            (_, Some(e)) => Err(e.clone()),
            (Some(m), None) => Ok(format!(
                "{} level ({}), {} impacts, {:.0} ms",
                m.level.name(),
                m.level_reason,
                m.result.summary.n_impacts,
                m.result.summary.wall_ms
            )),
            (None, None) => Err("the model did not run".into()),
        }
    }

    fn run(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let what = match str_of(t, "what") {
            Ok(Some(w)) => w.to_string(),
            Ok(None) => {
                return err(
                    index,
                    "run",
                    "",
                    "give `what` (model, study, methods, yield, overlay, calibrate, monitor or trend)",
                );
            }
            Err(e) => return err(index, "run", "", e),
        };
        match what.as_str() {
            "model" => match self.run_model() {
                Ok(d) => ok(index, "run", "model", d),
                Err(e) => err(index, "run", "model", e),
            },
            "study" => {
                let start = std::time::Instant::now();
                self.session.run_study_with(&self.progress.child());
                let Some(r) = &self.session.study else {
                    return err(index, "run", "study", "the study did not run");
                };
                let d = format!(
                    "{} cases, {} failed, {:.0} ms",
                    r.cases.len(),
                    r.failed,
                    start.elapsed().as_secs_f64() * 1e3
                );
                if r.failed > 0 {
                    let first = r
                        .cases
                        .iter()
                        .find_map(|c| c.error.clone())
                        .unwrap_or_default();
                    err(index, "run", "study", format!("{d}; first error: {first}"))
                } else {
                    ok(index, "run", "study", d)
                }
            }
            "methods" => {
                let start = std::time::Instant::now();
                self.session.run_methods_now();
                ok(
                    index,
                    "run",
                    "methods",
                    format!("quick methods lab, {:.1} s", start.elapsed().as_secs_f64()),
                )
            }
            "yield" => {
                self.session.run_yield_with(&self.progress.child());
                match &self.session.yields {
                    Some(y) => ok(
                        index,
                        "run",
                        "yield",
                        format!(
                            "{} images: {} pass, {} fail, {} error(s), {:.0} ms",
                            y.report.items,
                            y.report.passed,
                            y.report.failed,
                            y.report.errors,
                            y.wall_ms
                        ),
                    ),
                    None => err(index, "run", "yield", "the yield did not run"),
                }
            }
            "overlay" => match super::run_overlay_step(&mut self.session) {
                Ok(d) => ok(index, "run", "overlay", d),
                Err(d) => err(index, "run", "overlay", d),
            },
            "calibrate" => {
                match super::run_calibrate_step(&mut self.session, &self.progress.child()) {
                    Ok(d) => ok(index, "run", "calibrate", d),
                    Err(d) => err(index, "run", "calibrate", d),
                }
            }
            "monitor" => {
                let start = std::time::Instant::now();
                self.session.run_monitor_with(&self.progress.child());
                match &self.session.monitor {
                    Some(Ok(m)) => {
                        let failed: Vec<String> = m
                            .logs
                            .iter()
                            .filter_map(|l| {
                                l.report.as_ref().err().map(|e| format!("{}: {e}", l.file))
                            })
                            .collect();
                        let d = format!(
                            "{}: {} OK, {} NOK, {} not evaluated, {:.0} ms",
                            m.part_number,
                            m.ok,
                            m.nok,
                            m.not_evaluated,
                            start.elapsed().as_secs_f64() * 1e3
                        );
                        if failed.is_empty() {
                            ok(index, "run", "monitor", d)
                        } else {
                            err(
                                index,
                                "run",
                                "monitor",
                                format!("{d}; {}", failed.join("; ")),
                            )
                        }
                    }
                    Some(Err(e)) => err(index, "run", "monitor", e.clone()),
                    None => err(index, "run", "monitor", "the monitor did not run"),
                }
            }
            "trend" => match super::run_trend_step(&mut self.session, &self.progress.child()) {
                Ok(d) => ok(index, "run", "trend", d),
                Err(d) => err(index, "run", "trend", d),
            },
            other => err(
                index,
                "run",
                other,
                format!(
                    "cannot run `{other}` (allowed: model, study, methods, yield, overlay, calibrate, monitor, trend)"
                ),
            ),
        }
    }

    /// The pane, its UI state and size from a step; runs the model first
    /// when the pane shows it and it is stale.
    fn prepare(&mut self, t: &toml::Table) -> Result<(PaneId, PaneState, Option<String>), String> {
        let name = str_of(t, "pane")?.ok_or("give `pane`")?;
        let pane = PaneId::parse(name)
            .ok_or_else(|| format!("unknown pane `{name}` (allowed: {})", PaneId::names()))?;
        let size = match str_of(t, "size")? {
            Some(s) => parse_size(s)?,
            None => self.size,
        };
        let mut ui = PaneState::new(size.0, size.1);
        if let Some(v) = t.get("ui") {
            let tab = v
                .as_table()
                .ok_or("`ui` must be a table of option = value")?;
            let mut opts = Vec::new();
            ui_options(tab, "", &mut opts);
            for (k, v) in opts {
                ui.set_option(&k, &v)?;
            }
        }
        let needs_model = matches!(
            pane,
            PaneId::Session | PaneId::Signals | PaneId::Overlay | PaneId::Model
        );
        let mut note = None;
        if needs_model && !self.model_is_fresh() {
            match self.run_model() {
                Ok(_) => note = Some("model run first".to_string()),
                Err(e) => note = Some(format!("model run failed: {e}")),
            }
        }
        if let Some(ran) = self.session.prepare_pane(pane, &ui) {
            note = Some(match note {
                Some(n) => format!("{n}; {ran} first"),
                None => format!("{ran} first"),
            });
        }
        Ok((pane, ui, note))
    }

    fn export(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let r = (|| -> Result<(String, String), String> {
            let (pane, ui, note) = self.prepare(t)?;
            let path = str_of(t, "path")?.ok_or("give `path`")?;
            let full = export_path(&self.out, path)?;
            let format = match str_of(t, "format")? {
                Some(f) => Format::parse(f)
                    .ok_or_else(|| format!("format `{f}` (allowed: json, csv, png, text)"))?,
                None => Format::from_path(&full).ok_or(
                    "give `format` (json, csv, png, text) or a path ending in one of them",
                )?,
            };
            let view = panes::view(pane, &self.session, &ui);
            let what = export(&self.session, &view, format, (ui.width, ui.height), &full)?;
            self.written.push(full.display().to_string());
            let mut detail = format!("{what} → {}", full.display());
            if let Some(n) = note {
                detail.push_str(&format!(" ({n})"));
            }
            Ok((format!("{} → {path}", pane.name()), detail))
        })();
        match r {
            Ok((w, d)) => ok(index, "export", w, d),
            Err(e) => err(
                index,
                "export",
                str_of(t, "path").ok().flatten().unwrap_or(""),
                e,
            ),
        }
    }

    fn check(&mut self, index: usize, t: &toml::Table) -> StepReport {
        let label = str_of(t, "name").ok().flatten().map(str::to_string);
        let fig = str_of(t, "figure").ok().flatten().unwrap_or("").to_string();
        let pane_name = str_of(t, "pane").ok().flatten().unwrap_or("?").to_string();
        let op = str_of(t, "op").ok().flatten().unwrap_or("").to_string();
        let threshold = t.get("value").cloned();
        let what = {
            let th = threshold
                .as_ref()
                .map(|v| match v {
                    toml::Value::String(s) => format!("\"{s}\""),
                    other => other.to_string(),
                })
                .unwrap_or_default();
            let base = format!("{pane_name} {fig} {op} {th}");
            match &label {
                Some(l) => format!("{l}: {base}"),
                None => base,
            }
        };
        let r = (|| -> Result<(bool, String), String> {
            if fig.is_empty() {
                return Err("give `figure` (a dotted path in the pane's view model)".into());
            }
            let threshold = threshold.clone().ok_or("give `value` (the threshold)")?;
            let (pane, ui, note) = self.prepare(t)?;
            let view = panes::view(pane, &self.session, &ui);
            let json = view.to_json();
            let found = figure(&json, &fig)?;
            let shown = found.show();
            let pass = compare(&found, &op, &threshold)?;
            let mut detail = format!("value {shown}");
            if let Some(n) = note {
                detail.push_str(&format!(" ({n})"));
            }
            Ok((pass, detail))
        })();
        match r {
            Ok((pass, detail)) => StepReport {
                index,
                kind: "check".into(),
                what,
                outcome: if pass { Outcome::Pass } else { Outcome::Fail },
                detail,
            },
            // A check that cannot be evaluated fails (it did not show what it should).
            Err(e) => StepReport {
                index,
                kind: "check".into(),
                what,
                outcome: Outcome::Fail,
                detail: e,
            },
        }
    }
}

/// Compares a figure with a threshold.
fn compare(found: &super::Figure, op: &str, threshold: &toml::Value) -> Result<bool, String> {
    let num = match threshold {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    if let Some(th) = num {
        let v = found
            .as_f64()
            .ok_or_else(|| format!("the figure is {}, not a number", found.show()))?;
        if v.is_nan() {
            return Err("the figure is not available (NaN)".into());
        }
        return match op {
            "<" => Ok(v < th),
            "<=" => Ok(v <= th),
            ">" => Ok(v > th),
            ">=" => Ok(v >= th),
            "==" => Ok(v == th),
            "!=" => Ok(v != th),
            other => Err(format!(
                "op `{other}` (allowed for numbers: < <= > >= == !=)"
            )),
        };
    }
    let text = match found {
        super::Figure::Value(serde_json::Value::String(s)) => s.clone(),
        other => other.show(),
    };
    let th = match threshold {
        toml::Value::String(s) => s.clone(),
        toml::Value::Boolean(b) => b.to_string(),
        other => return Err(format!("value {other}: expected a number, text or boolean")),
    };
    match op {
        "==" => Ok(text == th),
        "!=" => Ok(text != th),
        "contains" => Ok(text.contains(&th)),
        other => Err(format!("op `{other}` (allowed for text: == != contains)")),
    }
}

#[cfg(test)]
#[path = "script_tests.rs"]
mod tests;
