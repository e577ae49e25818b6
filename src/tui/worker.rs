//! Background work: each job runs on its own thread with a shared
//! [`Progress`] (the status-line gauge reads it, Esc / `c` cancels it) and
//! sends its output back over a channel. The UI thread never waits on it.
//!
//! A job is a plain request ([`JobRequest`]) executed by [`execute`], a
//! pure function also used by tests to run jobs in line.

use crate::engine::calibrate::{CalibrationRun, run_calibration};
use crate::engine::entries::{ImageEntry, Loaded};
use crate::engine::load::load_path;
use crate::engine::model::{ModelRun, StudySetup, run_model, run_study};
use crate::engine::overlay::{OverlayRun, run_overlay};
use crate::engine::vision::{Inspected, YieldRun, inspect_image, run_yield};
use crate::model::params::Params;
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::CycleSet;
use crate::sim::LevelChoice;
use crate::sim::sweep::SweepResult;
use crate::vision::batch::RecipeBook;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};

/// What kind of work a job does (a new job of a kind supersedes the running one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JobKind {
    Model,
    Study,
    Load,
    Methods,
    Inspect,
    Yield,
    Overlay,
    Calibrate,
    Monitor,
    Trend,
}

/// A unit of background work.
#[derive(Debug, Clone)]
pub enum JobRequest {
    Model {
        params: Box<Params>,
        level: LevelChoice,
    },
    Study {
        params: Box<Params>,
        setup: StudySetup,
    },
    Load {
        paths: Vec<PathBuf>,
    },
    Methods,
    /// Inspect one image (the Vision pane's current image).
    Inspect {
        index: usize,
        image: Box<ImageEntry>,
        book: RecipeBook,
    },
    /// The batch yield over every image.
    Yield {
        images: Vec<ImageEntry>,
        book: RecipeBook,
    },
    /// The process monitor over the session's logs (the Line pane).
    Monitor {
        recipes: Vec<crate::process::ProcessRecipe>,
        logs: Vec<crate::engine::entries::LogEntry>,
        images: Vec<ImageEntry>,
        book: Option<RecipeBook>,
        /// The overlays already run (their bands join the connectors' stories).
        overlays: std::collections::BTreeMap<usize, crate::engine::overlay::OverlayRun>,
    },
    /// The wear trend over the session's logs (the Trend pane).
    Trend {
        logs: Vec<crate::engine::entries::LogEntry>,
        recipes: Vec<crate::engine::entries::RecipeEntry>,
    },
    /// Measured vs predicted for one log.
    Overlay {
        index: usize,
        log: Arc<RigLog>,
        cycles: Arc<CycleSet>,
    },
    /// One log calibrated against the model (the Overlay pane's key `C`).
    Calibrate {
        index: usize,
        log: Arc<RigLog>,
        cycles: Arc<CycleSet>,
    },
}

impl JobRequest {
    pub fn kind(&self) -> JobKind {
        match self {
            JobRequest::Model { .. } => JobKind::Model,
            JobRequest::Study { .. } => JobKind::Study,
            JobRequest::Load { .. } => JobKind::Load,
            JobRequest::Methods => JobKind::Methods,
            JobRequest::Inspect { .. } => JobKind::Inspect,
            JobRequest::Yield { .. } => JobKind::Yield,
            JobRequest::Overlay { .. } => JobKind::Overlay,
            JobRequest::Calibrate { .. } => JobKind::Calibrate,
            JobRequest::Monitor { .. } => JobKind::Monitor,
            JobRequest::Trend { .. } => JobKind::Trend,
        }
    }

    pub fn label(&self) -> String {
        match self {
            JobRequest::Model { .. } => "model".into(),
            JobRequest::Study { setup, .. } => format!("study ({} cases)", setup.grid.len()),
            JobRequest::Methods => "methods lab (quick)".into(),
            JobRequest::Inspect { image, .. } => format!("inspecting {}", image.name),
            JobRequest::Yield { images, .. } => format!("yield over {} images", images.len()),
            JobRequest::Overlay { log, .. } => format!("overlay of {}", log.file),
            JobRequest::Calibrate { log, .. } => format!("calibrating {}", log.file),
            JobRequest::Monitor { logs, .. } => format!("monitor over {} log(s)", logs.len()),
            JobRequest::Trend { logs, .. } => format!("trend over {} log(s)", logs.len()),
            JobRequest::Load { paths } => match paths.as_slice() {
                [one] => format!("opening {}", one.display()),
                many => format!("opening {} paths", many.len()),
            },
        }
    }
}

