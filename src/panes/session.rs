//! The session: every file the user opened, the parameters in force, and the
//! latest results the panes show.
//!
//! The session holds state only. Loading and running are the engine's
//! ([`crate::engine`]): [`load_path`] turns paths into [`Loaded`] items that
//! [`Session::absorb`] merges (the TUI loads on its worker thread and
//! absorbs on the UI thread; batch mode and `render` call both in a row);
//! the jobs ([`run_model`], [`run_study`], [`run_yield`], [`run_overlay`],
//! [`run_calibration`] …)
//! return results that enter through the `set_*` methods, so every pane
//! stays a pure function of the session.

pub use crate::engine::calibrate::{CalibrationRun, run_calibration};
pub use crate::engine::entries::{
    FINDING_SEP, FileEntry, FileKind, FileStatus, ImageEntry, ImageSource, Loaded, LogEntry,
    RecipeEntry,
};
pub use crate::engine::load::{load_image_bytes, load_log_bytes, load_path, load_toml_text};
pub use crate::engine::model::{
    MethodsLab, ModelRun, StudySetup, predicted_signals, run_methods, run_model, run_study,
};
pub use crate::engine::overlay::{OverlayRun, run_overlay};
pub use crate::engine::process::monitor_session;
pub use crate::engine::signals::{Channel, SignalSet};
pub use crate::engine::vision::{Inspected, YieldRun, inspect_image, recipe_book, run_yield};
use crate::model::params::Params;
pub use crate::process::run::MonitorRun;
use crate::progress::Progress;
use crate::sim::sweep::SweepResult;
use crate::sim::{Level, LevelChoice};
use crate::vision::batch::RecipeBook;
use std::borrow::Cow;
use std::path::Path;

/// The state every pane is computed from.
#[derive(Debug, Clone)]
pub struct Session {
    /// What this session is ("demo (embedded)", or the files opened).
    pub title: String,
    pub files: Vec<FileEntry>,
    pub params: Params,
    /// Where the parameters come from (preset, file, edits).
    pub params_source: String,
    pub level: LevelChoice,
    pub model: Option<ModelRun>,
    pub model_error: Option<String>,
    pub study_setup: StudySetup,
    pub study: Option<SweepResult>,
    pub study_error: Option<String>,
    pub logs: Vec<LogEntry>,
    pub recipes: Vec<RecipeEntry>,
    pub images: Vec<ImageEntry>,
    /// How the session is displayed (set by the front end: colours, image
    /// protocol), shown on the Session pane.
    pub display: Option<String>,
    /// The methods lab (quick effort: dynamics and vision), once run.
    pub methods: Option<MethodsLab>,
    pub methods_error: Option<String>,
    /// Vision inspections by image index (run on demand: the image shown).
    pub inspections: std::collections::BTreeMap<usize, Inspected>,
    /// The batch yield over every image (None: not run, or images changed since).
    pub yields: Option<YieldRun>,
    /// Measured-vs-predicted comparisons by log index.
    pub overlays: std::collections::BTreeMap<usize, OverlayRun>,
    /// Calibrations against the model by log index (run on demand: the
    /// Overlay pane's key `C`, batch `run calibrate`).
    pub calibrations: std::collections::BTreeMap<usize, CalibrationRun>,
    /// Process recipes (evaluation objects per part number).
    pub process_recipes: Vec<crate::process::ProcessRecipe>,
    /// The process monitor over the logs (None: not run, or inputs changed
    /// since), or why it could not run. Shared: the Line pane's view holds it
    /// every frame without copying it.
    pub monitor: Option<Result<std::sync::Arc<MonitorRun>, String>>,
    /// The wear trend over the logs (None: not run, or the logs or recipes
    /// changed since), or why it could not run.
    pub trend: Option<Result<std::sync::Arc<crate::wear::TrendReport>, String>>,
    /// The live line being followed (`tui --follow`, `demo --live`).
    pub live: Option<super::live_state::LiveState>,
}

impl Default for Session {
    fn default() -> Self {
        Self::new("empty session")
    }
}

