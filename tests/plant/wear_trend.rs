//! The wear trend on a synthetic history whose wear is known: a head whose
//! true clearance grows linearly in its cumulative cycles (c = 0.15 mm +
//! 2.5e-7 mm/cycle · n, 7 days and 200 000 cycles between logs, 12 cycles
//! per log), written by `rig::synth::wear_series`, calibrated and fitted by
//! `engine::trend::run_trend` (the one path of `pinsight trend`). The truth
//! is the generator's input, never read back from the logs.

use pinsight::engine::trend::{TrendCache, TrendOptions, run_trend};
use pinsight::model::Params;
use pinsight::panes::{PaneId, PaneState, Session};
use pinsight::progress::Progress;
use pinsight::rig::synth::wear_series::WearSeries;
use pinsight::wear::limit::DEFAULT_LADDER_MM;
use pinsight::wear::{Abscissa, WearModel, work_ladder};

#[test]
fn a_known_wear_rate_is_recovered_and_the_cache_calibrates_only_the_new_log() {
    let dir = tempfile::tempdir().unwrap();
    let series = WearSeries {
        logs: 8,
        seed: 7,
        ..WearSeries::default()
    };
    let logs = series.write(dir.path()).unwrap();
    let bad = dir.path().join("corrupt.mcap");
    std::fs::write(&bad, b"not an mcap file at all").unwrap();
    let missing = dir.path().join("missing.mcap");
    let limit = 0.8;
    let opts = TrendOptions {
        limit_mm: Some(limit),
        level: 0.95,
        ..TrendOptions::default()
    };
    let mut cache = TrendCache::default();

    // Day 1: the first 7 logs, a corrupt one and a missing one.
    let mut inputs: Vec<_> = logs[..7].iter().map(|l| l.path.clone()).collect();
    inputs.push(bad.clone());
    inputs.push(missing.clone());
    let r = run_trend(&inputs, &opts, &mut cache, &Progress::hidden());
    assert_eq!(r.calibrated, 7, "{:?}", r.errors);
    assert_eq!(r.cached, 0);
    assert_eq!(cache.entries.len(), 7);
    // Bad input: each listed with its error naming the file, the rest reported.
    assert_eq!(r.errors.len(), 2, "{:?}", r.errors);
    let bad_err = r
        .errors
        .iter()
        .find(|e| e.file.ends_with("corrupt.mcap"))
        .unwrap();
    assert!(bad_err.error.contains("MCAP"), "{}", bad_err.error);
    let miss_err = r
        .errors
        .iter()
        .find(|e| e.file.ends_with("missing.mcap"))
        .unwrap();
    assert!(
        miss_err.error.contains("no such file"),
        "{}",
        miss_err.error
    );
    assert_eq!(r.heads.len(), 1);
    assert_eq!(r.heads[0].points.len(), 7);

    // Day 2: one new log; the cache holds the other 7.
    let all: Vec<_> = logs
        .iter()
        .map(|l| l.path.clone())
        .chain([bad.clone()])
        .collect();
    let r = run_trend(&all, &opts, &mut cache, &Progress::hidden());
    assert_eq!(r.calibrated, 1, "only the new log is calibrated");
    assert_eq!(r.cached, 7);
    assert_eq!(r.errors.len(), 1);
    let h = &r.heads[0];
    assert_eq!(h.rig, "head-A");
    assert_eq!(h.abscissa, Some(Abscissa::Cycles));
    // Ordered by start time; the abscissa is the metadata's cycle counter.
    let truth_x: Vec<f64> = logs.iter().map(|l| l.head_cycles).collect();
    assert_eq!(h.x, truth_x);
    let f = h.fit.as_ref().unwrap();
    let true_rate = series.rate_mm_per_cycle;
    eprintln!(
        "true rate {true_rate:e} mm/cycle; fitted {:e} [{:e}, {:e}] (95 %), χ²/ν {:.2}, R² {:.3}",
        f.slope, f.slope_lo95, f.slope_hi95, f.chi2_red, f.r2
    );
    for (p, l) in h.points.iter().zip(&logs) {
        eprintln!(
            "  n {:>8.0}: true {:.4} calibrated {:.4} ± {:.4}",
            l.head_cycles, l.clearance_mm, p.clearance_mm, p.u95_mm
        );
    }
    assert!(
        f.slope_lo95 <= true_rate && true_rate <= f.slope_hi95,
        "the true rate {true_rate:e} is outside the fitted 95 % interval [{:e}, {:e}]",
        f.slope_lo95,
        f.slope_hi95
    );
    assert_eq!(f.dof, 6);

    // The forecast: the fitted line's crossing of the limit, counted from the last log.
    let fc = h.forecast.as_ref().unwrap();
    let closed = (limit - f.intercept) / f.slope;
    assert!(
        (fc.at - closed).abs() <= 1e-9 * closed,
        "{} vs {closed}",
        fc.at
    );
    assert!((fc.remaining - (closed - truth_x[7])).abs() <= 1e-9 * closed);
    // 200 000 cycles per 7 days.
    let per_day = 200_000.0 / 7.0;
    assert!((h.cycles_per_day.unwrap() - per_day).abs() < 1e-6 * per_day);
    assert!((fc.days.unwrap() - fc.remaining / per_day).abs() < 1e-9 * fc.days.unwrap());
    let true_cross = (limit - series.c0_mm) / true_rate;
    eprintln!(
        "crossing of {limit} mm: true {true_cross:.0}, forecast {:.0} [{:.0}, {:?}] (95 %)",
        fc.at, fc.at_lo, fc.at_hi
    );
    assert!(fc.at_lo < fc.at && fc.at_hi.is_some_and(|hi| hi > fc.at));

    // The Trend pane at 80×24 shows the answer: the verdict's days, the
    // rate with its interval, the limit, the forecast's interval and the
    // newest log's clearance.
    let mut s = Session::new("trend");
    s.open_paths(&all);
    s.set_trend(Ok(r.clone()));
    let text = pinsight::batch::render_text(&s, PaneId::Trend, &PaneState::new(80, 24));
    eprintln!("{text}");
    assert_eq!(text.lines().count(), 24);
    let days = format!("{:.1}", fc.days.unwrap());
    for want in [
        format!("{days} days"),
        format!("{:.2e}", f.slope),
        format!("[{:.2e}, {:.2e}]", f.slope_lo95, f.slope_hi95),
        "limit 0.800 mm (given)".to_string(),
        format!("95 % [{:.1},", fc.days_lo.unwrap()),
        format!("{:.4}", h.points[7].clearance_mm),
        "corrupt.mcap".to_string(),
    ] {
        assert!(
            text.contains(&want),
            "`{want}` not on the 80×24 pane:\n{text}"
        );
    }
}

