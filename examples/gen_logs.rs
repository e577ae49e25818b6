//! Generates synthetic rig logs with the `mcap` crate (see `pinsight::rig::synth`).
//!
//! ```sh
//! # the small fixtures of fixtures/logs/ (each NAME.mcap with NAME.truth.json)
//! cargo run --release --example gen_logs -- fixtures [--out fixtures/logs]
//! # a large log for the benchmark: ~100 MB of zstd chunks at 1200 rpm
//! cargo run --release --example gen_logs -- big --target-mb 100 --out /tmp/big.mcap [--compression zstd|lz4|none]
//! ```
//!
//! The truth file of a fixture is written from the generator's own
//! configuration (never from reading the log back): sensor zeros, encoder
//! offset, speed ripple, TDC times and message counts.

use pinsight::model::Params;
use pinsight::rig::SignalKind;
use pinsight::rig::synth::{self, Dropout, IdealTruth, SynthConfig, WriteSettings};
use serde_json::json;
use std::collections::BTreeMap;
use std::io::{BufWriter, Cursor};
use std::path::{Path, PathBuf};

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn compression(name: &str) -> Option<mcap::Compression> {
    match name {
        "lz4" => Some(mcap::Compression::Lz4),
        "none" => None,
        _ => Some(mcap::Compression::Zstd),
    }
}

fn meta(cfg: &SynthConfig, extra: &[(&str, &str)]) -> BTreeMap<String, String> {
    let mut m = SynthConfig {
        metadata: None,
        ..cfg.clone()
    }
    .rig_metadata();
    m.insert("rig_id".into(), "synthetic-head".into());
    for (k, v) in extra {
        m.insert(k.to_string(), v.to_string());
    }
    m
}

/// Writes NAME.mcap and NAME.truth.json.
fn fixture(
    dir: &Path,
    name: &str,
    cfg: &SynthConfig,
    settings: &WriteSettings,
    notes: &str,
) -> anyhow::Result<()> {
    let truth = IdealTruth::from_params(&Params::paper());
    fixture_with(
        dir,
        name,
        cfg,
        settings,
        notes,
        &truth,
        json!({"model": "ideal mechanism (closed form) of the paper preset, quasi-static process load", "preset": "paper", "clearance_mm": 0.0, "standoff_mm": Params::paper().standoff * 1e3}),
    )
}

/// Writes NAME.mcap and NAME.truth.json from any truth; `true_parameters`
/// describes it (written from the generator's inputs, never read back).
fn fixture_with(
    dir: &Path,
    name: &str,
    cfg: &SynthConfig,
    settings: &WriteSettings,
    notes: &str,
    truth: &dyn synth::Truth,
    true_parameters: serde_json::Value,
) -> anyhow::Result<()> {
    let log = synth::generate(cfg, truth);
    let mut cur = Cursor::new(Vec::new());
    synth::write(&log, &mut cur, settings)?;
    let bytes = cur.into_inner();
    let path = dir.join(format!("{name}.mcap"));
    std::fs::write(&path, &bytes)?;
    let mut counts = BTreeMap::new();
    let mut spans = BTreeMap::new();
    for (i, c) in log.channels.iter().enumerate() {
        let ts: Vec<u64> = log
            .messages
            .iter()
            .filter(|m| m.channel == i)
            .map(|m| m.log_time)
            .collect();
        counts.insert(c.topic.clone(), ts.len());
        spans.insert(c.topic.clone(), json!([ts.first(), ts.last()]));
    }
    let tdc: Vec<u64> = cfg
        .tdc_times()
        .iter()
        .map(|(t, _)| cfg.start_ns + (t * 1e9).round() as u64)
        .collect();
    let dur = cfg.duration_s();
    let t = json!({
        "file": format!("{name}.mcap"),
        "generator": "examples/gen_logs.rs (pinsight::rig::synth)",
        "true_parameters": true_parameters,
        "notes": notes,
        "file_size_bytes": bytes.len(),
        "compression": format!("{:?}", settings.compression),
        "config": cfg,
        "metadata": log.metadata[0].1,
        "messages": counts,
        "first_last_log_time_ns": spans,
        "tdc_log_times_ns": tdc,
        "complete_cycles": tdc.len().saturating_sub(1),
        "duration_s": dur,
        "force_tare_at_start_n": cfg.force_tare_n,
        "force_tare_at_end_n": cfg.force_tare_n + cfg.force_drift_n,
    });
    std::fs::write(
        dir.join(format!("{name}.truth.json")),
        serde_json::to_string_pretty(&t)?,
    )?;
    println!(
        "{} ({} bytes, {} messages)",
        path.display(),
        bytes.len(),
        log.messages.len()
    );
    Ok(())
}

