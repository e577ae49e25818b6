//! Generates synthetic connector images with exact ground truth
//! (`pinsight::vision::synth`).
//!
//!   cargo run --release --example gen_images                 # fixtures/vision (the test set)
//!   cargo run --release --example gen_images -- batch N DIR  # N varied 2×10 images (1024×768) for benchmarks
//!
//! Each image `NAME.<ext>` gets `NAME.json` beside it in the format of
//! spec/vision.md; the recipes used are copied next to them.

use image::{DynamicImage, ImageBuffer, Luma, Rgb};
use pinsight::vision::synth::{Damage, Rng, Scene, SceneExtra};
use pinsight::vision::{GrayData, Recipe, Verdict, truth::Truth};
use std::path::{Path, PathBuf};

fn interop_recipe(name: &str) -> Recipe {
    Recipe::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures/interop/images")
            .join(name),
    )
    .expect("recipe")
}

fn to_dynamic(g: &pinsight::vision::Gray) -> DynamicImage {
    match &g.data {
        GrayData::U8(d) => DynamicImage::ImageLuma8(
            ImageBuffer::<Luma<u8>, _>::from_raw(g.width, g.height, d.clone()).expect("size"),
        ),
        GrayData::U16(d) => DynamicImage::ImageLuma16(
            ImageBuffer::<Luma<u16>, _>::from_raw(g.width, g.height, d.clone()).expect("size"),
        ),
    }
}

enum Format {
    Png,
    PngRgb,
    Bmp,
    Tiff,
    Jpeg(u8),
}

fn save(
    dir: &Path,
    name: &str,
    recipe_file: &str,
    scene: &Scene,
    fmt: Format,
    truth_fix: impl Fn(&mut Truth),
) {
    let (g, mut t) = scene.render();
    t.recipe = recipe_file.to_string();
    truth_fix(&mut t);
    let img = to_dynamic(&g);
    let (ext, img) = match fmt {
        Format::Png => ("png", img),
        Format::PngRgb => {
            let l = img.to_luma8();
            // Grey values in an RGB container (luma of (v, v, v) is v).
            let rgb = ImageBuffer::from_fn(l.width(), l.height(), |x, y| {
                let v = l.get_pixel(x, y).0[0];
                Rgb([v, v, v])
            });
            ("png", DynamicImage::ImageRgb8(rgb))
        }
        Format::Bmp => ("bmp", DynamicImage::ImageLuma8(img.to_luma8())),
        Format::Tiff => ("tif", img),
        Format::Jpeg(q) => {
            let p = dir.join(format!("{name}.jpg"));
            let f = std::fs::File::create(&p).expect("create");
            let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(f, q);
            enc.encode_image(&DynamicImage::ImageLuma8(img.to_luma8()))
                .expect("jpeg");
            std::fs::write(
                dir.join(format!("{name}.json")),
                serde_json::to_vec_pretty(&t).expect("json"),
            )
            .expect("write");
            return;
        }
    };
    img.save(dir.join(format!("{name}.{ext}"))).expect("save");
    std::fs::write(
        dir.join(format!("{name}.json")),
        serde_json::to_vec_pretty(&t).expect("json"),
    )
    .expect("write");
}