/// A head whose clearance grows by an Archard law: dc/dn = k·W(c), W the
/// sliding work per cycle the model simulates (paper preset, 1200 rpm), k
/// chosen so the clearance opens from 0.15 to 0.5 mm over the 6 logs
/// (1 000 000 head cycles). The truth c(n) = G⁻¹(G(0.15) + k·n) is written
/// into the logs' generator as a table; `--model archard` fits k from the
/// calibrated clearances with W simulated at the last log's calibrated
/// parameters (not the truth's: standoff and F_ins are fitted), so the test
/// checks the whole chain, not the W computation against itself.
#[test]
fn a_known_archard_law_is_recovered() {
    let mut p = Params::paper();
    p.motor_rpm = 1200.0;
    let work = work_ladder(&p, 1200.0, &DEFAULT_LADDER_MM, 40);
    assert!(work.is_usable(), "{:?}", work.notes);
    // The sliding work grows with the clearance (the wear accelerates).
    let w = |c: f64| work.work_at(c);
    eprintln!("W(c): {:?}", work.ladder);
    assert!(w(0.5) > w(0.15), "W(0.15) {} W(0.5) {}", w(0.15), w(0.5));
    let logs_n = 6;
    let between = 200_000.0;
    let n_last = (logs_n - 1) as f64 * between;
    let k = (work.g(0.5) - work.g(0.15)) / n_last;
    let table: Vec<(f64, f64)> = (0..logs_n)
        .map(|i| {
            let n = i as f64 * between;
            (n, work.g_inv(work.g(0.15) + k * n))
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let series = WearSeries {
        logs: logs_n,
        seed: 21,
        clearance_table: table.clone(),
        ..WearSeries::default()
    };
    let logs = series.write(dir.path()).unwrap();
    let limit = 0.6;
    let opts = TrendOptions {
        model: WearModel::Archard,
        limit_mm: Some(limit),
        level: 0.95,
        ..TrendOptions::default()
    };
    let inputs: Vec<_> = logs.iter().map(|l| l.path.clone()).collect();
    let r = run_trend(
        &inputs,
        &opts,
        &mut TrendCache::default(),
        &Progress::hidden(),
    );
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    let h = &r.heads[0];
    let a = h.archard.as_ref().expect("an Archard fit");
    let f = h.fit.as_ref().unwrap();
    for (p, (n, c)) in h.points.iter().zip(&table) {
        eprintln!(
            "  n {n:>8.0}: true {c:.4} calibrated {:.4} ± {:.4}",
            p.clearance_mm, p.u95_mm
        );
    }
    eprintln!(
        "true k {k:.4e} mm/J; fitted {:.4e} [{:.4e}, {:.4e}] (95 %), χ²/ν {:.2}, R² {:.3}; rate now {:.3e} [{:.3e}, {:.3e}] mm/cycle at {:.3} mm",
        a.k_mm_per_j,
        a.k_lo95,
        a.k_hi95,
        f.chi2_red,
        f.r2,
        a.rate_now,
        a.rate_now_lo95,
        a.rate_now_hi95,
        a.clearance_now_mm
    );
    assert!(
        a.k_lo95 <= k && k <= a.k_hi95,
        "the true k {k:e} is outside the fitted 95 % interval [{:e}, {:e}]",
        a.k_lo95,
        a.k_hi95
    );
    // The rate now is k·W at the fitted clearance; the fitted curve passes
    // through G⁻¹ of the line.
    assert!((a.rate_now - a.k_mm_per_j * a.work.work_at(a.clearance_now_mm)).abs() < 1e-18);
    let x_last = *h.x.last().unwrap();
    assert!((h.fitted_mm(x_last).unwrap() - a.clearance_now_mm).abs() < 1e-9);
    // The forecast is the crossing of G(limit) by the line, said in mm.
    let fc = h.forecast.as_ref().unwrap();
    assert_eq!(fc.limit_mm, limit);
    let closed = (a.work.g(limit) - f.intercept) / f.slope;
    assert!((fc.at - closed).abs() <= 1e-9 * closed);
    let true_cross = (work.g(limit) - work.g(0.15)) / k;
    eprintln!(
        "crossing of {limit} mm: true {true_cross:.0}, forecast {:.0} [{:.0}, {:?}] (95 %)",
        fc.at, fc.at_lo, fc.at_hi
    );
    assert!(fc.at_lo < fc.at && fc.at_hi.is_some_and(|hi| hi > fc.at));
}

/// Bad input never reaches the fit silently: a valid MCAP of another kind
/// (one JSON channel that is no rig signal), a text file named `.mcap` and
/// an empty file are each listed with an error naming the file; no head is
/// made of them.
#[test]
fn foreign_and_broken_logs_are_listed_with_their_errors() {
    let dir = tempfile::tempdir().unwrap();
    let foreign = dir.path().join("weather.mcap");
    {
        let file = std::io::BufWriter::new(std::fs::File::create(&foreign).unwrap());
        let mut w = mcap::WriteOptions::new().create(file).unwrap();
        let ch = w
            .add_channel(
                0,
                "/weather/temperature",
                "json",
                &std::collections::BTreeMap::new(),
            )
            .unwrap();
        for i in 0..10u32 {
            let t = 1_790_000_000_000_000_000 + u64::from(i) * 1_000_000;
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: i,
                    log_time: t,
                    publish_time: t,
                },
                format!("{{\"celsius\": {}}}", 20 + i).as_bytes(),
            )
            .unwrap();
        }
        w.finish().unwrap();
    }
    let text = dir.path().join("notes.mcap");
    std::fs::write(&text, "minutes of the shift meeting").unwrap();
    let empty = dir.path().join("empty.mcap");
    std::fs::write(&empty, b"").unwrap();
    let opts = TrendOptions {
        limit_mm: Some(0.8),
        ..TrendOptions::default()
    };
    let r = run_trend(
        &[foreign, text, empty],
        &opts,
        &mut TrendCache::default(),
        &Progress::hidden(),
    );
    for e in &r.errors {
        eprintln!("{}: {}", e.file, e.error);
    }
    assert_eq!(r.logs, 3);
    assert_eq!(r.calibrated, 0);
    assert!(r.heads.is_empty(), "{:?}", r.heads.len());
    assert_eq!(r.errors.len(), 3, "{:?}", r.errors);
    for name in ["weather.mcap", "notes.mcap", "empty.mcap"] {
        let e = r.errors.iter().find(|e| e.file.ends_with(name)).unwrap();
        assert!(!e.error.trim().is_empty(), "{name}: empty error");
    }
    // The report's Markdown lists them under "Left out".
    let md = r.to_markdown();
    assert!(
        md.contains("## Left out") && md.contains("weather.mcap"),
        "{md}"
    );
}