fn fixtures(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    let base = SynthConfig::default();

    // Encoder zero off by 0.35 rad (not in the metadata), laser zero 9.7 mm, tare 0.05 N drifting.
    let c = SynthConfig {
        revolutions: 12.4,
        encoder_offset_rad: 0.35,
        laser_zero_mm: 9.7,
        force_tare_n: 0.05,
        force_drift_n: 0.03,
        seed: 11,
        ..base.clone()
    };
    let c = SynthConfig {
        metadata: Some(meta(&c, &[])),
        ..c
    };
    fixture(
        dir,
        "synth-1200-offsets",
        &c,
        &WriteSettings::default(),
        "encoder offset 0.35 rad not in the metadata: estimated from the cycle marks and applied",
    )?;

    // No cycle topic, lz4, encoder offset 0.5 rad: estimated from the displacement.
    let c = SynthConfig {
        motor_rpm: 1500.0,
        revolutions: 15.7,
        encoder_offset_rad: 0.5,
        cycle_topic: false,
        seed: 12,
        ..base.clone()
    };
    let c = SynthConfig {
        metadata: Some(meta(&c, &[])),
        ..c
    };
    fixture(
        dir,
        "synth-1500-nomarks-lz4",
        &c,
        &WriteSettings {
            compression: Some(mcap::Compression::Lz4),
            ..WriteSettings::default()
        },
        "no /rig/cycle: cycles from the angle; encoder offset 0.5 rad estimated from the displacement (biased by the laser lag ω·τ)",
    )?;

    // Sensor zeros given in the metadata, gear ratio 2, unchunked.
    let c = SynthConfig {
        motor_rpm: 2000.0,
        gear_ratio: 2.0,
        revolutions: 8.3,
        encoder_offset_rad: -0.2,
        laser_zero_mm: 10.25,
        force_tare_n: 0.01,
        force_drift_n: 0.0,
        seed: 13,
        ..base.clone()
    };
    let c = SynthConfig {
        metadata: Some(meta(
            &c,
            &[
                ("angle_offset_rad", "-0.2"),
                ("laser_zero_mm", "10.25"),
                ("force_tare_n", "0.01"),
            ],
        )),
        ..c
    };
    fixture(
        dir,
        "synth-2000-gear2-meta-plain",
        &c,
        &WriteSettings {
            chunked: false,
            ..WriteSettings::default()
        },
        "motor 2000 rpm through a 2:1 gear (crank 1000 rpm); angle offset, laser zero and tare in the metadata; not chunked",
    )?;

    // Larger ripple, latency, drop-outs, blocks.
    let c = SynthConfig {
        motor_rpm: 1800.0,
        revolutions: 12.2,
        speed_ripple: 0.02,
        ripple_phase: 2.0,
        latency_displacement_s: 100e-6,
        blocks: true,
        dropouts: vec![
            Dropout {
                signal: SignalKind::Displacement,
                from_s: 0.1,
                to_s: 0.104,
            },
            Dropout {
                signal: SignalKind::Force,
                from_s: 0.2,
                to_s: 0.23,
            },
        ],
        seed: 14,
        ..base
    };
    let c = SynthConfig {
        metadata: Some(meta(&c, &[])),
        ..c
    };
    fixture(
        dir,
        "synth-1800-ripple-dropouts-blocks",
        &c,
        &WriteSettings::default(),
        "2 % speed ripple, 100 µs displacement latency, a 4 ms displacement and a 30 ms force drop-out, blocks of 100 samples",
    )?;
    model_fixtures(dir)
}

