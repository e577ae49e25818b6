//! The wear-trend job: rig logs (files or folders) → the clearance of every
//! log calibrated (in parallel; a cache keyed by the file's SHA-256 so a
//! daily run calibrates only the new logs) → per head (`rig_id`) the history
//! in order, the linear wear fit, the clearance limit (given, or derived
//! with the model from a tolerance) and the forecast of its crossing
//! ([`crate::wear`]). The one path of `pinsight trend`, the Trend pane,
//! `render trend` and batch `run trend`.

use crate::overlay::calibrate::CalibrateOptions;
use crate::overlay::compare::model_params;
use crate::progress::Progress;
use crate::rig::LoadOptions;
use crate::wear::archard::{ArchardFit, WearWork, work_ladder};
use crate::wear::history::{self, HEAD_CYCLES_KEY, HistoryPoint};
use crate::wear::limit::{ClearanceLimit, DEFAULT_LADDER_MM, derive_limit};
use crate::wear::report::{HeadTrend, ItemError, TrendReport, WearModel};
use crate::wear::{fit_line, forecast};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to build the trend.
#[derive(Debug, Clone)]
pub struct TrendOptions {
    /// One trend per `rig_id` (else all logs are one head).
    pub by_rig: bool,
    pub model: WearModel,
    /// The user's clearance limit (mm): replaces the derivation.
    pub limit_mm: Option<f64>,
    /// The depth tolerance ± (mm) the limit is derived from (a side view's `height_tol_mm`).
    pub tolerance_mm: Option<f64>,
    /// The forecast interval's level.
    pub level: f64,
    pub calibrate: CalibrateOptions,
    pub load: LoadOptions,
    /// Crank-angle points per revolution of the calibration.
    pub points: usize,
    /// The limit's clearance ladder (mm) and revolutions simulated at each.
    pub ladder_mm: Vec<f64>,
    pub limit_revs: usize,
    /// Revolutions simulated at each clearance of the ladder for the Archard
    /// model's sliding work W(c).
    pub work_revs: usize,
}

impl Default for TrendOptions {
    fn default() -> Self {
        TrendOptions {
            by_rig: true,
            model: WearModel::Linear,
            limit_mm: None,
            tolerance_mm: None,
            level: 0.8,
            calibrate: CalibrateOptions::default(),
            load: LoadOptions::default(),
            points: 720,
            ladder_mm: DEFAULT_LADDER_MM.to_vec(),
            limit_revs: 60,
            work_revs: 40,
        }
    }
}

/// Calibrations already made, by the SHA-256 of the log's bytes.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct TrendCache {
    pub version: u32,
    pub entries: BTreeMap<String, HistoryPoint>,
}

/// Bumped when the calibration's settings change its results: a cache of
/// the older settings is then set aside, so one trend never mixes
/// calibrations of two settings (2: ensembles at rtol 1e-4, shorter force
/// fit searches).
const CACHE_VERSION: u32 = 2;

impl TrendCache {
    /// Reads a cache file; a missing file is an empty cache, an unreadable
    /// or foreign one an error naming the file.
    pub fn load(path: &Path) -> Result<Self, String> {
        if !path.exists() {
            return Ok(TrendCache {
                version: CACHE_VERSION,
                entries: BTreeMap::new(),
            });
        }
        let text = crate::input::read_text(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let c: TrendCache = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a trend cache ({e})", path.display()))?;
        if c.version != CACHE_VERSION {
            return Err(format!(
                "{}: trend cache version {} (this pinsight writes {CACHE_VERSION})",
                path.display(),
                c.version
            ));
        }
        Ok(c)
    }

    pub fn to_json(&self) -> Vec<u8> {
        serde_json::to_vec_pretty(&TrendCache {
            version: CACHE_VERSION,
            entries: self.entries.clone(),
        })
        .unwrap_or_default()
    }
}

/// The logs named: files as given, folders' `*.mcap` files (sorted, not
/// recursive). A path that does not exist is an error item.
pub fn collect_logs(inputs: &[PathBuf]) -> (Vec<PathBuf>, Vec<ItemError>) {
    let mut files = Vec::new();
    let mut errors = Vec::new();
    for p in inputs {
        if p.is_dir() {
            match std::fs::read_dir(p) {
                Ok(rd) => {
                    let mut v: Vec<PathBuf> = rd
                        .filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|f| {
                            f.is_file()
                                && f.extension()
                                    .is_some_and(|x| x.eq_ignore_ascii_case("mcap"))
                        })
                        .collect();
                    v.sort();
                    files.extend(v);
                }
                Err(e) => errors.push(ItemError {
                    file: p.display().to_string(),
                    error: format!("cannot list the folder: {e}"),
                }),
            }
        } else if p.exists() {
            files.push(p.clone());
        } else {
            errors.push(ItemError {
                file: p.display().to_string(),
                error: "no such file or folder".into(),
            });
        }
    }
    (files, errors)
}

