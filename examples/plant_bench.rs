//! The plant-scale benchmark (issue 19, BENCHMARKS.md "Plant scale"): one
//! `pinsight yield` process over a folder of images against the same batch
//! as N shards run P at a time (as a cluster would run them, here on one
//! machine), then `pinsight merge`; wall times, the merged folder checked
//! byte for byte against the single run's, and the sizes of the outputs.
//!
//! ```sh
//! cargo run --release --example gen_plant -- 100000 /work/bench-plant
//! cargo build --release
//! cargo run --release --example plant_bench -- /work/bench-plant \
//!     [--shards 8] [--parallel 2] [--repeat 3] [--merges 5] [--items parquet] [--bin target/release/pinsight]
//! ```
//!
//! The merge is cheap next to the shards: each repetition runs it
//! `--merges` times (default 5) into a fresh folder and keeps the median.
//!
//! The single run uses `--jobs P` (all the cores the shards share), each
//! shard `--jobs 1`. The single run and the sharded run alternate
//! `--repeat` times (default 3) and the medians are printed, with the load
//! average after each step (other work on the machine changes the figures). Outputs go to DIR/out-* and are
//! removed at the end unless `--keep`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

fn size(p: &Path) -> u64 {
    match std::fs::metadata(p) {
        Ok(m) if m.is_dir() => std::fs::read_dir(p)
            .map(|rd| rd.flatten().map(|e| size(&e.path())).sum())
            .unwrap_or(0),
        Ok(m) => m.len(),
        Err(_) => 0,
    }
}

