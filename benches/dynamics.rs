//! Speed targets of the dynamics engine (issue 2), as criterion benchmarks:
//! - the paper preset's deterministic window at rtol 1e-10 (target ≤ 1.5 ms);
//! - the default protocol (2 + 3 revolutions) at rtol 1e-8 (target ≥ 20× real
//!   time: the paper preset simulates 0.25 s, so ≤ 12.5 ms);
//! - the paper's whole study (4 × 5 × 5 cases, 5 revolutions, rtol 1e-8) on
//!   all cores (target ≤ 2 s on 2 cores).
//!
//! Run: `cargo bench --bench dynamics`. One core for the first two: rayon is
//! not involved in a single simulation.

use criterion::{Criterion, criterion_group, criterion_main};
use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::sim::sweep::{SweepGrid, run_sweep};
use pinsight::sim::{SimOptions, simulate};
use pinsight::solver::Method;
use std::hint::black_box;
use std::time::Duration;

fn window(c: &mut Criterion) {
    let p = Params::paper();
    let mut g = c.benchmark_group("paper_window_rtol1e-10");
    for m in [Method::Dop853, Method::Dopri5, Method::Radau5] {
        let o = SimOptions {
            method: m,
            ..SimOptions::deterministic_window(1e-10)
        };
        g.bench_function(m.name(), |b| {
            b.iter(|| {
                black_box(
                    simulate(&p, &o, &Progress::hidden())
                        .unwrap()
                        .summary
                        .n_impacts,
                )
            })
        });
    }
    let o = SimOptions {
        method: Method::Rk4,
        step: Some(p.period() / 20_000.0),
        ..SimOptions::deterministic_window(1e-10)
    };
    g.bench_function("rk4_T_over_20000", |b| {
        b.iter(|| {
            black_box(
                simulate(&p, &o, &Progress::hidden())
                    .unwrap()
                    .summary
                    .n_impacts,
            )
        })
    });
    g.finish();
}

fn protocol(c: &mut Criterion) {
    let p = Params::paper();
    let mut g = c.benchmark_group("paper_protocol_2+3_rtol1e-8");
    g.measurement_time(Duration::from_secs(10));
    // Realisations differ (chaos): cycle through 8 start offsets so the
    // median is over the distribution, not one trajectory.
    let mut k = 0u32;
    g.bench_function("dop853", |b| {
        b.iter(|| {
            k = (k + 1) % 8;
            let o = SimOptions {
                rtol: 1e-8,
                perturb_x4: f64::from(k) * 1e-9,
                ..SimOptions::default()
            };
            black_box(
                simulate(&p, &o, &Progress::hidden())
                    .unwrap()
                    .summary
                    .n_impacts,
            )
        })
    });
    g.finish();
}

fn study(c: &mut Criterion) {
    let p = Params::paper();
    let grid = SweepGrid::default();
    let o = SimOptions {
        rtol: 1e-8,
        ..SimOptions::default()
    };
    let mut g = c.benchmark_group("paper_study_100_cases");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.bench_function("all_cores", |b| {
        b.iter(|| black_box(run_sweep(&p, &grid, &o, &Progress::hidden()).failed))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: criterion's plotters backend needs system fonts (pitfalls.md).
    config = Criterion::default().without_plots();
    targets = window, protocol, study
}
criterion_main!(benches);