/// SHA-256 of a file's bytes, in hex.
/// Only a regular file is hashed (a device such as `/dev/zero` never ends).
pub fn file_sha256(path: &Path) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot open: {e}"))?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    let mut f = std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut h = Sha256::new();
    std::io::copy(&mut f, &mut h).map_err(|e| format!("cannot read: {e}"))?;
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

fn utc_text(t_ns: i64) -> String {
    let (y, m, d, hh, mm, ss, _) = crate::fmt::utc_civil(t_ns);
    format!("{y:04}-{m:02}-{d:02}T{hh:02}:{mm:02}:{ss:02}Z")
}

/// Calibrates one log as `pinsight calibrate` does (parameters: the `paper`
/// preset plus the log's `rig` metadata) and makes its history point.
pub fn calibrate_log(
    path: &Path,
    sha256: String,
    opts: &TrendOptions,
) -> Result<HistoryPoint, String> {
    let log = crate::rig::load(path, &opts.load, &Progress::hidden()).map_err(|e| e.to_string())?;
    let (base, _) = model_params(&log, None, &[]).map_err(|e| format!("model parameters: {e}"))?;
    let cs = super::overlay::cycles_of(&log, &base, opts.points);
    if log.signals.displacement.is_none() {
        return Err("no displacement channel: the clearance cannot be calibrated".into());
    }
    let r = super::calibrate::calibrate_job(
        &log,
        &cs,
        None,
        &[],
        &opts.calibrate,
        &Progress::hidden(),
    )?;
    let e = r
        .estimates
        .iter()
        .find(|e| e.name == "clearance")
        .ok_or("the calibration gave no clearance")?;
    let head_cycles = log
        .meta
        .raw
        .get(HEAD_CYCLES_KEY)
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| format!("metadata {HEAD_CYCLES_KEY} = '{v}' is not a cycle count"))
        })
        .transpose()?;
    Ok(HistoryPoint {
        file: path.display().to_string(),
        sha256,
        rig: log.meta.rig_id.clone().unwrap_or_else(|| "unknown".into()),
        start_ns: log.log_start_ns,
        start_utc: log.log_start_ns.map_or(String::new(), utc_text),
        head_cycles,
        cycles: r.cycles,
        motor_rpm: r.motor_rpm,
        clearance_mm: e.value,
        sigma_mm: e.sigma,
        u95_mm: e.u95,
        params: r.params.clone(),
    })
}

/// The trend of `inputs` (files or folders); `cache` is read and updated
/// with the new calibrations (the caller writes it).
pub fn run_trend(
    inputs: &[PathBuf],
    opts: &TrendOptions,
    cache: &mut TrendCache,
    progress: &Progress,
) -> TrendReport {
    let start = Instant::now();
    let (files, mut errors) = collect_logs(inputs);
    progress.set_total(files.len() as u64);
    let hashed: Vec<(PathBuf, Result<String, String>)> = files
        .par_iter()
        .map(|f| (f.clone(), file_sha256(f)))
        .collect();
    let mut points = Vec::new();
    let mut todo = Vec::new();
    let mut seen = BTreeMap::new();
    for (f, h) in hashed {
        match h {
            Err(e) => errors.push(ItemError {
                file: f.display().to_string(),
                error: e,
            }),
            Ok(h) => {
                if let Some(first) = seen.get(&h) {
                    errors.push(ItemError {
                        file: f.display().to_string(),
                        error: format!("the same bytes as {first}: counted once"),
                    });
                    continue;
                }
                seen.insert(h.clone(), f.display().to_string());
                match cache.entries.get(&h) {
                    Some(p) => {
                        let mut p = p.clone();
                        p.file = f.display().to_string();
                        points.push(p);
                        progress.inc(1);
                    }
                    None => todo.push((f, h)),
                }
            }
        }
    }
    let cached = points.len();
    let fresh: Vec<(PathBuf, Result<HistoryPoint, String>)> = todo
        .into_par_iter()
        .map(|(f, h)| {
            if progress.is_cancelled() {
                return (f, Err("cancelled".into()));
            }
            let r = calibrate_log(&f, h, opts);
            progress.inc(1);
            (f, r)
        })
        .collect();
    let mut calibrated = 0;
    for (f, r) in fresh {
        match r {
            Ok(p) => {
                calibrated += 1;
                cache.entries.insert(p.sha256.clone(), p.clone());
                points.push(p);
            }
            Err(e) => errors.push(ItemError {
                file: f.display().to_string(),
                error: e,
            }),
        }
    }
    // Errors in the order of the logs (the named inputs that are not logs
    // after them), whichever step found them: a sharded run's merge lists
    // them in the same order (`plant::trend`).
    let place: BTreeMap<String, usize> = files
        .iter()
        .map(|f| f.display().to_string())
        .enumerate()
        .map(|(i, f)| (f, i))
        .collect();
    errors.sort_by_key(|e| place.get(&e.file).copied().unwrap_or(usize::MAX));
    trend_report(points, errors, files.len(), calibrated, cached, opts, start)
}

