//! Tests of the cycle analysis: unwrapping, segmentation at TDC, offsets
//! and per-cycle figures on constructed signals with exact truth.

use super::fit::{fit_phase, speed_stats, to_grid};
use super::*;
use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::rig::signals::Signal;

fn signal(kind: SignalKind, t: Vec<i64>, v: Vec<f64>) -> Signal {
    Signal {
        kind,
        topic: "/t".into(),
        field: "f".into(),
        unit: kind.unit().into(),
        t_ns: t,
        values: v,
    }
}

#[test]
fn unwrap_wrapped_and_unwrapped_angles() {
    // 20 Hz crank sampled at 1 kHz, wrapped to [0, 2π), starting at 1 rad.
    let t: Vec<i64> = (0..500).map(|i| i * 1_000_000).collect();
    let truth: Vec<f64> = t
        .iter()
        .map(|&x| 1.0 + TAU * 20.0 * x as f64 * 1e-9)
        .collect();
    let wrapped: Vec<f64> = truth.iter().map(|a| a.rem_euclid(TAU)).collect();
    let (c, w) = Crank::unwrap(&signal(SignalKind::Angle, t.clone(), wrapped)).unwrap();
    assert!(w);
    for (a, b) in c.theta.iter().zip(&truth) {
        assert!((a - b).abs() < 1e-9);
    }
    let (c2, w2) = Crank::unwrap(&signal(SignalKind::Angle, t.clone(), truth.clone())).unwrap();
    assert!(!w2);
    assert!((c2.omega - TAU * 20.0).abs() < 1e-6);
    // TDC crossings at θ = π + 2πn: first at t = (π − 1)/(40π) s.
    let x = c.crossings(PI);
    let t0 = (PI - 1.0) / (TAU * 20.0);
    assert!(((x[0].0 as f64 * 1e-9) - t0).abs() < 1e-6);
    assert_eq!(x.len(), 10);
    assert_eq!(x[1].1 - x[0].1, 1);
}

#[test]
fn hinted_lookup_matches_binary_search() {
    let t: Vec<i64> = (0..1000).map(|i| i * 1000 + (i % 7) * 13).collect();
    let th: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
    let c = Crank {
        t_ns: t,
        theta: th,
        dt_ns: 1000,
        omega: 10.0,
    };
    let mut h = 0;
    for q in [
        -5i64, 0, 1, 500, 999, 1000, 1500, 70_000, 69_000, 999_000, 999_100, 2_000_000,
    ] {
        assert_eq!(
            c.at_from(q, &mut h),
            {
                let i = c.t_ns.partition_point(|&x| x < q);
                if i < c.t_ns.len() && c.t_ns[i] == q {
                    Some(c.theta[i])
                } else if i == 0 || i >= c.t_ns.len() {
                    None
                } else {
                    let w = (q - c.t_ns[i - 1]) as f64 / (c.t_ns[i] - c.t_ns[i - 1]) as f64;
                    Some(c.theta[i - 1] + w * (c.theta[i] - c.theta[i - 1]))
                }
            },
            "{q}"
        );
    }
}

#[test]
fn grid_interpolation_and_holes() {
    let pts: Vec<(f64, f64)> = (0..=100)
        .map(|i| (i as f64 * TAU / 100.0, i as f64))
        .collect();
    let g = to_grid(&pts, 200, 0.1);
    assert!((g[1] - 0.5).abs() < 1e-9);
    assert!((g[199] - 99.5).abs() < 1e-9);
    let holey: Vec<(f64, f64)> = pts
        .iter()
        .copied()
        .filter(|p| !(1.0..2.0).contains(&p.0))
        .collect();
    let g2 = to_grid(&holey, 200, 0.1);
    assert!(g2[40].is_nan());
    assert!(g2[10].is_finite());
}

#[test]
fn band_statistics_skip_nan() {
    let rows = [vec![1.0, f64::NAN], vec![3.0, 2.0]];
    let b = Band::of(rows.iter().map(|r| r.as_slice()), 2);
    assert_eq!(b.mean, vec![2.0, 2.0]);
    assert_eq!(b.count, vec![2, 1]);
    assert!((b.std[0] - 2f64.sqrt()).abs() < 1e-12);
    assert_eq!((b.min[0], b.max[0]), (1.0, 3.0));
}

#[test]
fn first_harmonic_ripple() {
    let s: Vec<(f64, f64)> = (0..400)
        .map(|i| {
            let phi = i as f64 * TAU / 400.0;
            (phi, 1200.0 * (1.0 + 0.005 * (phi + 0.7).cos()))
        })
        .collect();
    let (m, _, _, _, h) = speed_stats(&s);
    assert!((m - 1200.0).abs() < 1e-9);
    assert!((h - 0.005).abs() < 1e-9);
}

#[test]
fn encoder_lattice_detection() {
    let q = TAU / 4096.0;
    let v: Vec<f64> = (0..3000)
        .map(|i| ((i * 82 + i / 7) % 4096) as f64 * q)
        .collect();
    assert_eq!(detect_encoder_counts(&v), Some(4096));
    // Sampling in step with the crank: the same 300 counts every turn, 13 or 14 apart.
    let s: Vec<f64> = (0..3000)
        .map(|i| (((i % 300) * 4096 / 300) as f64) * q)
        .collect();
    assert_eq!(detect_encoder_counts(&s), Some(4096));
    let w: Vec<f64> = (0..3000)
        .map(|i| (i as f64 * 0.1234567).rem_euclid(TAU))
        .collect();
    assert_eq!(detect_encoder_counts(&w), None);
}

#[test]
fn phase_fit_recovers_a_known_offset() {
    let g = Geometry::of(&Params::paper());
    let th: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
    let d: Vec<f64> = th
        .iter()
        .map(|t| g.stroke_at(t + 0.3) * 1e3 - 10.0)
        .collect();
    let phi = fit_phase(&g, &th, &d, None).unwrap();
    assert!((phi - 0.3).abs() < 1e-6, "{phi}");
}
