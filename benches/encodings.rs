//! Encodings benchmark (issue 17): the same ~100 MB rig log in JSON, in
//! protobuf and in ROS 2 CDR, each through `pinsight overlay` (load, cycles,
//! model prediction, comparison), as fresh processes.
//!
//! ```sh
//! python3 -m pip install mcap mcap-protobuf-support mcap-ros2-support foxglove-schemas-protobuf
//! cargo bench --bench encodings
//! ```
//!
//! The JSON log is `rig_load`'s (generated once into `target/bench-data/`);
//! its protobuf and ROS 2 twins are written from it by the official Python
//! writers (`fixtures/twins/write_twins.py`, a few minutes the first time,
//! then cached). Reports the median wall time of 5 runs per encoding and
//! the ratios to JSON (target: at most 1.5).

use pinsight::model::Params;
use pinsight::rig::synth::{self, IdealTruth, SynthConfig, WriteSettings};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Revolutions giving ~100 MB of zstd JSON (4 MiB chunks), as in rig_load.
const REVOLUTIONS: f64 = 3018.0;

fn data_dir() -> PathBuf {
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("bench-data/encodings");
    std::fs::create_dir_all(&dir).expect("bench-data dir");
    dir
}

fn ensure_json(dir: &Path) -> PathBuf {
    let p = dir.join("big.mcap");
    if !p.exists() {
        let cfg = SynthConfig {
            revolutions: REVOLUTIONS,
            ..SynthConfig::default()
        };
        let settings = WriteSettings {
            chunk_size: 4 << 20,
            ..WriteSettings::default()
        };
        let tmp = dir.join("big.partial");
        let f = std::fs::File::create(&tmp).expect("create bench log");
        synth::write_streaming(
            &cfg,
            &IdealTruth::from_params(&Params::paper()),
            std::io::BufWriter::new(f),
            &settings,
        )
        .expect("write bench log");
        std::fs::rename(&tmp, &p).expect("rename bench log");
    }
    p
}

fn ensure_twins(dir: &Path) {
    if dir.join("big.pb.mcap").exists() && dir.join("big.ros2.mcap").exists() {
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/twins/write_twins.py");
    let t = Instant::now();
    let st = Command::new("python3")
        .arg(&script)
        .arg(dir)
        .arg(dir)
        .status()
        .expect("python3 (with the mcap writer packages) is needed to write the twins");
    assert!(st.success(), "write_twins.py failed");
    eprintln!("twins written in {:.0} s", t.elapsed().as_secs_f64());
}

fn median_overlay_s(file: &Path, map: Option<&Path>) -> f64 {
    let mut times = Vec::new();
    for _ in 0..5 {
        let mut c = Command::new(env!("CARGO_BIN_EXE_pinsight"));
        c.arg("overlay").arg(file).arg("--json");
        if let Some(m) = map {
            c.arg("--channels").arg(m);
        }
        let t = Instant::now();
        let out = c.output().expect("run pinsight");
        times.push(t.elapsed().as_secs_f64());
        assert!(
            out.status.code().is_some_and(|c| c <= 1),
            "{}: {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let dir = data_dir();
    let json = ensure_json(&dir);
    ensure_twins(&dir);
    let size = |p: &Path| std::fs::metadata(p).map_or(0.0, |m| m.len() as f64 / 1e6);
    let pb = dir.join("big.pb.mcap");
    let ros = dir.join("big.ros2.mcap");
    let ros_map = dir.join("big.ros2.channels.toml");
    let tj = median_overlay_s(&json, None);
    let tp = median_overlay_s(&pb, None);
    let tr = median_overlay_s(&ros, Some(&ros_map));
    println!(
        "overlay, fresh process, median of 5 ({} threads):",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    println!("  json      {:6.1} MB  {tj:.3} s", size(&json));
    println!(
        "  protobuf  {:6.1} MB  {tp:.3} s  ratio {:.2}",
        size(&pb),
        tp / tj
    );
    println!(
        "  ros2 cdr  {:6.1} MB  {tr:.3} s  ratio {:.2}",
        size(&ros),
        tr / tj
    );
}
