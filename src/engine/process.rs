//! The monitor job: rig logs judged against a process recipe, cycle by
//! cycle, with the SPC of the value checks over all logs and by lot.

use crate::model::params::Params;
use crate::process::run::{LogMonitor, MonitorRun};
use crate::process::story::{StoryReport, join};
use crate::process::{ProcessRecipe, learn, monitor};
use crate::progress::Progress;
use crate::rig::LoadOptions;
use crate::vision::InspectOptions;
use crate::vision::batch::{RecipeBook, collect_items, run_batch};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Loads one log and delimits its cycles (geometry: the `paper` preset).
fn cycles_of_log(
    path: &Path,
    opts: &LoadOptions,
    progress: &Progress,
) -> Result<(crate::rig::RigLog, crate::rig::cycles::CycleSet), String> {
    let log = crate::rig::load(path, opts, progress).map_err(|e| e.to_string())?;
    let cs = super::overlay::cycles_of(&log, &Params::paper(), 720);
    Ok((log, cs))
}

/// Learns the recipe's envelopes from the first `n` good cycles of the
/// first log that has them.
pub fn learn_from_logs(
    recipe: &ProcessRecipe,
    paths: &[PathBuf],
    opts: &LoadOptions,
    n: usize,
    progress: &Progress,
) -> Result<(ProcessRecipe, String), String> {
    let mut why = Vec::new();
    for p in paths {
        match cycles_of_log(p, opts, progress).and_then(|(_, cs)| learn(recipe, &cs, n)) {
            Ok(r) => return Ok(r),
            Err(e) => why.push(e),
        }
    }
    Err(format!("nothing to learn from: {}", why.join("; ")))
}

/// The stories of a log's connectors: its photographs inspected with the
/// vision recipes and joined with the cycle verdicts.
fn stories_of(
    path: &Path,
    cycles: &[crate::process::CycleVerdict],
    book: &RecipeBook,
    progress: &Progress,
) -> StoryReport {
    let (items, mut unreadable) = collect_items(&[path.to_path_buf()]);
    let opts = InspectOptions::default();
    let mut results = run_batch(&items, book, &opts, &progress.child());
    results.append(&mut unreadable);
    join(
        &path.display().to_string(),
        cycles,
        &results,
        &BTreeMap::new(),
    )
}

/// The monitor job over several logs; with `vision`, each connector's
/// photograph is inspected and joined with its cycle's verdict.
pub fn monitor_logs(
    recipe: &ProcessRecipe,
    paths: &[PathBuf],
    opts: &LoadOptions,
    vision: Option<&RecipeBook>,
    progress: &Progress,
) -> MonitorRun {
    progress.set_total(paths.len() as u64);
    let logs: Vec<LogMonitor> = paths
        .iter()
        .map(|p| {
            progress.set_message(format!("monitor: {}", p.display()));
            let out = match cycles_of_log(p, opts, progress) {
                Ok((log, cs)) => {
                    let mut rep = monitor(recipe, &cs);
                    if cs.cycles.is_empty() {
                        rep.notes.push("no complete cycle in the log".into());
                    }
                    let story = vision.map(|book| stories_of(p, &rep.cycles, book, progress));
                    LogMonitor {
                        story,
                        file: log.file.clone(),
                        lot: log.meta.lot.clone(),
                        motor_rpm: log.meta.motor_rpm,
                        report: Ok(rep),
                    }
                }
                Err(e) => LogMonitor {
                    file: p.display().to_string(),
                    lot: None,
                    motor_rpm: None,
                    report: Err(e),
                    story: None,
                },
            };
            progress.inc(1);
            out
        })
        .collect();
    MonitorRun::from_logs(recipe, logs)
}
