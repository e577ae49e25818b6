//! Times decoding and inspection of one image (medians over repetitions).
//! cargo run --release --example time_images -- RECIPE IMAGE [N]
use pinsight::vision::{self, InspectOptions, Recipe, image_io};
use std::time::Instant;
fn main() {
    // As `pinsight inspect` and `yield` run (src/allocator.rs).
    pinsight::allocator::settle_for_a_batch();
    let a: Vec<String> = std::env::args().skip(1).collect();
    let r = Recipe::load(std::path::Path::new(&a[0])).unwrap();
    let bytes = std::fs::read(&a[1]).unwrap();
    let n: usize = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(30);
    let (mut td, mut ti) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let t0 = Instant::now();
        let (g, info) = image_io::decode_bytes(&bytes).unwrap();
        let t1 = Instant::now();
        let ins = vision::inspect_gray(&r, &g, info, &InspectOptions::default()).unwrap();
        let t2 = Instant::now();
        std::hint::black_box(ins);
        td.push((t1 - t0).as_secs_f64() * 1e3);
        ti.push((t2 - t1).as_secs_f64() * 1e3);
    }
    td.sort_by(|a, b| a.total_cmp(b));
    ti.sort_by(|a, b| a.total_cmp(b));
    println!(
        "decode {:.2} ms, inspect {:.2} ms (medians of {n})",
        td[n / 2],
        ti[n / 2]
    );
}
