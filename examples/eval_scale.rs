//! The scale estimate (recipes without `mm_per_px`) against the truth of a
//! folder rendered by tests/python/connector_render.py: per image the true
//! and estimated tip width, or the error.
//!
//!   cargo run --release --example eval_scale -- DIR
use pinsight::vision::{GrayData, Plane, Recipe, View, image_io, scale};
use std::path::Path;

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| ".".into());
    let mut js: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    js.sort();
    for j in js {
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&j).expect("truth")).expect("json");
        let recipe = Recipe::load(&Path::new(&dir).join(t["recipe"].as_str().unwrap_or_default()))
            .expect("recipe");
        if recipe.mm_per_px.is_some() || recipe.view != View::Top {
            continue;
        }
        let img = Path::new(&dir).join(t["image"].as_str().unwrap_or_default());
        let (g, _) = image_io::load_path(&img).expect("image");
        let fs = g.full_scale();
        let (w, h) = (g.width as usize, g.height as usize);
        let sign = recipe.polarity.sign();
        let r = match &g.data {
            GrayData::U8(d) => scale::estimate(
                &Plane {
                    w,
                    h,
                    data: d.as_slice(),
                },
                sign,
                &recipe,
                fs,
            ),
            GrayData::U16(d) => scale::estimate(
                &Plane {
                    w,
                    h,
                    data: d.as_slice(),
                },
                sign,
                &recipe,
                fs,
            ),
        };
        let truth = t["factors"]["tip_px"].as_f64().unwrap_or(f64::NAN);
        match r {
            Ok(e) => println!(
                "{} truth {truth:.2} est {:.2} ratio {:.4} support {}",
                j.display(),
                e.pin_px,
                e.pin_px / truth,
                e.support
            ),
            Err(e) => println!("{} truth {truth:.2} ERROR {e}", j.display()),
        }
    }
}