/// The report of calibrated history points (any order) and the logs left
/// out (in the order to list them): grouped into heads, each fitted,
/// limited and forecast. `logs`, `calibrated`, `cached` are the counts to
/// report; `start` when the run began (for `wall_ms`). The second half of
/// [`run_trend`], and the merge of a sharded trend (`plant::trend`).
pub fn trend_report(
    points: Vec<HistoryPoint>,
    errors: Vec<ItemError>,
    logs: usize,
    calibrated: usize,
    cached: usize,
    opts: &TrendOptions,
    start: Instant,
) -> TrendReport {
    let mut groups: BTreeMap<String, Vec<HistoryPoint>> = BTreeMap::new();
    for p in points {
        let key = if opts.by_rig {
            p.rig.clone()
        } else {
            "all".into()
        };
        groups.entry(key).or_default().push(p);
    }
    let heads = groups
        .into_iter()
        .map(|(rig, pts)| head_trend(rig, pts, opts))
        .collect();
    TrendReport {
        model: opts.model,
        level: opts.level,
        logs,
        calibrated,
        cached,
        errors,
        heads,
        assumptions: assumptions(opts),
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

fn assumptions(opts: &TrendOptions) -> Vec<String> {
    let mut a = vec![
        "each log's clearance is the calibration's (preset paper + the log's rig metadata), weighted by its U95/2".into(),
        match opts.model {
            WearModel::Linear => format!(
                "wear is linear in the head's cumulative cycles (metadata {HEAD_CYCLES_KEY}; days since the first log when a log lacks it) and continues at the fitted rate"
            ),
            WearModel::Archard => format!(
                "Archard wear: the clearance grows by k·W(c) per cycle (metadata {HEAD_CYCLES_KEY}), W(c) = ∫F_N·|v_slip| dt per cycle simulated at the latest log's speed with its calibrated parameters ({} revolutions per clearance); k stays as fitted",
                opts.work_revs
            ),
        },
        "the forecast interval is Fieller's, from the fit's uncertainty only (Student t, ν = n − 2); it does not include a change of the line's use".into(),
        "days are counted at the cycle rate seen over the history (first to last log)".into(),
    ];
    if opts.limit_mm.is_none() && opts.tolerance_mm.is_some() {
        a.push(
            "the limit is simulated at the latest log's speed with its calibrated parameters"
                .into(),
        );
    }
    a
}

/// One head: order, abscissa, fit, limit, forecast and the verdict.
fn head_trend(rig: String, mut points: Vec<HistoryPoint>, opts: &TrendOptions) -> HeadTrend {
    history::order(&mut points);
    let mut notes = Vec::new();
    let (abscissa, x) = match history::abscissa(&points) {
        Some((a, x)) => (Some(a), x),
        None => {
            notes.push("neither the cycle counter nor the start times are known: no trend".into());
            (None, Vec::new())
        }
    };
    if abscissa == Some(history::Abscissa::Days) {
        notes.push(format!(
            "not every log has the head's cycle counter (metadata {HEAD_CYCLES_KEY}): wear against days"
        ));
    }
    let cycles_per_day = history::cycles_per_day(&points);
    let y: Vec<f64> = points.iter().map(|p| p.clearance_mm).collect();
    let s: Vec<f64> = points.iter().map(|p| p.weight_sigma_mm()).collect();
    // Archard: the sliding work per cycle W(c), simulated at the latest
    // log's speed with its calibrated parameters; the line is fitted to G(c).
    let mut work: Option<WearWork> = None;
    let fit = match (abscissa, opts.model) {
        (None, _) => Err("no abscissa".into()),
        (Some(history::Abscissa::Days), WearModel::Archard) => Err(format!(
            "the Archard model counts wear per cycle: every log needs the head's cycle counter (metadata {HEAD_CYCLES_KEY})"
        )),
        (Some(_), WearModel::Archard) => match points.last() {
            None => Err("no log".into()),
            Some(last) => {
                let w = work_ladder(
                    &last.params,
                    last.motor_rpm,
                    &opts.ladder_mm,
                    opts.work_revs,
                );
                if w.is_usable() {
                    let g: Vec<f64> = y.iter().map(|c| w.g(*c)).collect();
                    let sg: Vec<f64> = y.iter().zip(&s).map(|(c, s)| s / w.work_at(*c)).collect();
                    let f = fit_line(&x, &g, &sg).map_err(|e| e.0);
                    work = Some(w);
                    f
                } else {
                    Err(format!(
                        "the model gave no sliding work at 2 or more clearances ({})",
                        w.notes.join("; ")
                    ))
                }
            }
        },
        (Some(_), WearModel::Linear) => fit_line(&x, &y, &s).map_err(|e| e.0),
    };
    let limit = match (opts.limit_mm, opts.tolerance_mm, points.last()) {
        (Some(l), _, _) => Some(ClearanceLimit::user(l)),
        (None, Some(t), Some(last)) => Some(derive_limit(
            &last.params,
            last.motor_rpm,
            t,
            &opts.ladder_mm,
            opts.limit_revs,
        )),
        _ => {
            notes.push("no limit: give --limit MM or a tolerance (-r RECIPE with a side view, or --tolerance MM)".into());
            None
        }
    };
    let x_last = x.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let per_day = match abscissa {
        Some(history::Abscissa::Days) => Some(1.0),
        _ => cycles_per_day,
    };
    let archard = match (&fit, work) {
        (Ok(f), Some(w)) => {
            let (lo, hi) = y
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                    (a.min(*c), b.max(*c))
                });
            Some(ArchardFit::of(w, f, x_last, lo, hi))
        }
        _ => None,
    };
    let forecast = match (&fit, limit.as_ref().and_then(|l| l.limit_mm)) {
        (Ok(f), Some(l)) => match &archard {
            // The crossing of G(L) by the line in G, reported in mm.
            Some(a) => forecast(f, a.work.g(l), x_last, opts.level, per_day).map(|mut fc| {
                fc.limit_mm = l;
                fc
            }),
            None => forecast(f, l, x_last, opts.level, per_day),
        },
        (Err(e), _) => Err(format!("no fit ({e})")),
        (_, None) => Err("no clearance limit".into()),
    };
    let rate = match (&archard, &fit) {
        (Some(a), _) => format!(
            "wear now {:.3e} mm per cycle (Archard k {:.3e} mm/J)",
            a.rate_now, a.k_mm_per_j
        ),
        (None, Ok(f)) => format!(
            "wearing at {:.3e} mm per {}",
            f.slope,
            abscissa.map_or("", |a| a.unit()).trim_end_matches('s')
        ),
        _ => String::new(),
    };
    let verdict = verdict(&fit, &forecast, abscissa, &rate);
    HeadTrend {
        rig,
        points,
        abscissa,
        x,
        fit,
        archard,
        cycles_per_day,
        limit,
        forecast,
        verdict,
        notes,
    }
}

