//! Generates a plant-scale set of small synthetic connector images for the
//! sharding benchmark (BENCHMARKS.md, "Plant scale"): top views of the
//! 2×10 header at a coarse scale (small files, so 100 000 of them fit on a
//! modest disk), randomised pose, optics and faults as `gen_images batch`
//! does, in folders of 1 000, with the recipe (its `mm_per_px` set to the
//! scale used) beside them.
//!
//! ```sh
//! cargo run --release --example gen_plant -- N DIR [--mm-per-px 0.06] [--seed 0] [--scenes S] [--skip-existing]
//! ```
//!
//! Rendering a scene (anti-aliased tips, blur) is the slow part; with
//! `--scenes S` only S scenes are rendered and image `i` is scene `i mod S`
//! with sensor noise of its own added (σ 0.5–1.5 DN, seeded by `i`), so
//! every image is a different picture (every measurement differs by what
//! the noise moves) while poses and faults repeat every S images.
//!
//! `--skip-existing` keeps the images already there (an interrupted run
//! continued; each image is written whole, through a temporary file).
//!
//! Writes `DIR/recipe/hdr-2x10.toml` and `DIR/img/NNN/pNNNNNNN.png`;
//! nothing else (no truth files: the benchmark measures time and sizes,
//! the accuracy of the inspection is measured elsewhere, docs/vision.md).
//! Images are generated in parallel (rayon) and are a pure function of
//! their index and the seed.

use image::{DynamicImage, ImageBuffer, Luma};
use pinsight::vision::synth::{Damage, Rng, Scene};
use pinsight::vision::{GrayData, Recipe};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn png(g: &pinsight::vision::Gray) -> Vec<u8> {
    let img = match &g.data {
        GrayData::U8(d) => DynamicImage::ImageLuma8(
            ImageBuffer::<Luma<u8>, _>::from_raw(g.width, g.height, d.clone()).expect("size"),
        ),
        GrayData::U16(d) => DynamicImage::ImageLuma16(
            ImageBuffer::<Luma<u16>, _>::from_raw(g.width, g.height, d.clone()).expect("size"),
        ),
    };
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("png");
    out.into_inner()
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: gen_plant N DIR [--mm-per-px 0.06] [--seed 0]";
    let n: usize = args
        .first()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| anyhow::anyhow!(usage))?;
    let dir = PathBuf::from(args.get(1).ok_or_else(|| anyhow::anyhow!(usage))?);
    let scale: f64 = arg(&args, "--mm-per-px").map_or(Ok(0.06), |s| s.parse())?;
    let seed: u64 = arg(&args, "--seed").map_or(Ok(0), |s| s.parse())?;
    let scenes: usize = arg(&args, "--scenes").map_or(Ok(n), |s| s.parse())?;
    let skip_existing = args.iter().any(|a| a == "--skip-existing");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/images/hdr-2x10.toml");
    let mut recipe = Recipe::load(&src)?;
    recipe.mm_per_px = Some(scale);
    std::fs::create_dir_all(dir.join("recipe"))?;
    let text =
        std::fs::read_to_string(&src)?.replace("mm_per_px = 0.03", &format!("mm_per_px = {scale}"));
    std::fs::write(dir.join("recipe/hdr-2x10.toml"), text)?;
    for f in 0..n.div_ceil(1000) {
        std::fs::create_dir_all(dir.join(format!("img/{f:03}")))?;
    }
    let render = |i: usize| {
        let mut rng = Rng::new(seed.wrapping_mul(1_000_003).wrapping_add(i as u64));
        let mut sc = Scene::nominal(&recipe, scale);
        sc.randomise(&mut rng, 3.0, 8.0, 0.8);
        sc.noise_dn = rng.range(0.0, 1.5);
        sc.seed = i as u64;
        let k = (rng.uniform() * sc.pins.len() as f64) as usize % sc.pins.len();
        match (rng.uniform() * 12.0) as u32 {
            0 => sc.pins[k].present = false,
            1 => {
                let a = rng.range(0.0, std::f64::consts::TAU);
                sc.pins[k].offset_mm = (0.2 * a.cos(), 0.2 * a.sin());
            }
            2 => sc.pins[k].damage = Damage::Scaled(0.6),
            _ => {}
        }
        sc.render().0
    };
    let rendered: Vec<pinsight::vision::Gray> = if scenes < n {
        (0..scenes).into_par_iter().map(render).collect()
    } else {
        Vec::new()
    };
    let bytes: u64 = (0..n)
        .into_par_iter()
        .map(|i| {
            let file = dir.join(format!("img/{:03}/p{i:07}.png", i / 1000));
            if skip_existing && let Ok(m) = std::fs::metadata(&file) {
                return m.len();
            }
            let g = if scenes < n {
                let mut g = rendered[i % scenes].clone();
                let mut rng = Rng::new(seed ^ 0x5eed_0000_0000 ^ i as u64);
                let sigma = rng.range(0.5, 1.5);
                if let GrayData::U8(d) = &mut g.data {
                    for v in d.iter_mut() {
                        *v = (*v as f64 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8;
                    }
                }
                g
            } else {
                render(i)
            };
            let data = png(&g);
            // Whole files only: an interrupted run leaves no truncated
            // image for --skip-existing to keep.
            let tmp = file.with_extension("png.tmp");
            std::fs::write(&tmp, &data).expect("write image");
            std::fs::rename(&tmp, &file).expect("rename image");
            data.len() as u64
        })
        .sum();
    println!(
        "wrote {n} images ({:.1} MB, {:.1} kB each) into {}",
        bytes as f64 / 1e6,
        bytes as f64 / 1e3 / n.max(1) as f64,
        dir.display()
    );
    Ok(())
}