impl Session {
    /// An empty session on the `paper` preset.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            files: Vec::new(),
            params: Params::paper(),
            params_source: "preset paper".into(),
            level: LevelChoice::Fixed(Level::Clearance),
            model: None,
            model_error: None,
            study_setup: StudySetup::default(),
            study: None,
            study_error: None,
            logs: Vec::new(),
            recipes: Vec::new(),
            images: Vec::new(),
            display: None,
            methods: None,
            methods_error: None,
            inspections: Default::default(),
            yields: None,
            overlays: Default::default(),
            calibrations: Default::default(),
            process_recipes: Vec::new(),
            monitor: None,
            trend: None,
            live: None,
        }
    }

    /// Opens paths (synchronously) and merges them.
    pub fn open_paths<P: AsRef<Path>>(&mut self, paths: &[P]) {
        for p in paths {
            let items = load_path(p.as_ref(), &Progress::hidden());
            self.absorb(items);
        }
    }

    /// Merges loaded items. A parameter file replaces the parameters in
    /// force (the model must then be re-run); everything else is added.
    /// Returns whether the parameters changed.
    pub fn absorb(&mut self, items: Vec<Loaded>) -> bool {
        let mut params_changed = false;
        for item in items {
            match item {
                Loaded::Entry(e) => self.files.push(e),
                Loaded::Params(e, p) => {
                    self.params_source = e.path.clone();
                    self.params = *p;
                    self.files.push(e);
                    params_changed = true;
                }
                Loaded::Log(e, log) => {
                    self.files.push(e);
                    self.logs.push(*log);
                    self.monitor = None;
                    self.trend = None;
                }
                Loaded::Process(e, r) => {
                    self.files.push(e);
                    self.process_recipes.push(*r);
                    self.monitor = None;
                }
                Loaded::Recipe(e, r) => {
                    self.files.push(e);
                    self.recipes.push(*r);
                    self.trend = None;
                    // Another recipe can change which one an image gets.
                    self.inspections.clear();
                    self.yields = None;
                    self.monitor = None;
                }
                Loaded::Image(e, img) => {
                    self.files.push(e);
                    self.images.push(*img);
                    self.yields = None;
                    self.monitor = None;
                }
            }
        }
        params_changed
    }

    /// Errors found while loading (file, message).
    pub fn load_errors(&self) -> Vec<(&str, &str)> {
        self.files
            .iter()
            .filter_map(|f| match &f.status {
                FileStatus::Error(m) => Some((f.path.as_str(), m.as_str())),
                _ => None,
            })
            .collect()
    }

    /// Records a finished model run (or its error).
    pub fn set_model_run(&mut self, r: Result<ModelRun, String>) {
        match r {
            Ok(run) => {
                self.model = Some(run);
                self.model_error = None;
            }
            Err(e) => self.model_error = Some(e),
        }
    }

    /// Records a finished study.
    pub fn set_study(&mut self, r: SweepResult) {
        self.study_error = None;
        self.study = Some(r);
    }

    /// Runs the model now (batch mode and tests; the TUI runs [`run_model`]
    /// on its worker).
    pub fn run_model_now(&mut self) {
        let r = run_model(&self.params, self.level, &Progress::hidden());
        self.set_model_run(r);
    }

    /// Runs the quick methods lab now.
    pub fn run_methods_now(&mut self) {
        self.methods = Some(run_methods(&Progress::hidden()));
        self.methods_error = None;
    }

    /// Runs the study now.
    pub fn run_study_now(&mut self) {
        self.run_study_with(&Progress::hidden());
    }

    /// Runs the study now, reporting to (and stopped by) `progress`.
    pub fn run_study_with(&mut self, progress: &Progress) {
        let r = run_study(&self.params, &self.study_setup, progress);
        self.set_study(r);
    }

    /// The signals to show: the first loaded log, else the model's
    /// prediction over time (None when neither exists).
    pub fn signal_set(&self, log: usize) -> Option<Cow<'_, SignalSet>> {
        if let Some(l) = self.logs.get(log).or_else(|| self.logs.first()) {
            return Some(Cow::Borrowed(&l.signals));
        }
        self.model
            .as_ref()
            .map(|m| Cow::Owned(predicted_signals(m)))
    }
}

