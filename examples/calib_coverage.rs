//! The calibration's coverage sweep (see `pinsight::overlay::calibrate::coverage`):
//! synthetic logs with every factor randomised, each calibrated, the truth
//! compared with value ± U95; a table per condition on stdout and one JSON
//! line per case in `--jsonl FILE`.
//!
//! ```sh
//! # the full sweep of docs/rig-logs.md ("Calibration: bias and coverage")
//! cargo run --release --example calib_coverage -- --cases 120 --jsonl /tmp/coverage.jsonl
//! # a fixed condition (bias at one clearance): --clearance 0.5 --rpm 1200 --cycles 30
//! # chosen seeds, another ensemble tolerance: --seeds 30,50 --rtol 1e-6
//! # the same logs through another laser lag: --seeds 30,50 --laser-lag-us 0
//! ```

use pinsight::overlay::calibrate::CalibrateOptions;
use pinsight::overlay::calibrate::coverage::{CaseResult, CoverageCase, coverage_row, run_case};
use rayon::prelude::*;
use std::io::Write as _;

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse().ok())
}

fn row(label: &str, rs: &[&CaseResult]) -> String {
    let r = coverage_row(rs);
    format!(
        "| {label} | {} | {:.1} % | {:+.4} ± {:.4} | {:+.1} % | {:.4} | {:+.2} | {:.2} |",
        r.n,
        100.0 * r.coverage,
        r.bias_mm,
        r.bias_se_mm,
        100.0 * r.rel_bias,
        r.median_u95_mm,
        r.mean_z,
        r.rms_z
    )
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cases: u64 = arg(&args, "--cases").unwrap_or(40);
    let first: u64 = arg(&args, "--seed").unwrap_or(1);
    let jsonl: Option<String> = arg(&args, "--jsonl");
    let fixed_c: Option<f64> = arg(&args, "--clearance");
    let fixed_rpm: Option<f64> = arg(&args, "--rpm");
    let fixed_cycles: Option<usize> = arg(&args, "--cycles");
    let ideal_sensors = args.iter().any(|a| a == "--ideal-sensors");
    // The laser's lag (µs) instead of the drawn one: the same log (truth,
    // noise) seen through another lag, to check the fit does not move with it.
    let fixed_lag_us: Option<f64> = arg(&args, "--laser-lag-us");
    // Listed seeds instead of a range (`--seeds 30,50`).
    let listed: Option<Vec<u64>> = arg::<String>(&args, "--seeds")
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    let mut opts = CalibrateOptions::default();
    // The ensembles' integrator tolerance (to compare against the default).
    if let Some(r) = arg::<f64>(&args, "--rtol") {
        opts.predict.rtol = r;
    }
    if let Some(m) = arg::<String>(&args, "--method") {
        opts.predict.method = pinsight::solver::Method::parse(&m)
            .ok_or_else(|| anyhow::anyhow!("invalid --method `{m}`"))?;
    }
    if let Some(r) = arg::<usize>(&args, "--coarse-revs") {
        opts.predict.revs = r;
    }
    if let Some(r) = arg::<usize>(&args, "--refine-per-cycle") {
        opts.refine_cycles_factor = r;
    }
    if let Some(r) = arg::<usize>(&args, "--refine-min") {
        opts.refine_revs.0 = r;
    }
    let t = std::time::Instant::now();
    let mut out = jsonl
        .as_ref()
        .map(std::fs::File::create)
        .transpose()?
        .map(std::io::BufWriter::new);
    let mut results: Vec<CaseResult> = Vec::new();
    // Cases in parallel batches; calibrate is itself parallel inside.
    let seeds: Vec<u64> = listed.unwrap_or_else(|| (first..first + cases).collect());
    for chunk in seeds.chunks(2) {
        let rs: Vec<Result<CaseResult, String>> = chunk
            .par_iter()
            .map(|&s| {
                let mut c = CoverageCase::random(s);
                if let Some(v) = fixed_c {
                    c.clearance_mm = v;
                }
                if let Some(v) = fixed_rpm {
                    c.motor_rpm = v;
                }
                if let Some(v) = fixed_cycles {
                    c.cycles = v;
                }
                if let Some(v) = fixed_lag_us {
                    c.laser_lag_s = v * 1e-6;
                }
                if ideal_sensors {
                    c.material = "alloy_steel".into();
                    c.speed_ripple = 0.0;
                    c.laser_lag_s = 0.0;
                    c.laser_noise_mm = 0.0;
                    c.laser_quantum_mm = 0.0;
                    c.encoder_counts = 0;
                }
                run_case(&c, &opts)
            })
            .collect();
        for r in rs {
            match r {
                Ok(r) => {
                    eprintln!(
                        "seed {:4}: c {:.3} → {:.4} ± {:.4} mm ({}) {:4.0} rpm {:3} cycles {:16} gen {:.1} s cal {:.1} s{}",
                        r.case.seed,
                        r.case.clearance_mm,
                        r.clearance_mm,
                        r.u95_mm,
                        if r.covered() { "in" } else { "OUT" },
                        r.case.motor_rpm,
                        r.cycles_used,
                        r.case.material,
                        r.generate_s,
                        r.calibrate_s,
                        if r.at_edge { " (edge)" } else { "" }
                    );
                    if let Some(f) = out.as_mut() {
                        writeln!(f, "{}", serde_json::to_string(&r)?)?;
                        f.flush()?;
                    }
                    results.push(r);
                }
                Err(e) => eprintln!("{e}"),
            }
        }
    }
    let all: Vec<&CaseResult> = results.iter().collect();
    let sel = |f: &dyn Fn(&CaseResult) -> bool| -> Vec<&CaseResult> {
        results.iter().filter(|r| f(r)).collect()
    };
    println!(
        "{} cases in {:.0} s\n",
        results.len(),
        t.elapsed().as_secs_f64()
    );
    println!(
        "| condition | logs | coverage (truth in ± U95) | bias (mm) ± s.e. | bias / truth | median U95 (mm) | mean z | RMS z |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    println!("{}", row("all", &all));
    for (lo, hi) in [(0.05, 0.2), (0.2, 0.4), (0.4, 0.7), (0.7, 1.0)] {
        println!(
            "{}",
            row(
                &format!("clearance {lo}–{hi} mm"),
                &sel(&|r| r.case.clearance_mm >= lo && r.case.clearance_mm < hi)
            )
        );
    }
    for (lo, hi) in [(1000.0, 1333.0), (1333.0, 1667.0), (1667.0, 2000.0)] {
        println!(
            "{}",
            row(
                &format!("motor {lo:.0}–{hi:.0} rpm"),
                &sel(&|r| r.case.motor_rpm >= lo && r.case.motor_rpm < hi)
            )
        );
    }
    for (lo, hi) in [(10, 30), (30, 80), (80, 201)] {
        println!(
            "{}",
            row(
                &format!("cycles {lo}–{}", hi - 1),
                &sel(&|r| r.case.cycles >= lo && r.case.cycles < hi)
            )
        );
    }
    for m in pinsight::model::materials::MATERIALS.iter().map(|m| m.0) {
        println!("{}", row(m, &sel(&|r| r.case.material == m)));
    }
    let a = coverage_row(&all);
    println!(
        "\ncoverage {:.1} % (need ≥ 95 %), |bias| {:.4} mm vs a quarter of the median U95 {:.4} mm",
        100.0 * a.coverage,
        a.bias_mm.abs(),
        0.25 * a.median_u95_mm
    );
    Ok(())
}