fn fixtures(dir: &Path) {
    std::fs::create_dir_all(dir).expect("dir");
    for r in [
        "hdr-2x10.toml",
        "rnd-1x8.toml",
        "hdr-2x5-dark.toml",
        "hdr-2x8-auto.toml",
        "side-1x6.toml",
    ] {
        std::fs::copy(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("fixtures/interop/images")
                .join(r),
            dir.join(r),
        )
        .expect("copy recipe");
    }
    let hdr = interop_recipe("hdr-2x10.toml");
    // σ = 8 DN noise, random pose, one defect each.
    for i in 0..3u64 {
        let mut sc = Scene::nominal(&hdr, 0.03);
        sc.randomise(&mut Rng::new(500 + i), 5.0, 25.0, 1.2);
        sc.noise_dn = 8.0;
        sc.seed = 600 + i;
        match i {
            0 => sc.pins[4].offset_mm = (-0.12, 0.09),
            1 => sc.pins[13].damage = Damage::Scaled(0.7),
            _ => sc.extras.push(SceneExtra {
                u_mm: -3.81,
                v_mm: 0.0,
                r_mm: 0.22,
                opacity: 1.0,
            }),
        }
        save(
            dir,
            &format!("syn-2x10-noise8-{i:02}"),
            "hdr-2x10.toml",
            &sc,
            Format::Png,
            |_| {},
        );
    }
    // A whole end column missing: the housing places the grid.
    let mut sc = Scene::nominal(&hdr, 0.03);
    sc.randomise(&mut Rng::new(11), 4.0, 20.0, 0.8);
    sc.noise_dn = 2.0;
    for p in sc.pins.iter_mut().filter(|p| p.col == 9) {
        p.present = false;
    }
    save(
        dir,
        "syn-2x10-endcol",
        "hdr-2x10.toml",
        &sc,
        Format::Png,
        |_| {},
    );
    // Every damage kind and a near-tolerance ok pin, colour container.
    let mut sc = Scene::nominal(&hdr, 0.03);
    sc.randomise(&mut Rng::new(12), 3.0, 20.0, 0.9);
    sc.noise_dn = 3.0;
    sc.pins[1].damage = Damage::Scaled(0.68);
    sc.pins[3].damage = Damage::Scaled(1.33);
    sc.pins[5].damage = Damage::Chipped(0.45);
    sc.pins[12].damage = Damage::Burr(0.55);
    sc.pins[15].offset_mm = (0.0, 0.08);
    save(
        dir,
        "syn-2x10-damage-rgb",
        "hdr-2x10.toml",
        &sc,
        Format::PngRgb,
        |_| {},
    );
    // BMP and JPEG (truth is that of the render before compression).
    let mut sc = Scene::nominal(&hdr, 0.03);
    sc.randomise(&mut Rng::new(13), 5.0, 25.0, 1.0);
    sc.noise_dn = 1.5;
    save(dir, "syn-2x10", "hdr-2x10.toml", &sc, Format::Bmp, |_| {});
    sc.seed = 14;
    sc.pins[8].offset_mm = (0.2, 0.0);
    save(
        dir,
        "syn-2x10-q85",
        "hdr-2x10.toml",
        &sc,
        Format::Jpeg(85),
        |_| {},
    );
    // One-row round pins: end pin missing; 16-bit TIFF.
    let rnd = interop_recipe("rnd-1x8.toml");
    let mut sc = Scene::nominal(&rnd, 0.025);
    sc.randomise(&mut Rng::new(15), 3.0, 15.0, 0.8);
    sc.noise_dn = 2.0;
    sc.pins[0].present = false;
    sc.sixteen_bit = true;
    save(
        dir,
        "syn-1x8-endpin",
        "rnd-1x8.toml",
        &sc,
        Format::Tiff,
        |_| {},
    );
    // Dark polarity, 16-bit PNG, a missing pin and a bent one.
    let dark = interop_recipe("hdr-2x5-dark.toml");
    let mut sc = Scene::nominal(&dark, 0.03);
    sc.randomise(&mut Rng::new(16), 4.0, 20.0, 1.0);
    sc.sixteen_bit = true;
    sc.noise_dn = 4.0;
    sc.pins[3].present = false;
    sc.pins[6].offset_mm = (0.0, -0.15);
    save(
        dir,
        "syn-2x5-dark-16bit",
        "hdr-2x5-dark.toml",
        &sc,
        Format::Png,
        |_| {},
    );
    // Scale estimated from the pitch.
    let auto = interop_recipe("hdr-2x8-auto.toml");
    let mut sc = Scene::nominal(&auto, 0.0265);
    sc.randomise(&mut Rng::new(17), 5.0, 20.0, 1.0);
    sc.noise_dn = 3.0;
    save(
        dir,
        "syn-2x8-auto",
        "hdr-2x8-auto.toml",
        &sc,
        Format::Png,
        |_| {},
    );
    // Side view: end pin missing, a short and a high pin, dust, σ = 8.
    let side = interop_recipe("side-1x6.toml");
    let mut sc = Scene::nominal(&side, 0.025);
    sc.randomise(&mut Rng::new(18), 2.0, 15.0, 1.0);
    sc.noise_dn = 8.0;
    sc.pins[5].present = false;
    sc.pins[1].height_mm = 2.3;
    sc.pins[3].height_mm = 2.75;
    sc.extras.push(SceneExtra {
        u_mm: -3.0,
        v_mm: -4.2,
        r_mm: 0.22,
        opacity: 0.75,
    });
    save(
        dir,
        "syn-side-1x6",
        "side-1x6.toml",
        &sc,
        Format::Png,
        |_| {},
    );
    println!("wrote fixtures into {}", dir.display());
}

/// N varied 1024 × 768 2×10 images, about a third with one defect.
fn batch(n: usize, dir: &Path) {
    std::fs::create_dir_all(dir).expect("dir");
    let hdr = interop_recipe("hdr-2x10.toml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/images/hdr-2x10.toml"),
        dir.join("hdr-2x10.toml"),
    )
    .expect("copy");
    let mut passed = 0;
    for i in 0..n {
        let mut rng = Rng::new(10_000 + i as u64);
        let mut sc = Scene::nominal(&hdr, 0.03);
        sc.width = 1024;
        sc.height = 768;
        sc.centre_px = (512.0, 384.0);
        sc.randomise(&mut rng, 5.0, 40.0, 1.2);
        sc.noise_dn = rng.range(0.0, 3.0);
        sc.seed = i as u64;
        let k = (rng.uniform() * sc.pins.len() as f64) as usize % sc.pins.len();
        match (rng.uniform() * 9.0) as u32 {
            0 => sc.pins[k].present = false,
            1 => {
                let a = rng.range(0.0, std::f64::consts::TAU);
                sc.pins[k].offset_mm = (0.2 * a.cos(), 0.2 * a.sin());
            }
            2 => sc.pins[k].damage = Damage::Scaled(0.65),
            _ => {}
        }
        let (g, mut t) = sc.render();
        t.recipe = "hdr-2x10.toml".into();
        if t.verdict == Verdict::Pass {
            passed += 1;
        }
        let name: PathBuf = dir.join(format!("b{i:05}.png"));
        to_dynamic(&g).save(&name).expect("save");
        std::fs::write(
            name.with_extension("json"),
            serde_json::to_vec(&t).expect("json"),
        )
        .expect("write");
    }
    println!(
        "wrote {n} images into {} ({passed} pass by truth)",
        dir.display()
    );
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.first().map(|s| s.as_str()) == Some("batch") {
        let n = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
        let dir = a
            .get(2)
            .cloned()
            .unwrap_or_else(|| "/tmp/pinsight-batch".into());
        batch(n, Path::new(&dir));
    } else {
        let dir = a
            .first()
            .cloned()
            .unwrap_or_else(|| format!("{}/fixtures/vision", env!("CARGO_MANIFEST_DIR")));
        fixtures(Path::new(&dir));
    }
}