fn verdict(
    fit: &Result<crate::wear::LineFit, String>,
    fc: &Result<crate::wear::Forecast, String>,
    abscissa: Option<history::Abscissa>,
    rate: &str,
) -> String {
    let unit = abscissa.map_or("", |a| a.unit());
    match (fit, fc) {
        (Err(e), _) => format!("the data cannot support a trend: {e}"),
        (Ok(f), _) if f.slope_lo95 <= 0.0 => {
            format!("no wear the data can show: {rate} (95 % interval of the rate includes 0)")
        }
        (Ok(_), Ok(f)) if f.reached => format!(
            "the limit {:.3} mm is reached: change the connecting rod",
            f.limit_mm
        ),
        (Ok(_), Ok(f)) => match f.days {
            Some(d) => format!(
                "at the current wear rate the limit {:.3} mm is reached in {:.0} {unit} ≈ {d:.1} days",
                f.limit_mm, f.remaining
            ),
            None => format!(
                "at the current wear rate the limit {:.3} mm is reached in {:.0} {unit}",
                f.limit_mm, f.remaining
            ),
        },
        (Ok(_), Err(e)) => format!("{rate}; {e}"),
    }
}

/// The calibrations the session's trend has made in this process, by the
/// log's SHA-256: a re-run of the Trend pane (`r`, a revisit, another batch
/// step) calibrates only logs it has not seen (always with the default
/// options, so one memo serves every call).
static SESSION_CACHE: std::sync::Mutex<TrendCache> = std::sync::Mutex::new(TrendCache {
    version: CACHE_VERSION,
    entries: BTreeMap::new(),
});

