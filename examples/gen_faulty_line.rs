//! Writes a faulty line (`pinsight::process::synth`): a rig log whose
//! cycles carry insertion faults, with a side-view photograph of every
//! connector on its camera topic, and the truth of both beside it.
//!
//! ```sh
//! cargo run --release --example gen_faulty_line -- OUT.mcap [--cycles 200] [--rpm 1200]
//!     [--fault-rate 0.2] [--debris-rate 0.05] [--seed 1] [--no-images]
//! ```
//!
//! Writes `OUT.mcap` and `OUT.truth.json` (per connector: the fault drawn,
//! whether the process must be NOK, the photograph's true verdict, debris;
//! and the confusion table a correct report shows). Judge it with
//! `pinsight monitor OUT.mcap --process fixtures/process/side-1x6.process.toml
//! --recipe fixtures/vision/side-1x6.toml` (learn the envelope first with
//! `--learn 20`).

use pinsight::process::synth::{FaultyLineConfig, faulty_line};
use pinsight::rig::synth::faults::FaultRates;
use pinsight::rig::synth::{SynthConfig, WriteSettings, write};
use pinsight::vision::Recipe;
use std::io::Cursor;
use std::path::{Path, PathBuf};

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn num(args: &[String], name: &str, default: f64) -> anyhow::Result<f64> {
    arg(args, name).map_or(Ok(default), |s| {
        s.parse()
            .map_err(|_| anyhow::anyhow!("{name}: not a number: {s}"))
    })
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = PathBuf::from(
        args.first()
            .filter(|a| !a.starts_with("--"))
            .ok_or_else(|| anyhow::anyhow!("usage: gen_faulty_line OUT.mcap [options]"))?,
    );
    let recipe =
        Recipe::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/vision/side-1x6.toml"))?;
    let cycles = num(&args, "--cycles", 200.0)?;
    let cfg = FaultyLineConfig {
        rig: SynthConfig {
            motor_rpm: num(&args, "--rpm", 1200.0)?,
            revolutions: cycles + 1.6,
            seed: num(&args, "--seed", 1.0)? as u64,
            ..SynthConfig::default()
        },
        rates: FaultRates {
            fault_rate: num(&args, "--fault-rate", 0.2)?,
            ..FaultRates::default()
        },
        recipe,
        debris_rate: num(&args, "--debris-rate", 0.05)?,
        images: !args.iter().any(|a| a == "--no-images"),
    };
    let (log, truth) = faulty_line(&cfg);
    let mut cur = Cursor::new(Vec::new());
    write(&log, &mut cur, &WriteSettings::default())?;
    std::fs::write(&out, cur.into_inner())?;
    let truth_path = out.with_extension("truth.json");
    std::fs::write(&truth_path, serde_json::to_vec_pretty(&truth)?)?;
    let faults = truth.connectors.iter().filter(|c| c.process_nok).count();
    println!(
        "{}: {} connectors, {} with a process fault; confusion {:?}; truth in {}",
        out.display(),
        truth.connectors.len(),
        faults,
        truth.confusion,
        truth_path.display()
    );
    Ok(())
}
