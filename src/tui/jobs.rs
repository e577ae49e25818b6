//! The app's background work: which analysis the current pane needs and
//! does not have yet ([`App::schedule`]), starting jobs, cancelling them,
//! and taking a finished job's output into the session. The update loop
//! is in [`super::app`]; this is the part of it that talks to the worker.

use super::app::{App, Running};
use super::worker::{JobKind, JobOutput, JobRequest};
use crate::panes::PaneId;
use crate::panes::session::FileStatus;
use crate::progress::Progress;
use std::path::PathBuf;
use std::sync::Arc;

impl App {
    fn is_running(&self, kind: JobKind) -> bool {
        self.running.iter().any(|r| r.kind == kind)
    }

    /// Starts the analysis the current pane needs and does not have yet:
    /// the inspection of the Vision pane's image, the batch yield, the
    /// overlay of the log shown. Called after every update, so a pane
    /// shows real results as soon as the worker has them; the first frame
    /// never waits for them.
    pub fn schedule(&mut self) {
        match self.pane {
            PaneId::Vision if !self.session.images.is_empty() => {
                let n = self.session.images.len();
                let i = self.ui.vision.image.min(n - 1);
                if self.session.inspection(i).is_none()
                    && !self.is_running(JobKind::Inspect)
                    && !self.suppressed.contains(&JobKind::Inspect)
                {
                    self.start_inspect(i);
                }
            }
            PaneId::Yield
                if !self.session.images.is_empty()
                    && self.session.yields.is_none()
                    && !self.is_running(JobKind::Yield)
                    && !self.suppressed.contains(&JobKind::Yield) =>
            {
                self.start_yield();
            }
            PaneId::Line
                if !self.session.logs.is_empty()
                    && !self.session.process_recipes.is_empty()
                    && self.session.monitor.is_none()
                    && !self.is_running(JobKind::Monitor)
                    && !self.suppressed.contains(&JobKind::Monitor) =>
            {
                self.start_monitor();
            }
            PaneId::Trend
                if !self.session.logs.is_empty()
                    && self.session.trend.is_none()
                    && !self.is_running(JobKind::Trend)
                    && !self.suppressed.contains(&JobKind::Trend) =>
            {
                self.start_trend();
            }
            PaneId::Overlay if !self.session.logs.is_empty() => {
                let i = self.ui.overlay.log.min(self.session.logs.len() - 1);
                if self.session.overlay_of(i).is_none()
                    && !self.is_running(JobKind::Overlay)
                    && !self.suppressed.contains(&JobKind::Overlay)
                {
                    self.start_overlay(i);
                }
            }
            _ => {}
        }
    }

    pub fn start_inspect(&mut self, index: usize) {
        if let Some(img) = self.session.images.get(index) {
            self.start(JobRequest::Inspect {
                index,
                image: Box::new(img.clone()),
                book: self.session.recipe_book(),
            });
        }
    }

    pub fn start_monitor(&mut self) {
        let book = (!self.session.recipes.is_empty()).then(|| self.session.recipe_book());
        self.start(JobRequest::Monitor {
            recipes: self.session.process_recipes.clone(),
            logs: self.session.logs.clone(),
            images: self.session.images.clone(),
            book,
            overlays: self.session.overlays.clone(),
        });
    }

    pub fn start_trend(&mut self) {
        self.start(JobRequest::Trend {
            logs: self.session.logs.clone(),
            recipes: self.session.recipes.clone(),
        });
    }

    pub fn start_yield(&mut self) {
        self.start(JobRequest::Yield {
            images: self.session.images.clone(),
            book: self.session.recipe_book(),
        });
    }

    pub fn start_overlay(&mut self, index: usize) {
        match self.session.logs.get(index).map(|l| l.rig.clone()) {
            Some(Some((log, cycles))) => self.start(JobRequest::Overlay { index, log, cycles }),
            Some(None) => self.session.run_overlay_now(index), // records why not
            None => {}
        }
    }

    /// Calibrates log `index` against the model in the background (the
    /// Overlay pane's key `C`).
    pub fn start_calibration(&mut self, index: usize) {
        match self.session.logs.get(index).map(|l| l.rig.clone()) {
            Some(Some((log, cycles))) => self.start(JobRequest::Calibrate { index, log, cycles }),
            Some(None) => self
                .session
                .run_calibration_with(index, &Progress::hidden()), // records why not
            None => {}
        }
    }

    /// Queues a job; a running job of the same kind (model, study) is
    /// cancelled and its result will be ignored.
    pub fn start(&mut self, req: JobRequest) {
        let kind = req.kind();
        self.suppressed.retain(|k| *k != kind);
        if kind != JobKind::Load {
            for r in self.running.iter().filter(|r| r.kind == kind) {
                r.progress.cancel();
            }
            self.running.retain(|r| r.kind != kind);
        }
        let id = self.next_id;
        self.next_id += 1;
        let progress = Progress::new(0);
        self.running.push(Running {
            id,
            kind,
            label: req.label(),
            progress: progress.clone(),
        });
        self.requests.push((id, req, progress));
    }

    pub fn start_model(&mut self) {
        self.start(JobRequest::Model {
            params: Box::new(self.session.params.clone()),
            level: self.session.level,
        });
    }

    pub fn start_study(&mut self) {
        self.start(JobRequest::Study {
            params: Box::new(self.session.params.clone()),
            setup: self.session.study_setup.clone(),
        });
    }

