//! The `pinsight trend` benchmark of issue 15 (BENCHMARKS.md, "Wear trend"):
//! N logs of C cycles of one wearing head (the synthetic wear series),
//! `run_trend` from cold (empty cache), then again with one new log added
//! (the other N − 1 from the cache), then with nothing new (the run's cost
//! besides calibrating: hashing every log, the fits).
//!
//! ```sh
//! cargo run --release --example trend_bench -- [N=100] [CYCLES=30] [DIR]
//! ```
//! Prints the wall time of each run and the calibrations made; the logs are
//! written into DIR (a temporary folder when not given) and kept there.

use pinsight::engine::trend::{TrendCache, TrendOptions, run_trend};
use pinsight::progress::Progress;
use pinsight::rig::synth::wear_series::WearSeries;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = a.first().and_then(|s| s.parse().ok()).unwrap_or(100);
    let cycles: usize = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(30);
    let tmp;
    let dir = match a.get(2) {
        Some(d) => std::path::PathBuf::from(d),
        None => {
            tmp = tempfile::tempdir().expect("a temporary folder");
            tmp.path().to_path_buf()
        }
    };
    std::fs::create_dir_all(&dir).expect("the log folder");
    let t = Instant::now();
    let series = WearSeries {
        logs: n,
        cycles_per_log: cycles,
        cycles_between: 20_000.0,
        days_between: 1.0,
        rate_mm_per_cycle: 2.5e-7,
        ..WearSeries::default()
    };
    let logs = series.write(&dir).expect("the series");
    eprintln!(
        "{n} logs of {cycles} cycles written in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let opts = TrendOptions {
        limit_mm: Some(0.8),
        ..TrendOptions::default()
    };
    let all: Vec<_> = logs.iter().map(|l| l.path.clone()).collect();
    let mut cache = TrendCache::default();
    let t = Instant::now();
    let r = run_trend(&all, &opts, &mut cache, &Progress::hidden());
    println!(
        "cold: {n} logs, {} calibrated, {:.1} s wall",
        r.calibrated,
        t.elapsed().as_secs_f64()
    );
    // The daily run: the cache holds all but the newest log (the cold run's
    // calibrations of the other N − 1: the same bytes give the same entry).
    let newest = r
        .heads
        .iter()
        .flat_map(|h| h.points.iter())
        .find(|p| p.file == all[n - 1].display().to_string())
        .map(|p| p.sha256.clone());
    let mut cache2 = cache.clone();
    if let Some(h) = &newest {
        cache2.entries.remove(h);
    }
    let t = Instant::now();
    let r = run_trend(&all, &opts, &mut cache2, &Progress::hidden());
    println!(
        "one new log: {} calibrated, {} cached, {:.2} s wall",
        r.calibrated,
        r.cached,
        t.elapsed().as_secs_f64()
    );
    // Nothing new: what the run costs besides calibrating (hashing every
    // log, the fits).
    let t = Instant::now();
    let r = run_trend(&all, &opts, &mut cache2, &Progress::hidden());
    println!(
        "no new log: {} calibrated, {} cached, {:.2} s wall",
        r.calibrated,
        r.cached,
        t.elapsed().as_secs_f64()
    );
}