/// The trend of the session's logs (the Trend pane, `render trend`, batch
/// `run trend`): the logs' files with the default options, the limit
/// derived from the first side-view recipe's `height_tol_mm` when one is
/// loaded — what `pinsight trend LOGS -r SIDE_RECIPE --json` prints. The
/// calibrations are kept for the process ([`SESSION_CACHE`]).
pub fn trend_session(
    logs: &[super::entries::LogEntry],
    recipes: &[super::entries::RecipeEntry],
    progress: &Progress,
) -> Result<TrendReport, String> {
    if logs.is_empty() {
        return Err("no rig log loaded".into());
    }
    let inputs: Vec<PathBuf> = logs.iter().map(|l| PathBuf::from(&l.path)).collect();
    let opts = TrendOptions {
        tolerance_mm: recipes
            .iter()
            .find_map(|r| r.recipe.tolerance.height_tol_mm),
        ..TrendOptions::default()
    };
    // The memo is taken out while the trend runs (a poisoned lock, after a
    // panic elsewhere, is an empty memo).
    let mut cache = match SESSION_CACHE.lock() {
        Ok(mut c) => std::mem::take(&mut *c),
        Err(_) => TrendCache::default(),
    };
    let r = run_trend(&inputs, &opts, &mut cache, progress);
    if let Ok(mut c) = SESSION_CACHE.lock() {
        // Another call may have filled the memo meanwhile: keep both.
        c.entries.append(&mut cache.entries);
        c.version = CACHE_VERSION;
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    fn point(i: usize, cycles: Option<f64>, c: f64, u95: f64) -> HistoryPoint {
        HistoryPoint {
            file: format!("log-{i}.mcap"),
            sha256: format!("{i:064}"),
            rig: "head-B".into(),
            start_ns: Some(1_790_000_000_000_000_000 + i as i64 * 86_400_000_000_000),
            start_utc: String::new(),
            head_cycles: cycles,
            cycles: 12,
            motor_rpm: 1200.0,
            clearance_mm: c,
            sigma_mm: u95 / 2.0,
            u95_mm: u95,
            params: Params::paper(),
        }
    }

    fn opts() -> TrendOptions {
        TrendOptions {
            limit_mm: Some(0.8),
            ..TrendOptions::default()
        }
    }

    #[test]
    fn a_head_that_does_not_wear_says_so_and_gives_no_forecast() {
        // Clearances scattered about 0.2 mm with no trend (values chosen by hand).
        let cs = [0.21, 0.19, 0.205, 0.195, 0.2];
        let pts = (0..5)
            .map(|i| point(i, Some(i as f64 * 1e5), cs[i], 0.02))
            .collect();
        let h = head_trend("head-B".into(), pts, &opts());
        let f = h.fit.as_ref().unwrap();
        assert!(f.slope_lo95 < 0.0 && f.slope_hi95 > 0.0, "{f:?}");
        assert!(
            h.verdict.starts_with("no wear the data can show"),
            "{}",
            h.verdict
        );
        assert!(h.forecast.is_err());
    }

    #[test]
    fn too_few_logs_or_no_counter_are_said_not_guessed() {
        let two = vec![
            point(0, Some(0.0), 0.2, 0.02),
            point(1, Some(1e5), 0.25, 0.02),
        ];
        let h = head_trend("h".into(), two, &opts());
        assert!(
            h.verdict.contains("at least 3 calibrated logs"),
            "{}",
            h.verdict
        );
        // One log without the cycle counter: the abscissa is days (1 day apart).
        let pts = vec![
            point(0, Some(0.0), 0.2, 0.02),
            point(1, None, 0.25, 0.02),
            point(2, Some(2e5), 0.3, 0.02),
        ];
        let h = head_trend("h".into(), pts, &opts());
        assert_eq!(h.abscissa, Some(history::Abscissa::Days));
        assert!(
            h.x.iter()
                .zip([0.0, 1.0, 2.0])
                .all(|(a, b)| (a - b).abs() < 1e-9),
            "{:?}",
            h.x
        );
        assert!(h.notes.iter().any(|n| n.contains(HEAD_CYCLES_KEY)));
    }

    #[test]
    fn a_cache_that_is_not_one_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cache.json");
        std::fs::write(&p, b"{ not json").unwrap();
        let e = TrendCache::load(&p).unwrap_err();
        assert!(
            e.contains("cache.json") && e.contains("not a trend cache"),
            "{e}"
        );
        // A missing cache is an empty one.
        let c = TrendCache::load(&dir.path().join("none.json")).unwrap();
        assert!(c.entries.is_empty());
    }
}