    pub fn open(&mut self, paths: Vec<PathBuf>) {
        if !paths.is_empty() {
            self.start(JobRequest::Load { paths });
        }
    }

    /// Takes the queued jobs (the runtime starts them; tests run them in line).
    pub fn take_requests(&mut self) -> Vec<(u64, JobRequest, Arc<Progress>)> {
        std::mem::take(&mut self.requests)
    }

    /// Cancels every running job.
    pub fn cancel_jobs(&mut self) {
        if self.running.is_empty() {
            return;
        }
        for r in &self.running {
            r.progress.cancel();
            if matches!(
                r.kind,
                JobKind::Inspect
                    | JobKind::Yield
                    | JobKind::Overlay
                    | JobKind::Monitor
                    | JobKind::Trend
            ) {
                self.suppressed.push(r.kind);
            }
        }
        let names: Vec<String> = self.running.iter().map(|r| r.label.clone()).collect();
        self.running.clear();
        self.message = Some((format!("cancelled: {}", names.join(", ")), false));
    }

    pub(super) fn job_done(&mut self, id: u64, out: JobOutput) {
        let Some(pos) = self.running.iter().position(|r| r.id == id) else {
            return; // superseded or cancelled: ignore
        };
        let job = self.running.remove(pos);
        match out {
            JobOutput::Model(r) => {
                let r = *r;
                let failed = r.as_ref().err().cloned();
                self.session.set_model_run(r);
                self.message = failed.map(|e| (format!("model run failed: {e}"), true));
            }
            JobOutput::Study(r) => {
                let cancelled = job.progress.is_cancelled();
                let failed = r.failed;
                let n = r.cases.len();
                self.session.set_study(*r);
                self.message = Some(if cancelled {
                    (
                        format!("study cancelled ({failed} of {n} cases did not run)"),
                        true,
                    )
                } else if failed > 0 {
                    (format!("study done: {failed} of {n} cases failed"), true)
                } else {
                    (format!("study done: {n} cases"), false)
                });
            }
            JobOutput::Loaded(items) => {
                let n = items.len();
                let errors: Vec<String> = items
                    .iter()
                    .filter_map(|i| match &i.entry().status {
                        FileStatus::Error(m) => Some(format!("{}: {m}", i.entry().path)),
                        _ => None,
                    })
                    .collect();
                let first_new = self.session.files.len();
                let params_changed = self.session.absorb(items);
                self.ui.session.selected = first_new;
                self.message = Some(match errors.as_slice() {
                    [] => (format!("opened {n} file(s)"), false),
                    [one] => (one.clone(), true),
                    many => (
                        format!(
                            "{} of {n} file(s) could not be used (see Session)",
                            many.len()
                        ),
                        true,
                    ),
                });
                if params_changed {
                    self.start_model();
                }
            }
            JobOutput::Methods(lab) => {
                if job.progress.is_cancelled() {
                    self.message = Some(("methods lab cancelled".into(), true));
                } else {
                    self.session.methods = Some(*lab);
                    self.session.methods_error = None;
                    self.message = Some(("methods lab done".into(), false));
                }
            }
            JobOutput::Inspected(r) => {
                if let Some(e) = &r.result.error {
                    self.message = Some((format!("{}: {}", r.result.name, e.message), true));
                }
                self.session.set_inspection(*r);
            }
            JobOutput::Monitor(r) => {
                self.message = Some(match &*r {
                    Ok(run) => (
                        format!(
                            "monitor {}: {} OK, {} NOK, {} not evaluated",
                            run.part_number, run.ok, run.nok, run.not_evaluated
                        ),
                        false,
                    ),
                    Err(e) => (format!("monitor: {e}"), true),
                });
                self.session.set_monitor(*r);
            }
            JobOutput::Trend(r) => {
                self.message = Some(match &*r {
                    Ok(t) => (
                        format!(
                            "trend: {} head(s), {} log(s) calibrated, {} left out",
                            t.heads.len(),
                            t.calibrated,
                            t.errors.len()
                        ),
                        !t.errors.is_empty(),
                    ),
                    Err(e) => (format!("trend: {e}"), true),
                });
                self.session.set_trend(*r);
            }
            JobOutput::Yield(r) => {
                let rep = &r.report;
                self.message = Some((
                    format!(
                        "yield {}: {} of {} connectors pass, {} error(s), {:.1} s",
                        rep.yield_frac
                            .map(|y| format!("{:.1} %", 100.0 * y))
                            .unwrap_or_else(|| "–".into()),
                        rep.passed,
                        rep.inspected,
                        rep.errors,
                        r.wall_ms / 1e3
                    ),
                    false,
                ));
                self.session.set_yield(*r);
            }
            JobOutput::Overlay(r) => {
                if let Err(e) = &r.report {
                    self.message = Some((format!("overlay: {e}"), true));
                }
                self.session.set_overlay(*r);
            }
            JobOutput::Calibrated(r) => {
                self.message = Some(match &r.report {
                    Ok(c) => (
                        format!(
                            "calibrated {}: {} cycles, {:.1} s",
                            c.file,
                            c.cycles,
                            r.wall_ms / 1e3
                        ),
                        false,
                    ),
                    Err(e) => (format!("calibration: {e}"), true),
                });
                self.session.set_calibration(*r);
            }
            JobOutput::Failed(e) => {
                if job.kind == JobKind::Methods {
                    self.session.methods_error = Some(e.clone());
                }
                self.message = Some((e, true))
            }
        }
    }
}