impl Session {
    /// Runs, in line, the analysis a pane shows when it has not run yet:
    /// Vision the inspection of its image, Yield the batch, Overlay the
    /// comparison of its log (what the TUI's worker does when the pane is
    /// shown). Returns what ran, for batch reports.
    pub fn prepare_pane(&mut self, pane: super::PaneId, ui: &super::PaneState) -> Option<String> {
        use super::PaneId;
        match pane {
            PaneId::Vision if !self.images.is_empty() => {
                let i = ui.vision.image.min(self.images.len() - 1);
                if self.inspection(i).is_none() {
                    self.inspect_now(i);
                    return Some(format!("inspected image {i}"));
                }
            }
            PaneId::Yield if !self.images.is_empty() && self.yields.is_none() => {
                self.run_yield_now();
                return Some(format!("yield over {} images", self.images.len()));
            }
            PaneId::Overlay if !self.logs.is_empty() => {
                let i = ui.overlay.log.min(self.logs.len() - 1);
                let mut ran = Vec::new();
                if self.overlay_of(i).is_none() {
                    self.run_overlay_now(i);
                    ran.push(format!("overlay of log {i}"));
                }
                // The calibration is asked for (`overlay.calibrate=yes`):
                // the TUI runs it on its key.
                if ui.overlay.calibrate && self.calibration_of(i).is_none() {
                    self.run_calibration_with(i, &Progress::hidden());
                    ran.push(format!("calibration of log {i}"));
                }
                if !ran.is_empty() {
                    return Some(ran.join(", "));
                }
            }
            PaneId::Line
                if !self.logs.is_empty()
                    && !self.process_recipes.is_empty()
                    && self.monitor.is_none() =>
            {
                self.run_monitor_with(&Progress::hidden());
                return Some(format!("monitor over {} log(s)", self.logs.len()));
            }
            PaneId::Trend if !self.logs.is_empty() && self.trend.is_none() => {
                self.run_trend_with(&Progress::hidden());
                return Some(format!("trend over {} log(s)", self.logs.len()));
            }
            _ => {}
        }
        None
    }

    /// The recipe book of the session.
    pub fn recipe_book(&self) -> RecipeBook {
        let invalid = self
            .files
            .iter()
            .filter(|f| f.kind == FileKind::Recipe)
            .filter_map(|f| match &f.status {
                FileStatus::Error(m) => Some(m.clone()),
                _ => None,
            })
            .collect();
        recipe_book(&self.recipes, invalid)
    }

    /// Records an inspection (replacing an older one of the same image).
    pub fn set_inspection(&mut self, r: Inspected) {
        self.inspections.insert(r.image, r);
    }

    /// The inspection of image `i`, if it ran.
    pub fn inspection(&self, i: usize) -> Option<&Inspected> {
        self.inspections.get(&i)
    }

    /// Inspects image `i` now (batch mode, `render`, tests).
    pub fn inspect_now(&mut self, i: usize) {
        if let Some(img) = self.images.get(i) {
            let r = inspect_image(i, img, &self.recipe_book());
            self.set_inspection(r);
        }
    }

    pub fn set_yield(&mut self, r: YieldRun) {
        self.yields = Some(r);
    }

    /// Runs the batch yield now.
    pub fn run_yield_now(&mut self) {
        self.run_yield_with(&Progress::hidden());
    }

    /// Runs the batch yield now, reporting to (and stopped by) `progress`.
    pub fn run_yield_with(&mut self, progress: &Progress) {
        let r = run_yield(&self.images, &self.recipe_book(), progress);
        self.set_yield(r);
    }

    pub fn set_overlay(&mut self, r: OverlayRun) {
        self.overlays.insert(r.log, r);
    }

    /// The overlay of log `i`, if it ran.
    pub fn overlay_of(&self, i: usize) -> Option<&OverlayRun> {
        self.overlays.get(&i)
    }

    /// Runs the process monitor over the logs now (with the vision recipes,
    /// each connector's story), reporting to (and stopped by) `progress`.
    pub fn run_monitor_with(&mut self, progress: &Progress) {
        let book = (!self.recipes.is_empty()).then(|| self.recipe_book());
        self.set_monitor(monitor_session(
            &self.process_recipes,
            &self.logs,
            &self.images,
            book.as_ref(),
            &self.overlays,
            progress,
        ));
    }