/// What a job produced.
#[derive(Debug, Clone)]
pub enum JobOutput {
    Model(Box<Result<ModelRun, String>>),
    Study(Box<SweepResult>),
    Loaded(Vec<Loaded>),
    Methods(Box<crate::panes::session::MethodsLab>),
    Inspected(Box<Inspected>),
    Yield(Box<YieldRun>),
    Overlay(Box<OverlayRun>),
    Calibrated(Box<CalibrationRun>),
    Monitor(Box<Result<crate::process::run::MonitorRun, String>>),
    Trend(Box<Result<crate::wear::TrendReport, String>>),
    /// The job panicked (a defect): the message, for the status line.
    Failed(String),
}

/// Runs a job in the calling thread.
pub fn execute(req: JobRequest, progress: &Progress) -> JobOutput {
    match req {
        JobRequest::Model { params, level } => {
            JobOutput::Model(Box::new(run_model(&params, level, progress)))
        }
        JobRequest::Study { params, setup } => {
            JobOutput::Study(Box::new(run_study(&params, &setup, progress)))
        }
        JobRequest::Methods => {
            JobOutput::Methods(Box::new(crate::panes::session::run_methods(progress)))
        }
        JobRequest::Inspect { index, image, book } => {
            progress.set_total(1);
            let r = inspect_image(index, &image, &book);
            progress.inc(1);
            JobOutput::Inspected(Box::new(r))
        }
        JobRequest::Yield { images, book } => {
            JobOutput::Yield(Box::new(run_yield(&images, &book, progress)))
        }
        JobRequest::Overlay { index, log, cycles } => {
            JobOutput::Overlay(Box::new(run_overlay(index, &log, &cycles, progress)))
        }
        JobRequest::Calibrate { index, log, cycles } => {
            JobOutput::Calibrated(Box::new(run_calibration(index, &log, &cycles, progress)))
        }
        JobRequest::Monitor {
            recipes,
            logs,
            images,
            book,
            overlays,
        } => JobOutput::Monitor(Box::new(crate::engine::process::monitor_session(
            &recipes,
            &logs,
            &images,
            book.as_ref(),
            &overlays,
            progress,
        ))),
        JobRequest::Trend { logs, recipes } => JobOutput::Trend(Box::new(
            crate::engine::trend::trend_session(&logs, &recipes, progress),
        )),
        JobRequest::Load { paths } => {
            let mut out = Vec::new();
            for p in paths {
                if progress.is_cancelled() {
                    break;
                }
                progress.set_message(format!("opening {}", p.display()));
                out.extend(load_path(&p, progress));
            }
            JobOutput::Loaded(out)
        }
    }
}

/// Runs jobs on threads and collects their outputs.
pub struct Worker {
    tx: Sender<(u64, JobOutput)>,
    rx: Receiver<(u64, JobOutput)>,
}

impl Default for Worker {
    fn default() -> Self {
        let (tx, rx) = channel();
        Self { tx, rx }
    }
}

impl Worker {
    /// Starts a job on a new thread. A panic inside it becomes
    /// [`JobOutput::Failed`], never a crash of the interface.
    pub fn spawn(&self, id: u64, req: JobRequest, progress: Arc<Progress>) {
        let tx = self.tx.clone();
        let spawned = std::thread::Builder::new()
            .name(format!("pinsight-job-{id}"))
            .spawn(move || {
                let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    execute(req, &progress)
                }))
                .unwrap_or_else(|payload| {
                    let msg = payload
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_else(|| "unknown panic".into());
                    JobOutput::Failed(format!("internal error in background work: {msg}"))
                });
                let _ = tx.send((id, out));
            });
        if let Err(e) = spawned {
            let _ = self
                .tx
                .send((id, JobOutput::Failed(format!("cannot start a thread: {e}"))));
        }
    }

    /// Outputs that arrived since the last call.
    pub fn poll(&self) -> Vec<(u64, JobOutput)> {
        self.rx.try_iter().collect()
    }
}
