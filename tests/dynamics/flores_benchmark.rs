//! The `flores` preset against flores-benchmark.md (an independent
//! reference implementation of model.md in Python/SciPy).

use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::sim::ensemble::run_ensemble;
use pinsight::sim::{SimOptions, simulate};
use pinsight::solver::Method;

struct Window {
    c_mm: f64,
    impacts: u64,
    onsets_ms: [f64; 5],
    approach_mps: [f64; 5],
    peak_a4: f64,
    peak_fn: f64,
    mean_ds_mm: f64,
    rms_dm: f64,
    peak_m12: f64,
}

const WINDOWS: [Window; 3] = [
    Window {
        c_mm: 0.5,
        impacts: 13,
        onsets_ms: [
            0.353150761,
            0.925324435,
            1.052588914,
            1.218513630,
            1.497723688,
        ],
        approach_mps: [2.8392, 1.3896, 0.9162, 0.9056, 0.7857],
        peak_a4: 188_048.608,
        peak_fn: 26326.8142,
        mean_ds_mm: 0.308117282,
        rms_dm: 86.4810619,
        peak_m12: 687.247966,
    },
    Window {
        c_mm: 0.25,
        impacts: 12,
        onsets_ms: [
            0.249882336,
            0.709589384,
            0.816067375,
            1.045719881,
            1.230953139,
        ],
        approach_mps: [2.0037, 1.2894, 0.6742, 0.6846, 0.7513],
        peak_a4: 144_831.754,
        peak_fn: 20276.4471,
        mean_ds_mm: 0.176252345,
        rms_dm: 63.6454794,
        peak_m12: 405.815462,
    },
    Window {
        c_mm: 0.1,
        impacts: 13,
        onsets_ms: [
            0.158104413,
            0.478502545,
            0.593097719,
            0.817003481,
            0.927627307,
        ],
        approach_mps: [1.2657, 0.9783, 0.6160, 0.8608, 0.4224],
        peak_a4: 103_755.560,
        peak_fn: 14525.7917,
        mean_ds_mm: 0.0906243414,
        rms_dm: 30.5224993,
        peak_m12: 228.281397,
    },
];

