//! Unit tests of the calibration (golden section, jackknife, t95, the
//! windowed spread, the smoothed grid, the force fit).
use super::*;

#[test]
fn golden_and_jackknife() {
    let x = golden(0.0, 4.0, 60, |x| (x - 1.3).powi(2));
    assert!((x - 1.3).abs() < 1e-9);
    // Jackknife of the mean of n blocks = the standard error of the mean.
    let v = [1.0, 2.0, 3.0, 4.0];
    let means: Vec<f64> = (0..4)
        .map(|i| {
            v.iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|x| x.1)
                .sum::<f64>()
                / 3.0
        })
        .collect();
    let se = (v.iter().map(|x| (x - 2.5f64).powi(2)).sum::<f64>() / 3.0 / 4.0).sqrt();
    assert!((jackknife(&means) - se).abs() < 1e-12);
}

#[test]
fn t95_matches_the_table_of_student_t() {
    // Two-sided 95 % quantiles (any statistics table).
    for (nu, t) in [(1.0, 12.706), (5.0, 2.571), (15.0, 2.131), (1e9, 1.960)] {
        assert!((t95(nu) - t).abs() < 1e-3, "ν {nu}: {}", t95(nu));
    }
    // Between rows: between the neighbours.
    let t = t95(9.0);
    assert!(t < 2.306 && t > 2.228, "{t}");
}

#[test]
fn smoothing_the_fine_nodes_keeps_a_quadratic_and_averages_noise() {
    // Curves exactly quadratic in c at 5 fine nodes (spread 0.3c + 0.2c²
    // + 0.01j, mean 1 + c·j), variance 1e-6 each; coarse nodes at 0.1
    // and 1.0 left as they are.
    let n = 4;
    let node = |c: f64| Curves {
        mean: (0..n).map(|j| 1.0 + c * j as f64).collect(),
        spread: (0..n)
            .map(|j| 0.3 * c + 0.2 * c * c + 0.01 * j as f64)
            .collect(),
        dmean: vec![0.0; n],
        var_mean: vec![1e-6; n],
        var_spread: vec![1e-6; n],
    };
    let fine: Vec<f64> = [0.76, 0.87, 1.0, 1.15, 1.32]
        .iter()
        .map(|f| f * 0.4)
        .collect();
    let mut grid = vec![(0.1, node(0.1))];
    grid.extend(fine.iter().map(|&c| (c, node(c))));
    grid.push((1.0, node(1.0)));
    let g = smooth_grid(&grid, &fine);
    assert_eq!(g.len(), 2 + 41);
    assert_eq!(g[0].0, 0.1);
    assert_eq!(g[g.len() - 1].0, 1.0);
    for (c, cu) in &g[1..g.len() - 1] {
        for j in 0..n {
            let want = 0.3 * c + 0.2 * c * c + 0.01 * j as f64;
            assert!((cu.spread[j] - want).abs() < 1e-12, "{c} {j}");
            assert!((cu.mean[j] - (1.0 + c * j as f64)).abs() < 1e-12);
            // The quadratic through 5 nodes of variance 1e-6 predicts
            // with less variance than one node (3/5 of it on average).
            assert!(
                cu.var_spread[j] > 0.0 && cu.var_spread[j] < 1e-6,
                "{}",
                cu.var_spread[j]
            );
        }
    }
    // A gap in the fine nodes (or fewer than 4): the grid as it was.
    assert_eq!(smooth_grid(&grid, &fine[..3]).len(), grid.len());
}

#[test]
fn windowed_spread_of_independent_rows_is_c4_times_sigma() {
    // Rows = constant + N(0, 1) per point: the mean of the σ of windows
    // of 4 rows is c4(4)·1 = 0.9213 (the measured statistic at k = 4),
    // while the σ over all rows is ≈ 1.
    let mut rng = crate::rng::SplitMix64::<7>::new(3);
    let rows: Vec<Vec<f64>> = (0..4000)
        .map(|_| (0..8).map(|_| rng.normal()).collect())
        .collect();
    let refs: Vec<&[f64]> = rows.iter().map(|r| r.as_slice()).collect();
    let w = curves_windowed(&refs, 8, 4);
    let all = curves_of(&refs, 8);
    for j in 0..8 {
        assert!((w.spread[j] - 0.9213).abs() < 0.02, "{}", w.spread[j]);
        assert!((all.spread[j] - 1.0).abs() < 0.03, "{}", all.spread[j]);
    }
}