/// Logs of the clearance-joint model (for calibration): the true clearance
/// and standoff differ from the nominal ones in the metadata.
fn model_fixtures(dir: &Path) -> anyhow::Result<()> {
    let base = SynthConfig::default();
    let runs = [
        // (name, motor rpm, true clearance mm, true standoff mm, encoder offset, laser zero in metadata, seed, notes)
        (
            "synth-1200-model-c030",
            1200.0,
            0.30,
            13.8,
            0.0,
            false,
            21u64,
            "clearance-joint model, true clearance 0.30 mm and standoff 13.8 mm (metadata: 0.1 and 14.0)",
        ),
        (
            "synth-1500-model-c020",
            1500.0,
            0.20,
            14.25,
            0.2,
            true,
            22u64,
            "clearance-joint model at 1500 rpm, true clearance 0.20 mm and standoff 14.25 mm (metadata: 0.1 and 14.0); encoder offset 0.2 rad not in the metadata, laser zero in it",
        ),
    ];
    for (name, rpm, c_mm, so_mm, enc, lz_meta, seed, notes) in runs {
        let mut p = Params::paper();
        p.clearance = c_mm * 1e-3;
        p.standoff = so_mm * 1e-3;
        let cfg = SynthConfig {
            motor_rpm: rpm,
            revolutions: 30.4,
            encoder_offset_rad: enc,
            laser_zero_mm: 10.0,
            seed,
            ..base.clone()
        };
        let extra: Vec<(&str, &str)> = if lz_meta {
            vec![("laser_zero_mm", "10.0")]
        } else {
            Vec::new()
        };
        let cfg = SynthConfig {
            metadata: Some(meta(&cfg, &extra)),
            ..cfg
        };
        let (warmup, grid_deg, rtol) = (3.0, 0.05, 1e-8);
        let truth = synth::ModelTruth::simulate(&p, &cfg, warmup, grid_deg, rtol)?;
        fixture_with(
            dir,
            name,
            &cfg,
            &WriteSettings::default(),
            notes,
            &truth,
            json!({
                "model": "clearance-joint model (pinsight::sim, level clearance, DOP853), constant crank speed, the speed ripple applied as a time warp",
                "preset": "paper",
                "clearance_mm": c_mm,
                "standoff_mm": so_mm,
                "motor_rpm": rpm,
                "warmup_revolutions": warmup,
                "grid_deg": grid_deg,
                "rtol": rtol,
                "nominal_vs_true": {"clearance_mm": [0.1, c_mm], "standoff_mm": [14.0, so_mm]},
            }),
        )?;
    }
    Ok(())
}

fn big(args: &[String]) -> anyhow::Result<()> {
    let out = PathBuf::from(arg(args, "--out").unwrap_or_else(|| "big.mcap".into()));
    let target_mb: f64 = arg(args, "--target-mb").map_or(Ok(100.0), |s| s.parse())?;
    let settings = WriteSettings {
        compression: compression(&arg(args, "--compression").unwrap_or_default()),
        chunk_size: 4 << 20,
        ..WriteSettings::default()
    };
    let blocks = args.iter().any(|a| a == "--blocks");
    let truth = IdealTruth::from_params(&Params::paper());
    // Pilot: bytes per revolution.
    let pilot = SynthConfig {
        revolutions: 40.0,
        blocks,
        ..SynthConfig::default()
    };
    let mut cur = Cursor::new(Vec::new());
    synth::write_streaming(&pilot, &truth, &mut cur, &settings)?;
    let per_rev = cur.into_inner().len() as f64 / pilot.revolutions;
    let revs = (target_mb * 1e6 / per_rev).ceil();
    let cfg = SynthConfig {
        revolutions: revs,
        blocks,
        ..SynthConfig::default()
    };
    let t = std::time::Instant::now();
    let file = std::fs::File::create(&out)?;
    let n = synth::write_streaming(
        &cfg,
        &truth,
        BufWriter::with_capacity(1 << 20, file),
        &settings,
    )?;
    let size = std::fs::metadata(&out)?.len();
    println!(
        "{}: {:.1} MB, {n} messages, {revs} revolutions ({:.1} s of log), written in {:.1} s",
        out.display(),
        size as f64 / 1e6,
        cfg.duration_s(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("fixtures") => fixtures(Path::new(
            &arg(&args, "--out").unwrap_or_else(|| "fixtures/logs".into()),
        )),
        Some("big") => big(&args),
        _ => {
            eprintln!(
                "usage: gen_logs fixtures [--out DIR] | gen_logs big [--target-mb N] [--out FILE] [--compression zstd|lz4|none] [--blocks]"
            );
            std::process::exit(2);
        }
    }
}
