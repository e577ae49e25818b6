//! Writes a synthetic wear series (see `pinsight::rig::synth::wear_series`):
//! `cargo run --release --example wear_series -- DIR [RIG] [LOGS] [RATE_MM_PER_CYCLE] [C0_MM] [SEED]`
//! e.g. a wearing head and one that does not:
//! `… -- series head-A 10 2.5e-7 0.15 1` and `… -- series head-B 6 0 0.2 2`.
//!
//! The forecast's coverage over seeded series (issue 15: the interval covers
//! the true crossing in ≥ 90 % of seeded series; docs/trend.md):
//! `cargo run --release --example wear_series -- --coverage FIRST_SEED SERIES [LOGS] [LEVEL]`
//! writes each series (c = 0.15 mm + 2.5e-7 mm/cycle · n, 12 cycles per
//! log, 200 000 head cycles apart) into a temporary folder, runs the trend
//! with the limit 0.8 mm (true crossing 2 600 000 head cycles) and prints
//! one line per series and the coverage of the rate's 95 % interval and of
//! the forecast's interval at LEVEL (default 0.8) and at 0.95.

use pinsight::engine::trend::{TrendCache, TrendOptions, run_trend};
use pinsight::progress::Progress;
use pinsight::rig::synth::wear_series::WearSeries;

/// The forecast coverage sweep (see the module comment).
fn coverage(a: &[String]) {
    let num = |i: usize, d: f64| a.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(d);
    let first = num(1, 1.0) as u64;
    let series = num(2, 40.0) as u64;
    let logs = num(3, 10.0) as usize;
    let level = num(4, 0.8);
    let limit = 0.8;
    let t0 = std::time::Instant::now();
    let (mut rate_in, mut fc_in, mut fc95_in, mut done) = (0, 0, 0, 0);
    println!(
        "| seed | fitted rate (mm/cycle) | 95 % interval | rate covered | crossing forecast | {:.0} % interval | covered | 95 % interval | covered |",
        100.0 * level
    );
    println!("|---:|---:|---|:-:|---:|---|:-:|---|:-:|");
    for seed in first..first + series {
        let s = WearSeries {
            logs,
            seed,
            ..WearSeries::default()
        };
        let truth = (limit - s.c0_mm) / s.rate_mm_per_cycle;
        let dir = tempfile::tempdir().expect("a temporary folder");
        let written = match s.write(dir.path()) {
            Ok(w) => w,
            Err(e) => {
                eprintln!("seed {seed}: {e}");
                continue;
            }
        };
        let paths: Vec<_> = written.iter().map(|l| l.path.clone()).collect();
        let run = |lvl: f64, cache: &mut TrendCache| {
            let o = TrendOptions {
                limit_mm: Some(limit),
                level: lvl,
                ..TrendOptions::default()
            };
            run_trend(&paths, &o, cache, &Progress::hidden())
        };
        let mut cache = TrendCache::default();
        let r = run(level, &mut cache);
        // The same calibrations (cached) at 95 %.
        let r95 = run(0.95, &mut cache);
        let (Some(h), Some(h95)) = (r.heads.first(), r95.heads.first()) else {
            eprintln!("seed {seed}: no head ({:?})", r.errors);
            continue;
        };
        let (Ok(f), Ok(fc), Ok(fc95)) = (&h.fit, &h.forecast, &h95.forecast) else {
            eprintln!(
                "seed {seed}: no fit or forecast ({:?}, {:?})",
                h.fit.as_ref().err(),
                h.forecast.as_ref().err()
            );
            continue;
        };
        let covers = |lo: f64, hi: Option<f64>| lo <= truth && hi.is_none_or(|h| truth <= h);
        let rate_ok = f.slope_lo95 <= s.rate_mm_per_cycle && s.rate_mm_per_cycle <= f.slope_hi95;
        let fc_ok = covers(fc.at_lo, fc.at_hi);
        let fc95_ok = covers(fc95.at_lo, fc95.at_hi);
        done += 1;
        rate_in += usize::from(rate_ok);
        fc_in += usize::from(fc_ok);
        fc95_in += usize::from(fc95_ok);
        let hi = |h: Option<f64>| h.map_or("∞".to_string(), |x| format!("{x:.0}"));
        let yn = |b: bool| if b { "yes" } else { "**no**" };
        println!(
            "| {seed} | {:.4e} | [{:.4e}, {:.4e}] | {} | {:.0} | [{:.0}, {}] | {} | [{:.0}, {}] | {} |",
            f.slope,
            f.slope_lo95,
            f.slope_hi95,
            yn(rate_ok),
            fc.at,
            fc.at_lo,
            hi(fc.at_hi),
            yn(fc_ok),
            fc95.at_lo,
            hi(fc95.at_hi),
            yn(fc95_ok)
        );
    }
    let pct = |k: usize| 100.0 * k as f64 / done.max(1) as f64;
    println!(
        "\n{done} series of {logs} logs in {:.0} s (true crossing {:.0} head cycles): rate in its 95 % interval {rate_in}/{done} ({:.0} %), forecast covered at {:.0} % {fc_in}/{done} ({:.0} %), at 95 % {fc95_in}/{done} ({:.0} %)",
        t0.elapsed().as_secs_f64(),
        (limit - WearSeries::default().c0_mm) / WearSeries::default().rate_mm_per_cycle,
        pct(rate_in),
        100.0 * level,
        pct(fc_in),
        pct(fc95_in)
    );
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.first().is_some_and(|s| s == "--coverage") {
        coverage(&a);
        return;
    }
    let Some(dir) = a.first() else {
        eprintln!("usage: wear_series DIR [RIG] [LOGS] [RATE_MM_PER_CYCLE] [C0_MM] [SEED]");
        std::process::exit(2);
    };
    let num = |i: usize, d: f64| a.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(d);
    let d = WearSeries::default();
    let s = WearSeries {
        rig_id: a.get(1).cloned().unwrap_or(d.rig_id.clone()),
        logs: num(2, d.logs as f64) as usize,
        rate_mm_per_cycle: num(3, d.rate_mm_per_cycle),
        c0_mm: num(4, d.c0_mm),
        seed: num(5, d.seed as f64) as u64,
        ..d
    };
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("{dir}: {e}");
        std::process::exit(1);
    }
    match s.write(std::path::Path::new(dir)) {
        Ok(logs) => {
            for l in logs {
                println!(
                    "{}  head_cycles {:>9.0}  true clearance {:.4} mm",
                    l.path.display(),
                    l.head_cycles,
                    l.clearance_mm
                );
            }
        }
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
