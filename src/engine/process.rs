//! The monitor job: rig logs judged against a process recipe, cycle by
//! cycle, with the SPC of the value checks over all logs and by lot, and
//! (with vision recipes) each connector's story.
//!
//! One function judges one log ([`monitor_log`]); `pinsight monitor`
//! ([`monitor_logs`], logs from paths) and the Line pane / batch `run
//! monitor` ([`monitor_session`], the session's logs and images) both go
//! through it, so the same inputs give the same verdicts whichever face
//! asked.

use super::entries::{ImageEntry, LogEntry};
use super::overlay::OverlayRun;
use super::vision::{YieldInput, run_yield_inputs, yield_item};
use crate::model::params::Params;
use crate::overlay::compare::OverlayOptions;
use crate::process::run::{LogMonitor, MonitorRun};
use crate::process::story::{BandFit, join};
use crate::process::{ProcessRecipe, learn, monitor};
use crate::progress::Progress;
use crate::rig::cycles::{CycleOptions, CycleSet};
use crate::rig::{LoadOptions, RigLog};
use crate::vision::InspectOptions;
use crate::vision::batch::{RecipeBook, collect_items};
use crate::vision::report::GroupBy;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Loads one log and delimits its cycles as the session's loader does
/// (geometry: the `paper` preset, the default crank-angle grid).
fn cycles_of_log(
    path: &Path,
    opts: &LoadOptions,
    progress: &Progress,
) -> Result<(RigLog, CycleSet), String> {
    let log = crate::rig::load(path, opts, progress).map_err(|e| e.to_string())?;
    let cs = super::overlay::cycles_of(
        &log,
        &Params::paper(),
        CycleOptions::default().points_per_rev,
    );
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

/// Judges one log's cycles; with `photos` (its camera images as yield
/// inputs) and vision recipes, joins each connector's photograph with its
/// cycle's verdict and (from `bands`, by cycle index) the model's band.
pub fn monitor_log(
    recipe: &ProcessRecipe,
    log: &RigLog,
    cs: &CycleSet,
    photos: Option<(&[YieldInput], &RecipeBook)>,
    bands: &BTreeMap<u64, BandFit>,
    progress: &Progress,
) -> LogMonitor {
    let mut rep = monitor(recipe, cs);
    if cs.cycles.is_empty() {
        rep.notes.push("no complete cycle in the log".into());
    }
    if photos.is_some_and(|(inputs, _)| inputs.is_empty()) {
        rep.notes
            .push("no connector photographs in the log: no process × vision story".into());
    }
    let story = photos.filter(|(i, _)| !i.is_empty()).map(|(inputs, book)| {
        let run = run_yield_inputs(
            inputs,
            book,
            &InspectOptions::default(),
            GroupBy::Lot,
            &progress.child(),
        );
        join(&log.file, &rep.cycles, &run.results, bands)
    });
    LogMonitor {
        file: log.file.clone(),
        lot: log.meta.lot.clone(),
        motor_rpm: log.meta.motor_rpm,
        report: Ok(rep),
        story,
    }
}

/// A log that could not be monitored.
fn not_monitored(file: String, why: String) -> LogMonitor {
    LogMonitor {
        file,
        lot: None,
        motor_rpm: None,
        report: Err(why),
        story: None,
    }
}

/// The model's band for every cycle of a log: the overlay job with the
/// Overlay pane's defaults (the `paper` preset with the log's `rig`
/// metadata, the clearance level, each speed group at its logged speed).
pub fn model_bands(
    log: &RigLog,
    cs: &CycleSet,
    progress: &Progress,
) -> Result<BTreeMap<u64, BandFit>, String> {
    let rep =
        super::overlay::overlay_job(log, cs, None, &[], &OverlayOptions::default(), progress)?;
    Ok(BandFit::of_overlay(&rep))
}

/// The monitor job over log files (`pinsight monitor`); with `vision`,
/// each log's camera images are inspected and joined with their cycles;
/// with `band`, each connector's story gets the model's band for its cycle
/// (an overlay prediction per log).
pub fn monitor_logs(
    recipe: &ProcessRecipe,
    paths: &[PathBuf],
    opts: &LoadOptions,
    vision: Option<&RecipeBook>,
    band: bool,
    progress: &Progress,
) -> MonitorRun {
    progress.set_total(paths.len() as u64);
    let logs: Vec<LogMonitor> = paths
        .iter()
        .map(|p| {
            progress.set_message(format!("monitor: {}", p.display()));
            let out = match cycles_of_log(p, opts, progress) {
                Ok((log, cs)) => {
                    // The log's photographs (as the session lists them:
                    // one item per camera image; a log without any gives
                    // none, not an error item as `yield` does).
                    let photos = vision.map(|book| {
                        let (items, _) = collect_items(&[p.to_path_buf()]);
                        let inputs: Vec<YieldInput> =
                            items.into_iter().map(YieldInput::Image).collect();
                        (inputs, book)
                    });
                    let (bands, band_note) = if band {
                        match model_bands(&log, &cs, &progress.child()) {
                            Ok(b) => (b, None),
                            Err(e) => (BTreeMap::new(), Some(format!("no model band: {e}"))),
                        }
                    } else {
                        (BTreeMap::new(), None)
                    };
                    let mut m = monitor_log(
                        recipe,
                        &log,
                        &cs,
                        photos.as_ref().map(|(i, b)| (i.as_slice(), *b)),
                        &bands,
                        progress,
                    );
                    if let (Some(n), Ok(r)) = (band_note, &mut m.report) {
                        r.notes.push(n);
                    }
                    m
                }
                Err(e) => not_monitored(p.display().to_string(), e),
            };
            progress.inc(1);
            out
        })
        .collect();
    MonitorRun::from_logs(recipe, logs)
}

/// The process recipe for a part: the one naming it, else the only one.
pub fn recipe_for<'a>(
    recipes: &'a [ProcessRecipe],
    part: Option<&str>,
) -> Option<&'a ProcessRecipe> {
    part.and_then(|p| recipes.iter().find(|r| r.part_number == p))
        .or(match recipes {
            [r] => Some(r),
            _ => None,
        })
}