#[test]
fn force_fit_recovers_a_table_and_standoff() {
    // A synthetic cycle: stroke ramps through the part, force = F_ins(s − 14) lagged.
    let p = Params::paper();
    let n = 720;
    let dt = 0.05 / n as f64;
    let s: Vec<f64> = (0..n)
        .map(|j| 8.0 - 8.0 * (j as f64 * TAU / n as f64).cos())
        .collect();
    let v = velocity(&s, TAU * 20.0);
    let tau = 150e-6;
    let mut f: Vec<f64> = (0..n)
        .map(|j| {
            let d = s[j] - 13.8;
            if v[j] > 0.0 && d > 0.0 {
                p.f_ins.eval(d * 1e-3)
            } else {
                0.0
            }
        })
        .collect();
    super::super::predict::lag_filter(&mut f, dt, tau);
    let c = ForceCycle::new(s, f, v, dt);
    let knots = [0.0, 0.2, 0.5, 2.0];
    let (so, t, vals) = fit_force(&[&c], &knots, None, &p, (14.0, 200e-6), (1.0, 200e-6));
    assert!((so - 13.8).abs() < 0.01, "{so}");
    assert!((t - tau).abs() < 10e-6, "{t}");
    assert!(
        (vals[2] - 21.0).abs() < 0.5 && (vals[3] - 23.0).abs() < 0.5,
        "{vals:?}"
    );
}

