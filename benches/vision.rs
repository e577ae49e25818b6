//! Vision throughput on one core: inspection of a decoded image (pipeline
//! only) and end to end from the file's bytes (decode + inspection), for a
//! 1024 × 768 2 × 10 header (PNG) and a 2448 × 2048 (5 MP) 2 × 20 header
//! (JPEG) from the interop set, plus a 1 MP (1155 × 866) 2 × 10 render of
//! the project's generator.
//!
//!   cargo bench --bench vision
//!
//! The allocator is tuned as the batch commands tune it
//! (`pinsight::allocator::settle_for_a_batch`).
//!
//! Criterion runs on the calling thread only, so these are one-core figures.

use criterion::{Criterion, criterion_group, criterion_main};
use pinsight::vision::synth::{Rng, Scene};
use pinsight::vision::{self, InspectOptions, Recipe, image_io};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/interop/images")
        .join(name)
}

fn bench(c: &mut Criterion) {
    // The C allocator as `pinsight inspect` and `yield` set it (no page
    // faults per image from a heap trimmed and grown again).
    pinsight::allocator::settle_for_a_batch();
    let opts = InspectOptions::default();
    let mut g = c.benchmark_group("vision");
    g.sample_size(30).measurement_time(Duration::from_secs(6));
    for (label, recipe, image) in [
        ("2x10_1024x768_png", "hdr-2x10.toml", "h2x10-02.png"),
        ("2x20_5mp_jpeg", "hdr-2x20.toml", "h2x20-01.jpg"),
    ] {
        let r = Recipe::load(&fixture(recipe)).unwrap();
        let bytes = std::fs::read(fixture(image)).unwrap();
        let (gray, info) = image_io::decode_bytes(&bytes).unwrap();
        g.bench_function(format!("inspect/{label}"), |b| {
            b.iter(|| vision::inspect_gray(&r, black_box(&gray), info.clone(), &opts).unwrap())
        });
        g.bench_function(format!("decode_and_inspect/{label}"), |b| {
            b.iter(|| vision::inspect_bytes(&r, black_box(&bytes), &opts).unwrap())
        });
        g.bench_function(format!("decode/{label}"), |b| {
            b.iter(|| image_io::decode_bytes(black_box(&bytes)).unwrap())
        });
    }
    // A true 1 MP frame of a 2 × 10 header from the generator (noise 2 DN).
    let r = Recipe::load(&fixture("hdr-2x10.toml")).unwrap();
    let mut sc = Scene::nominal(&r, 0.03);
    sc.width = 1155;
    sc.height = 866;
    sc.centre_px = (577.0, 433.0);
    sc.randomise(&mut Rng::new(3), 4.0, 30.0, 1.0);
    sc.noise_dn = 2.0;
    let (gray, _) = sc.render();
    g.bench_function("inspect/2x10_1mp_synthetic", |b| {
        b.iter(|| vision::inspect_gray(&r, black_box(&gray), Default::default(), &opts).unwrap())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: criterion's plotters backend needs system fonts (pitfalls.md).
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