/// The monitor job over the session's logs (the Line pane, batch `run
/// monitor`): each log judged by the process recipe of its part (or the
/// only one); with vision recipes, the session's images of each log are
/// its connectors' photographs. The run is reported under the first log's
/// recipe; a log whose part has no recipe is listed as not monitored. A
/// log whose overlay has run (`overlays`, by log index) gives its
/// connectors the model's band.
pub fn monitor_session(
    recipes: &[ProcessRecipe],
    logs: &[LogEntry],
    images: &[ImageEntry],
    book: Option<&RecipeBook>,
    overlays: &BTreeMap<usize, OverlayRun>,
    progress: &Progress,
) -> Result<MonitorRun, String> {
    if recipes.is_empty() {
        return Err("no process recipe loaded".into());
    }
    if logs.is_empty() {
        return Err("no rig log loaded".into());
    }
    progress.set_total(logs.len() as u64);
    let mut chosen: Option<&ProcessRecipe> = None;
    let mut out = Vec::new();
    for (i, l) in logs.iter().enumerate() {
        let Some((log, cs)) = &l.rig else {
            out.push(not_monitored(
                l.path.clone(),
                "not a rig log (no cycles)".into(),
            ));
            continue;
        };
        let part = log.meta.part_number.as_deref();
        let Some(r) = recipe_for(recipes, part) else {
            out.push(not_monitored(
                l.path.clone(),
                format!(
                    "no process recipe for part {} (loaded: {})",
                    part.unwrap_or("(none named)"),
                    recipes
                        .iter()
                        .map(|r| r.part_number.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
            continue;
        };
        if chosen.is_some_and(|c| c.part_number != r.part_number) {
            out.push(not_monitored(
                l.path.clone(),
                format!(
                    "part {} — one run reports one part; monitor it on its own",
                    r.part_number
                ),
            ));
            continue;
        }
        chosen = Some(r);
        let inputs: Vec<YieldInput> = images
            .iter()
            .filter(|i| i.meta.log.as_deref() == Some(l.path.as_str()))
            .map(yield_item)
            .collect();
        let bands = overlays
            .get(&i)
            .and_then(|o| o.report.as_ref().ok())
            .map(|r| BandFit::of_overlay(r))
            .unwrap_or_default();
        let mut m = monitor_log(
            r,
            log,
            cs,
            book.map(|b| (inputs.as_slice(), b)),
            &bands,
            progress,
        );
        m.file = l.path.clone();
        if let Some(s) = &mut m.story {
            for c in &mut s.connectors {
                c.log = l.path.clone();
            }
        }
        out.push(m);
        progress.inc(1);
    }
    let recipe = chosen.unwrap_or(&recipes[0]);
    Ok(MonitorRun::from_logs(recipe, out))
}
