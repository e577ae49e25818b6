//! Writes a synthetic wear series (see `pinsight::rig::synth::wear_series`):
//! `cargo run --release --example wear_series -- DIR [RIG] [LOGS] [RATE_MM_PER_CYCLE] [C0_MM] [SEED]`
//! e.g. a wearing head and one that does not:
//! `… -- series head-A 10 2.5e-7 0.15 1` and `… -- series head-B 6 0 0.2 2`.

use pinsight::rig::synth::wear_series::WearSeries;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = a.first() else {
        eprintln!("usage: wear_series DIR [RIG] [LOGS] [RATE_MM_PER_CYCLE] [C0_MM] [SEED]");
        std::process::exit(2);
    };
    let num = |i: usize, d: f64| a.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(d);
    let d = WearSeries::default();
    let s = WearSeries {
        rig_id: a.get(1).cloned().unwrap_or(d.rig_id.clone()),
        logs: num(2, d.logs as f64) as usize,
        rate_mm_per_cycle: num(3, d.rate_mm_per_cycle),
        c0_mm: num(4, d.c0_mm),
        seed: num(5, d.seed as f64) as u64,
        ..d
    };
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("{dir}: {e}");
        std::process::exit(1);
    }
    match s.write(std::path::Path::new(dir)) {
        Ok(logs) => {
            for l in logs {
                println!(
                    "{}  head_cycles {:>9.0}  true clearance {:.4} mm",
                    l.path.display(),
                    l.head_cycles,
                    l.clearance_mm
                );
            }
        }
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
