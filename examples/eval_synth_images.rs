//! Renders random synthetic scenes for each recipe of a folder, inspects
//! them and prints verdict agreement and centre RMS error per noise level.
//! cargo run --release --example eval_synth_images -- [RECIPE_DIR] [N]
use pinsight::vision::synth::{Rng, Scene};
use pinsight::vision::{self, InspectOptions, PinStatus, Recipe, truth};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let dir = a
        .first()
        .cloned()
        .unwrap_or_else(|| "fixtures/interop/images".into());
    let n: u64 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(4);
    let mut recipes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    recipes.sort();
    for noise in [0.0, 8.0] {
        for rp in &recipes {
            let r = Recipe::load(rp).unwrap();
            let m = r.mm_per_px.unwrap_or(0.026);
            let (mut sq, mut k, mut vok, mut hmax) = (0.0, 0usize, 0, 0f64);
            let mut bad = Vec::new();
            for s in 0..n {
                let mut sc = Scene::nominal(&r, m);
                let mut rng = Rng::new(s * 31 + 7);
                sc.randomise(&mut rng, 5.0, 30.0, 1.2);
                sc.noise_dn = noise;
                sc.seed = s;
                let (g, t) = sc.render();
                let info = Default::default();
                match vision::inspect_gray(&r, &g, info, &InspectOptions::default()) {
                    Ok(ins) => {
                        let c = truth::compare(&ins, &t, 15.0);
                        if c.verdict_ok {
                            vok += 1
                        } else {
                            bad.push(format!("{s}:{:?}", c.status_mismatches))
                        }
                        for e in c.centre_errors.iter().filter(|e| e.2 == PinStatus::Ok) {
                            sq += e.3 * e.3 + e.4 * e.4;
                            k += 1;
                        }
                        for e in &c.height_errors {
                            hmax = hmax.max(e.abs());
                        }
                    }
                    Err(e) => bad.push(format!("{s}: ERR {e}")),
                }
            }
            println!(
                "noise {noise:4} {:16} verdicts {vok}/{n} rms {:.4} px over {k} pins, max |dh| {:.4} mm {}",
                r.part_number,
                (sq / k.max(1) as f64).sqrt(),
                hmax,
                bad.join(" ")
            );
        }
    }
}