    /// Runs the wear trend over the logs now, reporting to (and stopped by) `progress`.
    pub fn run_trend_with(&mut self, progress: &Progress) {
        let r = crate::engine::trend::trend_session(&self.logs, &self.recipes, progress);
        self.set_trend(r);
    }

    /// Records a finished trend (or why it could not run).
    pub fn set_trend(&mut self, r: Result<crate::wear::TrendReport, String>) {
        self.trend = Some(r.map(std::sync::Arc::new));
    }

    /// Records a finished monitor run (or why it could not run).
    pub fn set_monitor(&mut self, r: Result<MonitorRun, String>) {
        self.monitor = Some(r.map(std::sync::Arc::new));
    }

    pub fn set_calibration(&mut self, r: CalibrationRun) {
        self.calibrations.insert(r.log, r);
    }

    /// The calibration of log `i`, if it ran.
    pub fn calibration_of(&self, i: usize) -> Option<&CalibrationRun> {
        self.calibrations.get(&i)
    }

    /// Calibrates log `i` now against the model, reporting to (and stopped
    /// by) `progress`.
    pub fn run_calibration_with(&mut self, i: usize, progress: &Progress) {
        let r = match self.rig_of(i) {
            Some(Ok((log, cycles))) => run_calibration(i, log, cycles, progress),
            Some(Err(e)) => CalibrationRun {
                log: i,
                report: Err(e),
                wall_ms: 0.0,
            },
            None => return,
        };
        self.set_calibration(r);
    }

    /// Log `i`'s rig data and cycles, or why it has none (None: no log `i`).
    fn rig_of(
        &self,
        i: usize,
    ) -> Option<Result<(&crate::rig::RigLog, &crate::rig::cycles::CycleSet), String>> {
        let l = self.logs.get(i)?;
        Some(match &l.rig {
            Some((log, cycles)) => Ok((log, cycles)),
            None => Err(format!("{}: not a rig log (no cycles to compare)", l.path)),
        })
    }

    /// Runs the overlay of log `i` now.
    pub fn run_overlay_now(&mut self, i: usize) {
        let r = match self.rig_of(i) {
            Some(Ok((log, cycles))) => run_overlay(i, log, cycles, &Progress::hidden()),
            Some(Err(e)) => OverlayRun {
                log: i,
                report: Err(e),
                wall_ms: 0.0,
            },
            None => return,
        };
        self.set_overlay(r);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::load::load_path;

    #[test]
    fn missing_unknown_and_corrupt_files_become_errors() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope.mcap");
        let r = load_path(&missing, &Progress::hidden());
        assert_eq!(r.len(), 1);
        assert!(r[0].entry().status.is_error());
        let odd = dir.path().join("a.xyz");
        std::fs::write(&odd, b"hello").unwrap();
        let r = load_path(&odd, &Progress::hidden());
        assert!(r[0].entry().status.is_error());
        let png = dir.path().join("broken.png");
        std::fs::write(&png, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let r = load_path(&png, &Progress::hidden());
        match &r[0].entry().status {
            // The vision decoder's words, as `pinsight inspect` gives them.
            FileStatus::Error(m) => assert!(m.contains("corrupt or truncated png data"), "{m}"),
            s => panic!("{s:?}"),
        }
        // A folder lists its files; ground-truth JSON is skipped quietly.
        std::fs::write(dir.path().join("truth.json"), b"{}").unwrap();
        let r = load_path(dir.path(), &Progress::hidden());
        assert_eq!(r.len(), 2, "{r:?}");
        let mut s = Session::default();
        s.absorb(r);
        assert_eq!(s.load_errors().len(), 2);
        // The broken image stays an image of the session, so the yield
        // counts it as an error item instead of dropping it.
        assert_eq!(s.images.len(), 1);
        s.run_yield_now();
        let y = s.yields.as_ref().unwrap();
        assert_eq!((y.report.items, y.report.errors), (1, 1));
    }
}
