//! The generated fixtures of fixtures/logs/ (examples/gen_logs.rs) against
//! the generator's own truth (its configuration, written beside each log):
//! encoder offset, laser zero mark, force tare and drift, gear ratio, speed
//! ripple, drop-outs and cycle TDC times are recovered within the
//! uncertainty the analysis reports.

use pinsight::progress::Progress;
use pinsight::rig::cycles::{CycleOptions, CycleSet, CycleSource, ValueSource, analyse};
use pinsight::rig::{FindingCode, LoadOptions, LoadStatus, RigLog, SignalKind, load};
use serde_json::Value;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/logs")
        .join(name)
}

fn open(name: &str) -> (RigLog, CycleSet, Value) {
    let log = load(
        &fixture(&format!("{name}.mcap")),
        &LoadOptions::default(),
        &Progress::hidden(),
    )
    .unwrap();
    let cs = analyse(&log, &CycleOptions::default());
    let t: Value = serde_json::from_str(
        &std::fs::read_to_string(fixture(&format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    (log, cs, t)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Checks shared by every fixture: counts, cycles and TDC times, laser zero, tare line.
/// `tdc_bias_ns`: a systematic shift of the TDC times the test expects (see its caller).
fn common(log: &RigLog, cs: &CycleSet, t: &Value, tdc_bias_ns: f64) {
    let cfg = &t["config"];
    for (topic, n) in t["messages"].as_object().unwrap() {
        let ch = log.channels.iter().find(|c| &c.topic == topic).unwrap();
        assert_eq!(ch.messages, n.as_u64().unwrap(), "{topic}");
    }
    let tdc: Vec<i64> = t["tdc_log_times_ns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_i64().unwrap())
        .collect();
    assert_eq!(
        cs.cycles.len() as u64,
        t["complete_cycles"].as_u64().unwrap()
    );
    let crank_rpm = f(&cfg["motor_rpm"]) / f(&cfg["gear_ratio"]);
    let count_ns = 60.0 / crank_rpm / 4096.0 * 1e9;
    for c in &cs.cycles {
        let k = c.index as usize;
        let err = (c.t_start_ns - tdc[k]).abs() as f64;
        if cs.source == CycleSource::Marks {
            assert!(err <= 1.0, "cycle {k}: {err} ns");
        } else {
            assert!(
                err <= count_ns + tdc_bias_ns,
                "cycle {k}: {err} ns > one count ({count_ns} ns) + {tdc_bias_ns} ns"
            );
        }
    }
    assert!((cs.crank.crank_rpm_mean - crank_rpm).abs() < 1e-3 * crank_rpm);
    assert!((cs.crank.motor_rpm_mean - f(&cfg["motor_rpm"])).abs() < 2e-3 * f(&cfg["motor_rpm"]));

    // Laser zero: the ideal mechanism has no clearance, so only noise and the laser quantum remain.
    let lz = &cs.offsets.laser_zero_mm;
    let want = f(&cfg["laser_zero_mm"]);
    assert!(
        (lz.applied - want).abs()
            <= 4.0 * lz.sigma.unwrap()
                + f(&cfg["laser_quantum_mm"])
                + 0.002 * f(&cfg["latency_displacement_s"]) * 1e4,
        "laser zero {} vs {want}",
        lz.applied
    );

    // Force tare line at the log's ends.
    let o = &cs.offsets;
    let dur = f(&t["duration_s"]);
    let span = (log.log_end_ns.unwrap() - log.log_start_ns.unwrap()) as f64 * 1e-9;
    let (t0, t1) = (f(&t["force_tare_at_start_n"]), f(&t["force_tare_at_end_n"]));
    let end_want = t0 + (t1 - t0) * span / dur;
    assert!(
        (o.force_tare_start_n.unwrap() - t0).abs() <= 4.0 * o.force_tare_start_sigma_n.unwrap(),
        "tare start {:?} vs {t0}",
        o.force_tare_start_n
    );
    assert!(
        (o.force_tare_end_n.unwrap() - end_want).abs() <= 4.0 * o.force_tare_end_sigma_n.unwrap(),
        "tare end {:?} vs {end_want}",
        o.force_tare_end_n
    );
}

#[test]
fn encoder_offset_from_the_marks() {
    let (log, cs, t) = open("synth-1200-offsets");
    common(&log, &cs, &t, 0.0);
    let ao = &cs.offsets.angle_offset_rad;
    let want = f(&t["config"]["encoder_offset_rad"]);
    assert_eq!(ao.source, ValueSource::Estimated);
    assert!(
        (ao.applied - want).abs() <= 4.0 * ao.sigma.unwrap(),
        "{} ± {:?} vs {want}",
        ao.applied,
        ao.sigma
    );
    assert!(log.report.status == LoadStatus::Ok);
    assert!(cs.findings.iter().any(
        |x| x.code == FindingCode::OffsetEstimated && x.message.contains("encoder zero is off")
    ));
}

#[test]
fn encoder_offset_from_the_displacement_without_marks() {
    let (log, cs, t) = open("synth-1500-nomarks-lz4");
    // Without marks the TDCs come from the angle, whose offset is estimated
    // from the displacement: the laser's lag τ shifts them by up to τ.
    let lag_ns = f(&t["config"]["laser_lag_s"]) * 1e9;
    common(&log, &cs, &t, lag_ns);
    assert_eq!(cs.source, CycleSource::Angle);
    let cfg = &t["config"];
    // The displacement fit sees the laser's lag as a phase: ω·τ.
    let omega = TAU * f(&cfg["motor_rpm"]) / 60.0;
    let want = f(&cfg["encoder_offset_rad"]) - omega * f(&cfg["laser_lag_s"]);
    let ao = &cs.offsets.angle_offset_rad;
    assert!(
        (ao.applied - want).abs() <= 4.0 * ao.sigma.unwrap(),
        "{} ± {:?} vs {want}",
        ao.applied,
        ao.sigma
    );
}

#[test]
fn metadata_zeros_and_a_gear_ratio() {
    let (log, cs, t) = open("synth-2000-gear2-meta-plain");
    common(&log, &cs, &t, 0.0);
    assert_eq!(log.report.status, LoadStatus::Ok);
    assert!(!log.container.chunked);
    let o = &cs.offsets;
    assert_eq!(o.angle_offset_rad.source, ValueSource::Metadata);
    assert_eq!(o.laser_zero_mm.source, ValueSource::Metadata);
    assert_eq!(o.force_tare_n.source, ValueSource::Metadata);
    assert_eq!(o.angle_offset_rad.applied, -0.2);
    assert!((cs.crank.crank_rpm_mean - 1000.0).abs() < 1.0 && cs.crank.gear_ratio == 2.0);
    // The estimates agree with the metadata, so nothing is flagged.
    assert!(
        cs.findings
            .iter()
            .all(|x| x.severity == pinsight::rig::Severity::Info),
        "{:#?}",
        cs.findings
    );
}

#[test]
fn ripple_latency_dropouts_and_blocks() {
    let (log, cs, t) = open("synth-1800-ripple-dropouts-blocks");
    common(&log, &cs, &t, 0.0);
    let cfg = &t["config"];
    let h: Vec<f64> = cs.usable().map(|c| c.ripple_first_harmonic).collect();
    let m = h.iter().sum::<f64>() / h.len() as f64;
    let sd = (h.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (h.len() - 1) as f64).sqrt();
    assert!(
        (m - f(&cfg["speed_ripple"])).abs() <= 4.0 * sd / (h.len() as f64).sqrt(),
        "ripple {m} ± {sd}"
    );
    for d in cfg["dropouts"].as_array().unwrap() {
        let (kind, lat) = if d["signal"] == "force" {
            (SignalKind::Force, f(&cfg["latency_force_s"]))
        } else {
            (SignalKind::Displacement, f(&cfg["latency_displacement_s"]))
        };
        let st = log.stats_of(kind).unwrap();
        let g: Vec<_> = st.gaps.iter().filter(|g| g.missing_samples > 2).collect();
        assert_eq!(g.len(), 1);
        let t0 = log.log_start_ns.unwrap();
        // Log times are stamped `latency` after the sample was taken.
        let from = (g[0].from_ns - t0) as f64 * 1e-9 - lat;
        let to = (g[0].to_ns - t0) as f64 * 1e-9 - lat;
        // The last sample before and the first after the window, one 10 kHz interval apart from its edges.
        assert!(
            from < f(&d["from_s"]) && f(&d["from_s"]) - from <= 1.01e-4,
            "{from}"
        );
        assert!(
            to >= f(&d["to_s"]) && to - f(&d["to_s"]) <= 1.01e-4 + 1e-4,
            "{to}"
        );
    }
    assert!(log.stats_of(SignalKind::Force).unwrap().blocks > 0);
}