fn flores(c_mm: f64) -> Params {
    let mut p = Params::flores();
    p.clearance = c_mm * 1e-3;
    p.validate().unwrap();
    p
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Deterministic window (warmup 0, revs 0.5) at the tightest tolerance, as
/// the benchmark's acceptance asks: exact impact count, each of the first
/// five onsets within 1e-5 ms, the five figures within 1e-5 relative.
/// Also: every located onset and loss satisfies |δ| ≤ 1e-5·c.
#[test]
fn deterministic_window_matches_reference() {
    for w in &WINDOWS {
        let p = flores(w.c_mm);
        let mut o = SimOptions::deterministic_window(1e-12);
        o.atol = 1e-16;
        o.method = Method::Dop853;
        let r = simulate(&p, &o, &Progress::hidden()).unwrap();
        let s = &r.summary;
        assert_eq!(s.n_impacts, w.impacts, "c = {} mm: impact count", w.c_mm);
        let onsets: Vec<_> = r.events.iter().filter(|e| e.onset).collect();
        for (k, e) in onsets.iter().take(5).enumerate() {
            let t_ms = e.t_s * 1e3;
            assert!(
                (t_ms - w.onsets_ms[k]).abs() <= 1e-5,
                "c = {} mm onset {}: {t_ms:.9} ms vs {:.9} ms",
                w.c_mm,
                k + 1,
                w.onsets_ms[k]
            );
            // Approach velocities (the reference gives 4 decimals).
            assert!(
                (e.delta_dot_mps - w.approach_mps[k]).abs() <= 6e-5,
                "c = {} mm onset {} approach {} vs {}",
                w.c_mm,
                k + 1,
                e.delta_dot_mps,
                w.approach_mps[k]
            );
        }
        for e in &r.events {
            assert!(
                e.residual_rel <= 1e-5,
                "event at {} s: |δ|/c = {}",
                e.t_s,
                e.residual_rel
            );
        }
        let checks = [
            ("peak |a4|", s.peak_accel_mps2, w.peak_a4),
            ("peak F_N", s.peak_contact_force_n, w.peak_fn),
            ("mean |Δs|", s.disp_dev_mean_mm, w.mean_ds_mm),
            ("RMS ΔM", s.torque_dev_rms_nm.unwrap(), w.rms_dm),
            ("peak |M12|", s.peak_torque_nm.unwrap(), w.peak_m12),
        ];
        for (name, got, want) in checks {
            assert!(
                rel(got, want) <= 1e-5,
                "c = {} mm {name}: {got} vs {want} ({:.1e} relative)",
                w.c_mm,
                rel(got, want)
            );
        }
    }
}

/// The same window with the other methods: counts exact and figures close
/// (a cross-check of the integrators on the real problem).
#[test]
fn deterministic_window_with_other_methods() {
    let w = &WINDOWS[0];
    let p = flores(w.c_mm);
    for (method, rtol, step, tol) in [
        (Method::Dopri5, 1e-12, None, 1e-5),
        (Method::Radau5, 1e-11, None, 1e-4),
        (Method::Rk4, 0.0, Some(5e-9), 1e-5),
    ] {
        let mut o = SimOptions::deterministic_window(if rtol > 0.0 { rtol } else { 1e-10 });
        o.atol = 1e-16;
        o.method = method;
        o.step = step;
        let r = simulate(&p, &o, &Progress::hidden()).unwrap();
        let s = &r.summary;
        assert_eq!(s.n_impacts, w.impacts, "{method:?}");
        assert!(
            rel(s.peak_accel_mps2, w.peak_a4) < tol,
            "{method:?} peak a4 {}",
            s.peak_accel_mps2
        );
        assert!(
            rel(s.disp_dev_mean_mm, w.mean_ds_mm) < tol,
            "{method:?} mean ds {}",
            s.disp_dev_mean_mm
        );
        assert!(
            rel(s.torque_dev_rms_nm.unwrap(), w.rms_dm) < tol,
            "{method:?} rms dM {:?}",
            s.torque_dev_rms_nm
        );
    }
}

struct Band {
    name: &'static str,
    lo: f64,
    hi: f64,
}

/// Statistics over 30 revolutions (warmup 2, rtol 1e-10, 8 realisations
/// offset by k nm): each 8-realisation mean inside the reference band.
#[test]
fn thirty_revolution_statistics_within_bands() {
    let cases: [(f64, [Band; 6]); 3] = [
        (
            0.5,
            [
                Band {
                    name: "impacts_per_rev",
                    lo: 9.41,
                    hi: 14.94,
                },
                Band {
                    name: "peak_accel_mps2",
                    lo: 2.142e5,
                    hi: 2.495e5,
                },
                Band {
                    name: "peak_contact_force_n",
                    lo: 29_880.0,
                    hi: 38_680.0,
                },
                Band {
                    name: "disp_dev_mean_mm",
                    lo: 0.3635,
                    hi: 0.4018,
                },
                Band {
                    name: "torque_dev_rms_nm",
                    lo: 67.05,
                    hi: 77.51,
                },
                Band {
                    name: "peak_torque_nm",
                    lo: 1_317.0,
                    hi: 1_456.0,
                },
            ],
        ),
        (
            0.25,
            [
                Band {
                    name: "impacts_per_rev",
                    lo: 5.33,
                    hi: 9.98,
                },
                Band {
                    name: "peak_accel_mps2",
                    lo: 1.488e5,
                    hi: 1.663e5,
                },
                Band {
                    name: "peak_contact_force_n",
                    lo: 21_040.0,
                    hi: 23_790.0,
                },
                Band {
                    name: "disp_dev_mean_mm",
                    lo: 0.2022,
                    hi: 0.2235,
                },
                Band {
                    name: "torque_dev_rms_nm",
                    lo: 45.20,
                    hi: 53.35,
                },
                Band {
                    name: "peak_torque_nm",
                    lo: 774.2,
                    hi: 953.8,
                },
            ],
        ),
        (
            0.1,
            [
                Band {
                    name: "impacts_per_rev",
                    lo: 0.0,
                    hi: 2.65,
                },
                Band {
                    name: "peak_accel_mps2",
                    lo: 3.264e4,
                    hi: 6.604e4,
                },
                Band {
                    name: "peak_contact_force_n",
                    lo: 4_972.0,
                    hi: 9_670.0,
                },
                Band {
                    name: "disp_dev_mean_mm",
                    lo: 0.09131,
                    hi: 0.1009,
                },
                Band {
                    name: "torque_dev_rms_nm",
                    lo: 17.61,
                    hi: 27.92,
                },
                Band {
                    name: "peak_torque_nm",
                    lo: 262.7,
                    hi: 448.3,
                },
            ],
        ),
    ];
    // flores-benchmark.md: a correct implementation has about a 5 % chance
    // that one of the 18 checks fails; "repeat a failing check with 8 new
    // realisations before calling it a discrepancy". A failing figure is
    // rerun once with offsets 8–15 nm, and must then be inside its band.
    let mut failures = Vec::new();
    let o = SimOptions {
        warmup: 2.0,
        revs: 30.0,
        rtol: 1e-10,
        atol: 1e-16,
        method: Method::Dop853,
        ..SimOptions::default()
    };
    for (c_mm, bands) in &cases {
        let p = flores(*c_mm);
        let e = run_ensemble(&p, &o, 8, 1e-9, false, &Progress::hidden()).unwrap();
        let mut retry: Option<pinsight::sim::ensemble::EnsembleResult> = None;
        for b in bands {
            let m = e.stats(b.name).unwrap().mean;
            eprintln!(
                "c = {c_mm} mm {}: mean {m:.5} band {} – {}",
                b.name, b.lo, b.hi
            );
            if m >= b.lo && m <= b.hi {
                continue;
            }
            let r = retry.get_or_insert_with(|| {
                let o2 = SimOptions {
                    perturb_x4: 8e-9,
                    ..o.clone()
                };
                run_ensemble(&p, &o2, 8, 1e-9, false, &Progress::hidden()).unwrap()
            });
            let m2 = r.stats(b.name).unwrap().mean;
            eprintln!("  repeated with realisations 8–15 nm: mean {m2:.5}");
            if !(m2 >= b.lo && m2 <= b.hi) {
                failures.push(format!(
                    "c = {c_mm} mm {}: means {m} and {m2} (8 new realisations) outside {} – {}",
                    b.name, b.lo, b.hi
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The double-crossing guard (model.md): at 5000 rpm a free-flight step can
/// carry the journal into the wall and out again; without the guard the
/// c = 0.5 mm window shows 11 impacts at rtol 1e-8 or 1e-11 instead of 13
/// (flores-benchmark.md). With it the count is exact at every tolerance.
#[test]
fn double_crossing_guard_keeps_every_impact() {
    let p = flores(0.5);
    for rtol in [1e-6, 1e-8, 1e-10, 1e-11] {
        for atol in [1e-16, 1e-14] {
            let mut o = SimOptions::deterministic_window(rtol);
            o.atol = atol;
            let s = simulate(&p, &o, &Progress::hidden()).unwrap().summary;
            assert_eq!(s.n_impacts, 13, "rtol {rtol} atol {atol}");
        }
    }
}