fn run(bin: &Path, args: &[String]) -> anyhow::Result<()> {
    let o = Command::new(bin).args(args).output()?;
    anyhow::ensure!(
        matches!(o.status.code(), Some(0 | 3)),
        "{} {}: {}",
        bin.display(),
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    Ok(())
}

/// The numbers of images and of pins in a yield report (`report.items`,
/// `report.pins_inspected`).
fn count_items(yield_json: &Path) -> (u64, u64) {
    let v = std::fs::read(yield_json)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .unwrap_or_default();
    (
        v["report"]["items"].as_u64().unwrap_or(0),
        v["report"]["pins_inspected"].as_u64().unwrap_or(0),
    )
}

fn same_tree(a: &Path, b: &Path) -> anyhow::Result<bool> {
    let mut fa = Vec::new();
    let mut fb = Vec::new();
    fn walk(root: &Path, d: &Path, out: &mut Vec<PathBuf>) {
        if let Ok(rd) = std::fs::read_dir(d) {
            for e in rd.flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(root, &p, out);
                } else if let Ok(r) = p.strip_prefix(root) {
                    out.push(r.to_path_buf());
                }
            }
        }
    }
    walk(a, a, &mut fa);
    walk(b, b, &mut fb);
    fa.sort();
    fb.sort();
    if fa != fb {
        return Ok(false);
    }
    for f in &fa {
        if std::fs::read(a.join(f))? != std::fs::read(b.join(f))? {
            println!("  {} differs", f.display());
            return Ok(false);
        }
    }
    Ok(true)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = PathBuf::from(
        args.first()
            .ok_or_else(|| anyhow::anyhow!("usage: plant_bench DIR [options]"))?,
    );
    let n: u32 = arg(&args, "--shards").map_or(Ok(8), |s| s.parse())?;
    let p: usize = arg(&args, "--parallel").map_or(Ok(2), |s| s.parse())?;
    let items = arg(&args, "--items").unwrap_or_else(|| "parquet".into());
    let bin =
        PathBuf::from(arg(&args, "--bin").unwrap_or_else(|| "target/release/pinsight".into()));
    let keep = args.iter().any(|a| a == "--keep");
    let repeat: usize = arg(&args, "--repeat").map_or(Ok(3), |s| s.parse())?;
    let merge_runs: usize = arg(&args, "--merges").map_or(Ok(5), |s| s.parse())?;
    anyhow::ensure!(merge_runs >= 1, "--merges must be at least 1");
    anyhow::ensure!(repeat >= 1, "--repeat must be at least 1");
    let (img, rec) = (dir.join("img"), dir.join("recipe"));
    let out = |s: &str| dir.join(format!("out-{s}"));
    let common = |o: &Path, jobs: usize| -> Vec<String> {
        vec![
            "yield".into(),
            img.display().to_string(),
            "-r".into(),
            rec.display().to_string(),
            "--jobs".into(),
            jobs.to_string(),
            "--items".into(),
            items.clone(),
            "--out".into(),
            o.display().to_string(),
        ]
    };
    println!("load average before: {}", load());
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };

    // Alternating single run and sharded run, `--repeat` times, so a
    // change of the machine's load hits both sides alike.
    let (mut singles, mut shardeds, mut merges) = (Vec::new(), Vec::new(), Vec::new());
    for rep in 0..repeat {
        for d in ["single", "merged"] {
            let _ = std::fs::remove_dir_all(out(d));
        }
        let t = Instant::now();
        run(&bin, &common(&out("single"), p))?;
        let single = t.elapsed().as_secs_f64();
        println!(
            "[{rep}] single process (--jobs {p}): {single:.1} s   load {}",
            load()
        );

        let t = Instant::now();
        let next = std::sync::atomic::AtomicU32::new(0);
        let shard_times = std::sync::Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for _ in 0..p {
                s.spawn(|| {
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        if k >= n {
                            break;
                        }
                        let mut a = common(&out(&format!("shard-{k}")), 1);
                        a.push("--shard".into());
                        a.push(format!("{k}/{n}"));
                        let t = Instant::now();
                        let r = run(&bin, &a);
                        shard_times
                            .lock()
                            .unwrap()
                            .push((k, t.elapsed().as_secs_f64(), r.is_ok()));
                    }
                });
            }
        });
        let sharded = t.elapsed().as_secs_f64();
        let mut st = shard_times.into_inner().unwrap();
        st.sort_by_key(|x| x.0);
        anyhow::ensure!(st.iter().all(|x| x.2), "a shard failed: {st:?}");
        println!(
            "[{rep}] {n} shards, {p} at a time (--jobs 1 each): {sharded:.1} s = {:.3} × the single run   load {}",
            sharded / single,
            load()
        );
        println!(
            "  per shard: {}",
            st.iter()
                .map(|x| format!("{:.1}", x.1))
                .collect::<Vec<_>>()
                .join(", ")
        );

        let mut m = vec!["merge".to_string()];
        m.extend((0..n).map(|k| out(&format!("shard-{k}")).display().to_string()));
        m.push("--out".into());
        m.push(out("merged").display().to_string());
        let mut times = Vec::new();
        for _ in 0..merge_runs {
            let _ = std::fs::remove_dir_all(out("merged"));
            let t = Instant::now();
            run(&bin, &m)?;
            times.push(t.elapsed().as_secs_f64());
        }
        let merge = median(&mut times.clone());
        println!(
            "[{rep}] merge: {merge:.2} s (median of {merge_runs}: {})   load {}",
            times
                .iter()
                .map(|t| format!("{t:.2}"))
                .collect::<Vec<_>>()
                .join(", "),
            load()
        );
        println!(
            "[{rep}] merged folder = single run's, byte for byte: {}",
            same_tree(&out("single"), &out("merged"))?
        );
        singles.push(single);
        shardeds.push(sharded);
        merges.push(merge);
    }
    let ratios: Vec<f64> = singles.iter().zip(&shardeds).map(|(a, b)| b / a).collect();
    println!(
        "medians of {repeat}: single {:.1} s, sharded {:.1} s, sharded / single {:.3} (pairs: {:?}), merge {:.2} s",
        median(&mut singles.clone()),
        median(&mut shardeds.clone()),
        median(&mut ratios.clone()),
        ratios.iter().map(|r| format!("{r:.3}")).collect::<Vec<_>>(),
        median(&mut merges.clone()),
    );
    let images = size(&out("single").join("images.parquet")) + size(&out("single").join("images"));
    let pins = size(&out("single").join("pins.parquet")) + size(&out("single").join("pins"));
    let (count, pins_n) = count_items(&out("single").join("yield.json"));
    if count > 0 {
        println!(
            "Parquet: images {:.2} MB + pins {:.2} MB for {count} images, {pins_n} pins = {:.0} B per image (× 100 000 = {:.1} MB)",
            images as f64 / 1e6,
            pins as f64 / 1e6,
            (images + pins) as f64 / count as f64,
            (images + pins) as f64 / count as f64 * 1e5 / 1e6
        );
    }
    let s = out("single");
    for f in [
        "images.parquet",
        "pins.parquet",
        "yield.json",
        "items.csv",
        "pins.csv",
    ] {
        let b = size(&s.join(f));
        if b > 0 {
            println!("  {f}: {:.2} MB", b as f64 / 1e6);
        }
    }
    let partials: u64 = (0..n)
        .map(|k| size(&out(&format!("shard-{k}")).join("partial.json")))
        .sum();
    println!(
        "  partial.json, all shards: {:.2} MB",
        partials as f64 / 1e6
    );
    if !keep {
        for d in std::fs::read_dir(&dir)?.flatten() {
            if d.file_name().to_string_lossy().starts_with("out-") {
                std::fs::remove_dir_all(d.path())?;
            }
        }
    }
    Ok(())
}