/// Two heads in one run, from synthetic logs: head A wears (the default
/// law), head B does not (rate 0, its clearance 0.3 mm throughout). Each
/// is its own trend (`by_rig`); B's says there is no wear the data can
/// show and gives no forecast, A's still has one. The truth is the
/// generator's input.
#[test]
fn a_second_head_that_does_not_wear_is_told_apart_from_one_that_does() {
    let dir = tempfile::tempdir().unwrap();
    let a = WearSeries {
        logs: 5,
        seed: 11,
        ..WearSeries::default()
    };
    let b = WearSeries {
        rig_id: "head-B".into(),
        logs: 5,
        seed: 12,
        c0_mm: 0.3,
        rate_mm_per_cycle: 0.0,
        ..WearSeries::default()
    };
    let (dir_a, dir_b) = (dir.path().join("a"), dir.path().join("b"));
    std::fs::create_dir_all(&dir_a).unwrap();
    std::fs::create_dir_all(&dir_b).unwrap();
    let logs_a = a.write(&dir_a).unwrap();
    let logs_b = b.write(&dir_b).unwrap();
    assert!(logs_b.iter().all(|l| l.clearance_mm == 0.3));
    let inputs: Vec<_> = logs_a
        .iter()
        .chain(&logs_b)
        .map(|l| l.path.clone())
        .collect();
    let opts = TrendOptions {
        limit_mm: Some(0.8),
        ..TrendOptions::default()
    };
    let r = run_trend(
        &inputs,
        &opts,
        &mut TrendCache::default(),
        &Progress::hidden(),
    );
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_eq!(r.heads.len(), 2);
    let head = |id: &str| r.heads.iter().find(|h| h.rig == id).unwrap();
    let (ha, hb) = (head("head-A"), head("head-B"));
    assert_eq!((ha.points.len(), hb.points.len()), (5, 5));
    for (p, l) in hb.points.iter().zip(&logs_b) {
        eprintln!(
            "  head-B n {:>8.0}: true {:.4} calibrated {:.4} ± {:.4}",
            l.head_cycles, l.clearance_mm, p.clearance_mm, p.u95_mm
        );
    }
    let fb = hb.fit.as_ref().unwrap();
    eprintln!(
        "head-B: rate {:e} [{:e}, {:e}]; {}",
        fb.slope, fb.slope_lo95, fb.slope_hi95, hb.verdict
    );
    assert!(
        fb.slope_lo95 <= 0.0 && 0.0 <= fb.slope_hi95,
        "the true rate 0 is outside head B's 95 % interval [{:e}, {:e}]",
        fb.slope_lo95,
        fb.slope_hi95
    );
    assert!(
        hb.verdict.starts_with("no wear the data can show"),
        "{}",
        hb.verdict
    );
    assert!(hb.forecast.is_err());
    let fa = ha.fit.as_ref().unwrap();
    eprintln!(
        "head-A: rate {:e} [{:e}, {:e}] (true {:e}); {}",
        fa.slope, fa.slope_lo95, fa.slope_hi95, a.rate_mm_per_cycle, ha.verdict
    );
    assert!(fa.slope_lo95 > 0.0, "head A's wear is not told from none");
    assert!(
        fa.slope_lo95 <= a.rate_mm_per_cycle && a.rate_mm_per_cycle <= fa.slope_hi95,
        "the true rate is outside head A's interval"
    );
    assert!(ha.forecast.is_ok());
}
