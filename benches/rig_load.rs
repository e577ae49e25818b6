//! Rig-log loading benchmark (criterion, `harness = false`).
//!
//! ```sh
//! cargo bench --bench rig_load
//! ```
//!
//! Generates (once, cached in `target/bench-data/`) a ~100 MB zstd log of
//! the 1200 rpm synthetic run (`pinsight::rig::synth`, as `gen_logs big`):
//! ~3.8 million messages, ~4.5 million samples. Measures `rig::load`
//! alone and `load` + `cycles::analyse`; reports MB/s and samples/s. Peak
//! memory is measured in a fresh child process (this binary re-run with
//! `PINSIGHT_BENCH_CHILD=1`), from /proc/self/status (VmHWM = peak resident
//! set, file-backed map pages included; RssAnon = heap at the end).

use criterion::{Criterion, Throughput};
use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::rig::cycles::{CycleOptions, analyse};
use pinsight::rig::synth::{self, IdealTruth, SynthConfig, WriteSettings};
use pinsight::rig::{LoadOptions, load};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[path = "../examples/common/proc_stats.rs"]
mod proc_stats;
use proc_stats::{cpu_s, status_kb};

/// Revolutions giving ~100 MB of zstd (4 MiB chunks) with the default sensors.
const REVOLUTIONS: f64 = 3018.0;

fn log_path() -> PathBuf {
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("bench-data");
    let _ = std::fs::create_dir_all(&dir);
    dir.join(format!("rig-1200rpm-{REVOLUTIONS}rev-zstd-v1.mcap"))
}

fn ensure_log() -> PathBuf {
    let p = log_path();
    if !p.exists() {
        let cfg = SynthConfig {
            revolutions: REVOLUTIONS,
            ..SynthConfig::default()
        };
        let settings = WriteSettings {
            chunk_size: 4 << 20,
            ..WriteSettings::default()
        };
        let tmp = p.with_extension("partial");
        let f = std::fs::File::create(&tmp).expect("create bench log");
        let t = Instant::now();
        synth::write_streaming(
            &cfg,
            &IdealTruth::from_params(&Params::paper()),
            std::io::BufWriter::new(f),
            &settings,
        )
        .expect("write bench log");
        std::fs::rename(&tmp, &p).expect("rename bench log");
        eprintln!(
            "generated {} in {:.1} s",
            p.display(),
            t.elapsed().as_secs_f64()
        );
    }
    p
}

/// One load + cycles in this process; prints the figures as one JSON line.
fn child(path: &std::path::Path) {
    let c0 = cpu_s();
    let t = Instant::now();
    let log = load(path, &LoadOptions::default(), &Progress::hidden()).expect("load");
    let t_load = t.elapsed().as_secs_f64();
    let cpu_load = cpu_s() - c0;
    let hwm_load = status_kb("VmHWM");
    let cs = analyse(&log, &CycleOptions::default());
    let t_all = t.elapsed().as_secs_f64();
    println!(
        "{{\"load_s\": {t_load}, \"load_cpu_s\": {cpu_load}, \"load_cycles_s\": {t_all}, \"samples\": {}, \"cycles\": {}, \"vmhwm_after_load_kb\": {hwm_load}, \"vmhwm_kb\": {}, \"rss_anon_kb\": {}}}",
        log.signals.total_samples(),
        cs.cycles.len(),
        status_kb("VmHWM"),
        status_kb("RssAnon")
    );
}

fn main() {
    let path = ensure_log();
    if std::env::var_os("PINSIGHT_BENCH_CHILD").is_some() {
        child(&path);
        return;
    }
    let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    let probe = load(&path, &LoadOptions::default(), &Progress::hidden()).expect("load");
    let samples = probe.signals.total_samples();
    let messages = probe.report.counts.messages;
    drop(probe);
    eprintln!(
        "log: {} ({:.1} MB, {messages} messages, {samples} samples), {} threads",
        path.display(),
        size as f64 / 1e6,
        rayon::current_num_threads()
    );
    // Peak memory and single-run timings, each in a fresh process.
    let exe = std::env::current_exe().expect("current exe");
    let mut runs = Vec::new();
    for _ in 0..5 {
        let out = std::process::Command::new(&exe)
            .env("PINSIGHT_BENCH_CHILD", "1")
            .output()
            .expect("run child");
        let line = String::from_utf8_lossy(&out.stdout).trim().to_string();
        if let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) {
            runs.push(v);
        }
    }
    let median = |k: &str| {
        let mut v: Vec<f64> = runs.iter().filter_map(|r| r[k].as_f64()).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let load_s = median("load_s");
    let all_s = median("load_cycles_s");
    eprintln!(
        "fresh process, median of {}: load {:.3} s ({:.1} MB/s, {:.2} M samples/s; CPU {:.3} s), load + cycles {:.3} s; peak RSS (VmHWM) {:.0} MB (after load {:.0} MB), heap at end (RssAnon) {:.0} MB",
        runs.len(),
        load_s,
        size as f64 / 1e6 / load_s,
        samples as f64 / 1e6 / load_s,
        median("load_cpu_s"),
        all_s,
        median("vmhwm_kb") / 1024.0,
        median("vmhwm_after_load_kb") / 1024.0,
        median("rss_anon_kb") / 1024.0
    );

    let mut c = Criterion::default()
        .sample_size(10)
        .without_plots()
        .measurement_time(Duration::from_secs(20))
        .configure_from_args();
    {
        let mut g = c.benchmark_group("rig_100MB_zstd");
        g.throughput(Throughput::Bytes(size));
        g.bench_function("load", |b| {
            b.iter(|| load(&path, &LoadOptions::default(), &Progress::hidden()).expect("load"))
        });
        g.bench_function("load_and_cycles", |b| {
            b.iter(|| {
                let log = load(&path, &LoadOptions::default(), &Progress::hidden()).expect("load");
                analyse(&log, &CycleOptions::default())
            })
        });
        g.finish();
    }
    c.final_summary();
}