/// The force objective skips the approach to the part (where every
/// regressor is exactly zero): its sum of squares and fitted-sample count
/// must be those of the plain loop over every sample, to the bit, on
/// cycles with force noise above the fitted threshold before the part,
/// missing samples, the pin bar at rest or moving up near TDC, and with
/// and without a withdrawal load.
#[test]
fn the_force_objective_skipping_the_approach_equals_the_plain_loop() {
    use crate::model::table::Table;
    let p = Params::paper();
    let n = 720;
    let knots = [0.0, 0.2, 0.5, 2.0];
    let vals = [0.0, 8.0, 21.0, 23.0];
    let mut rng = crate::rng::SplitMix64::<0>::new(7);
    // The plain loop (the objective as it was before the skip), for fixed
    // table values.
    let plain = |c: &ForceCycle, f_wd: &Table, so: f64, tau: f64| -> (f64, usize) {
        // Hat basis on the knots (the last value held beyond the last knot).
        let hat = |d: f64| -> [f64; 4] {
            let mut b = [0.0; 4];
            if d >= knots[3] {
                b[3] = 1.0;
            } else if d > 0.0 {
                let i = knots.iter().position(|&x| x > d).unwrap();
                let w = (d - knots[i - 1]) / (knots[i] - knots[i - 1]);
                b[i - 1] = 1.0 - w;
                b[i] = w;
            }
            b
        };
        let cd = |v: f64| crate::model::contact::smoothing(v, p.v0, p.v1);
        let (ea, b0, b1) = crate::overlay::predict::ramp_lag_coefficients(c.dt, tau);
        let excl = (BDC_EXCLUDE_DEG / 360.0 * n as f64).round() as usize;
        let stop = (0..n / 2)
            .find(|&j| {
                c.s[j].is_finite()
                    && c.s[j] - so > -0.5
                    && c.v[j].is_finite()
                    && c.v[j] < FIT_MIN_SPEED
            })
            .unwrap_or(n / 2);
        let (mut st, mut prev, mut ss, mut cnt) = ([0.0; 4], [0.0; 4], 0.0, 0);
        let (mut st_wd, mut prev_wd) = (0.0, 0.0);
        for j in 0..stop {
            let (s, v) = (c.s[j], c.v[j]);
            let d = s - so;
            let (mut x, mut wd) = ([0.0; 4], 0.0);
            if d.is_finite() && v.is_finite() {
                if v > 0.0 {
                    x = hat(d).map(|b| b * cd(v));
                } else {
                    wd = -f_wd.eval(d * 1e-3) * cd(-v);
                }
            }
            for i in 0..4 {
                st[i] = ea * st[i] + b0 * prev[i] + b1 * x[i];
            }
            st_wd = ea * st_wd + b0 * prev_wd + b1 * wd;
            prev = x;
            prev_wd = wd;
            let y = c.f[j];
            let seen = st.iter().any(|x| x.abs() > 1e-9);
            if j.abs_diff(n / 2) > excl && y.is_finite() && (seen || y.abs() > 0.5) {
                let pred: f64 = st.iter().zip(&vals).map(|(a, b)| a * b).sum::<f64>() + st_wd;
                ss += (y - pred).powi(2);
                cnt += 1;
            }
        }
        (ss, cnt)
    };
    let wd_tables = [
        Table::zero(),
        Table::from_mm(&[(0.0, 3.0), (1.0, 6.0)]).unwrap(),
    ];
    for trial in 0..40 {
        let so = rng.range(13.0, 15.0);
        let s: Vec<f64> = (0..n)
            .map(|j| {
                let x = 8.0 - 8.0 * (j as f64 * TAU / n as f64).cos() + 0.002 * rng.normal();
                if rng.uniform() < 0.01 { f64::NAN } else { x }
            })
            .collect();
        let v = velocity(&s, TAU * 20.0);
        let f: Vec<f64> = (0..n)
            .map(|j| {
                let d = s[j] - so;
                let clean = if v[j] > 0.0 && d > 0.0 { 20.0 } else { 0.0 };
                clean + rng.range(0.2, 1.0) * rng.normal()
            })
            .collect();
        let c = ForceCycle::new(s, f, v, 0.05 / n as f64);
        let f_wd = &wd_tables[trial % 2];
        for (so_try, tau) in [(so, 150e-6), (so - 0.4, 0.0), (so + 0.3, 40e-6)] {
            let (ss, _, cnt) = force_fit(&[&c], &knots, Some(&vals), f_wd, so_try, tau, p.v0, p.v1);
            let (ss_ref, cnt_ref) = plain(&c, f_wd, so_try, tau);
            assert_eq!(cnt, cnt_ref, "trial {trial}, standoff {so_try}");
            let rel = (ss - ss_ref).abs() / ss_ref.max(1e-300);
            assert!(rel < 1e-12, "trial {trial}: {ss} vs {ss_ref}");
        }
    }
}

#[test]
fn the_scout_keeps_the_fine_range_and_its_two_neighbours() {
    let grid = [0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0];
    let f = [0.76, 0.87, 1.0, 1.15, 1.32];
    // 0.3 mm: the fine grid spans 0.228–0.396, widened 0.182–0.495;
    // inside 0.2, 0.3, 0.4; neighbours 0.15 and 0.5.
    assert_eq!(scout_near(&grid, 0.3, &f), vec![0.15, 0.2, 0.3, 0.4, 0.5]);
    // 0.12 mm: 0.073–0.198 → 0.1, 0.15; neighbours 0.05 (ratio 0.42,
    // the one a span by ratio alone missed) and 0.2.
    assert_eq!(scout_near(&grid, 0.12, &f), vec![0.05, 0.1, 0.15, 0.2]);
    // At the grid's ends: the neighbour on the open side does not exist,
    // and at least three nodes stay.
    assert_eq!(scout_near(&grid, 0.015, &f), vec![0.02, 0.05, 0.1]);
    assert_eq!(scout_near(&grid, 1.4, &f), vec![0.65, 0.8, 1.0]);
    // No estimate: every node.
    assert_eq!(scout_near(&grid, f64::NAN, &f), grid.to_vec());
}
