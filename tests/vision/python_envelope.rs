//! Verdict accuracy on images from an independent renderer:
//! `tests/python/connector_render.py` (numpy/OpenCV/Pillow, its own
//! optics: pillbox and mixed PSFs, bevelled tips with a glint, polynomial
//! vignetting, Poisson-Gaussian noise, OpenCV/Pillow JPEG) draws every
//! factor of the envelope at once, with exact truth in the spec's format.
//! Nothing in pinsight was tuned on these seeds (700 000 …): a guard
//! against tuning to our own generator.
//!
//! The floors are a ratchet at the level measured when the test landed
//! (2026-11-26, figures beside the constants at the end), less a small margin;
//! the 1000-image held-out figures (seeds 500 020 – 501 019) and the OpenCV
//! baseline's on the same images are in docs/vision.md, from
//! `python3 tests/python/vision_crosscheck.py DIR`.

use pinsight::vision::{self, InspectOptions, PinStatus, Recipe, truth};
use std::path::{Path, PathBuf};
use std::process::Command;

const FIRST: u64 = 700_000;
const N: u64 = 60;

#[test]
fn verdicts_hold_on_an_independent_renderers_images() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyenv-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    let st = Command::new("python3")
        .arg(root.join("tests/python/connector_render.py"))
        .arg(&dir)
        .arg(FIRST.to_string())
        .arg(N.to_string())
        .status()
        .expect(
            "python3 with numpy, opencv-python-headless and Pillow (.ci/python-requirements.txt)",
        );
    assert!(st.success(), "the Python renderer failed");
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("rendered dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    assert_eq!(jsons.len() as u64, N, "one truth file per image");
    let (mut right, mut errors, mut pins, mut pins_wrong) = (0usize, 0usize, 0usize, 0usize);
    let mut ok_err = Vec::new();
    for j in &jsons {
        let text = std::fs::read_to_string(j).expect("truth");
        let t = truth::Truth::from_json(&text).expect("truth in the spec's format");
        let v: serde_json::Value = serde_json::from_str(&text).expect("json");
        let recipe = Recipe::load(&dir.join(&t.recipe)).expect("recipe");
        let img = dir.join(v["image"].as_str().expect("image name"));
        pins += t.pins.len();
        match vision::inspect_path(&recipe, &img, &InspectOptions::default()) {
            Err(e) => {
                eprintln!("{}: ERROR {e}", img.display());
                errors += 1;
                pins_wrong += t.pins.len();
            }
            Ok(ins) => {
                let c = truth::compare(&ins, &t, 15.0);
                if c.verdict_ok {
                    right += 1;
                } else {
                    eprintln!("{}: wrong verdict {:?}", img.display(), ins.verdict);
                }
                pins_wrong += c.status_mismatches.len();
                ok_err.extend(
                    c.centre_errors
                        .iter()
                        .filter(|e| e.2 == PinStatus::Ok)
                        .map(|e| e.3.hypot(e.4)),
                );
            }
        }
    }
    ok_err.sort_by(|a, b| a.total_cmp(b));
    let median = ok_err[ok_err.len() / 2];
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    eprintln!(
        "{N} images: verdicts right {right} ({:.1} %), errors {errors}, pin statuses right {:.2} %, ok-pin centre error median {median:.3} px",
        pct(right, N as usize),
        pct(pins - pins_wrong, pins)
    );
    assert!(
        pct(right, N as usize) >= FLOOR_VERDICTS,
        "verdicts right {:.1} %",
        pct(right, N as usize)
    );
    assert!(
        pct(pins - pins_wrong, pins) >= FLOOR_PINS,
        "pin statuses right {:.2} %",
        pct(pins - pins_wrong, pins)
    );
    assert_eq!(errors, 0, "{errors} images ended as errors");
    assert!(
        median <= MAX_MEDIAN_PX,
        "ok-pin centre error median {median:.3} px"
    );
}

// Measured 2026-11-26 on these 60: 59 right (98.3 %), 1 error (a side
// view whose housing edge was not measurable between the pins), pin
// statuses 98.49 %, ok-pin centre error median 0.062 px. Measured again
// 2026-12-05: 60 right (100 %), no error, pin statuses 99.88 %, median
// 0.072 px; the floors raised to one image and 0.3 % of pins below that
// (the median's bound kept at 0.075 px: it rose from 0.062 to 0.072 px
// over the rounds since, a cause not traced to one change).
const FLOOR_VERDICTS: f64 = 98.3;
const FLOOR_PINS: f64 = 99.55;
const MAX_MEDIAN_PX: f64 = 0.075;

/// Large tips without `mm_per_px`: the scale search used to lock onto a
/// lattice of tip fragments at a fifth of the tip width (rim slivers and
/// glints a narrow top-hat leaves of a 27–37 px round tip) and the image
/// became a `no_pins` error. Seed 600 123 (tuning set, 3 × 2, 37 px) is the
/// case that located the bug, 920 025 (3 × 2, 27 px, colour) one of the
/// held-out images it fixed (docs/vision.md, "Estimated scale").
#[test]
fn large_tips_are_scaled_by_their_own_lattice() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyscale-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    // A sub-harmonic lock is 70–80 % off; with 6 pins, each up to 0.8 of
    // the position band off its node, the fitted scale is within about
    // 1 % (measured: −0.48 % and +0.95 %).
    for seed in [600_123u64, 920_025] {
        scale_found_and_verdict_right(&dir, seed);
    }
}

/// Renders `seed` (its recipe without `mm_per_px`) and asserts the
/// inspection estimated the scale within 2 % of the renderer's and got the
/// verdict right.
fn scale_found_and_verdict_right(dir: &Path, seed: u64) {
    let (recipe, t, v, img) = render_seed(dir, seed);
    assert!(
        recipe.mm_per_px.is_none(),
        "{seed}: the scale is to be found"
    );
    let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
        .unwrap_or_else(|e| panic!("{seed}: {e}"));
    let want = v["mm_per_px"].as_f64().expect("true scale");
    let got = ins.grid.mm_per_px;
    assert!(
        ins.grid.mm_per_px_estimated && (got / want - 1.0).abs() < 0.02,
        "{seed}: mm_per_px {got} against {want}"
    );
    let c = truth::compare(&ins, &t, 15.0);
    assert!(c.verdict_ok, "{seed}: {:?}", c.status_mismatches);
}

/// Python seed 720 190 (a held-out seed): a dark 1 × 18, 18 px tips, on a
/// bright housing 2.4 tips tall over a dark fixture, scale given. As for
/// 590 370 below, the tips vanished from the top-hat; but 6 blobs of the
/// fixture's texture passed as tips, so the last passes were never tried,
/// and those blobs made an error ("3 pins lie on the grid but outside the
/// recipe's 1 × 18 positions"). Tips of which no two stand a pitch apart
/// now send the search to the last passes too (`top_candidates::last_passes`).
#[test]
fn texture_taken_for_tips_gives_way_to_the_tips_the_last_pass_finds() {
    every_status_right_at_the_given_scale(720_190, "pinsight-pytexture-");
}

/// Dark round tips (35 px) on a white one-row housing about 2.5 tips tall,
/// on a fixture darker than the tips, scale not given (seed 590 370, a
/// tuning seed since 2026-12-02). The coarse search's background closing,
/// wider than the housing, filled the whole band to the fixture's level,
/// no tip stood in the top-hat, and the image was a `no_pins` error ("no
/// tip-sized dark blob found"). The last pass bounds the closing to a
/// clearance hole's reach (`detect::Smoothing::HoleReach`): every pin is
/// found and the verdict, every pin's status and the scale match the
/// renderer's truth.
#[test]
fn dark_tips_on_a_narrow_housing_over_a_black_fixture_are_found() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyband-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    let seed = 590_370u64;
    let (recipe, t, v, img) = render_seed(&dir, seed);
    let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
        .unwrap_or_else(|e| panic!("{seed}: {e}"));
    let c = truth::compare(&ins, &t, 15.0);
    assert!(c.verdict_ok, "{seed}: {:?}", c.status_mismatches);
    assert!(c.status_mismatches.is_empty(), "{:?}", c.status_mismatches);
    let want = v["mm_per_px"].as_f64().expect("true scale");
    assert!(
        (ins.grid.mm_per_px / want - 1.0).abs() < 0.02,
        "mm_per_px {} against {want}",
        ins.grid.mm_per_px
    );
}

/// A bright 1 × 2 part with one pin bent, `mm_per_px` given (590 360, the
/// renderer's seed; 40 px tips, noise σ 9.6 DN, vignetting 0.48): two
/// pins fit the grid's rotation and centre exactly, so only the housing's
/// outline can show the bend, and one pixel's step of its edge was lost
/// in the noise on most profiles. Every pin's status must match the
/// renderer's truth.
#[test]
fn a_bent_pin_of_two_is_placed_by_the_housing_under_noise() {
    every_status_right_at_the_given_scale(590_360, "pinsight-pybent2-");
}

/// Renders `seed` into a temporary directory named from `prefix` (removed
/// when it drops, on a failed assertion too) and asserts that its recipe
/// gives the scale and that the verdict and every pin's status match the
/// renderer's truth.
fn every_status_right_at_the_given_scale(seed: u64, prefix: &str) {
    let tmp = tempfile::Builder::new()
        .prefix(prefix)
        .tempdir()
        .expect("temp dir");
    let (recipe, t, _v, img) = render_seed(tmp.path(), seed);
    assert!(recipe.mm_per_px.is_some(), "{seed}: the scale is given");
    let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
        .unwrap_or_else(|e| panic!("{seed}: {e}"));
    let c = truth::compare(&ins, &t, 15.0);
    assert!(c.verdict_ok, "{seed}: {:?}", c.status_mismatches);
    assert!(c.status_mismatches.is_empty(), "{:?}", c.status_mismatches);
}

/// Debris on a bright fixture is told from the fixture's own texture by how
/// far it rises above that texture at its own scale, not above the pixel
/// noise. 590 341 (bright, contrast 0.36, texture 5.3 DN, JPEG quality 63,
/// 48 px tips) holds no debris; a texture clump below the housing stands
/// 4.6 σ of the fixture's residual and was taken for debris when the seeds
/// began at 4 σ. 620 154 holds one piece on the fixture, 7.2 σ: still
/// found. Both verdicts and the extras must match the renderer's truth.
#[test]
fn a_texture_clump_on_a_bright_fixture_is_no_debris_but_debris_there_is() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyfixture-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    for (seed, debris) in [(590_341u64, 0usize), (620_154, 1)] {
        let (recipe, t, _v, img) = render_seed(&dir, seed);
        let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
            .unwrap_or_else(|e| panic!("{seed}: {e}"));
        let c = truth::compare(&ins, &t, 15.0);
        assert_eq!(t.extras.len(), debris, "{seed}: the renderer's debris");
        assert_eq!(
            (c.extras_found, c.extras_spurious),
            (debris, 0),
            "{seed}: extras {:?}",
            ins.extras
        );
        assert!(c.verdict_ok, "{seed}: {:?}", c.status_mismatches);
    }
}

/// Large tips (43–45 px) at contrast 0.33–0.40 on a fixture whose texture
/// is blotchy at the tips' own scale, scale not given (tuning seeds
/// 650 365 and 650 388 since 2026-12-03). That texture lifts the coarse
/// top-hat's noise floor (6 σ of the whole image's) to the tips' peak:
/// only their cores cleared it, a tenth to a third of a tip, so the scale
/// search fitted no width to them or the wrong one ("no tip-sized blobs in
/// a row", "fewer than two pins"), and the inspection at the right scale
/// found no tip whole in its window. The scale's last pass searches
/// narrower than the width it scores with blobs grown to half their peak
/// (`detect::at_half_peak`), and so do the inspection's last passes.
/// Seed 590 094 (41 px tips at contrast 0.32, a tuning seed since
/// 2026-12-03) found its tips' cores at their own width and a texture
/// lattice at 10 px too, which won ("7 pins outside the recipe's
/// positions"); the usual passes now grow cores at large widths. No
/// error, the scale within 2 % and the verdict must match the renderer's
/// truth.
#[test]
fn large_tips_on_texture_at_their_own_scale_are_found() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyblotch-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    for seed in [650_365u64, 650_388, 590_094] {
        scale_found_and_verdict_right(&dir, seed);
    }
}

/// Debris on a dark part's fixture, and the fixture's texture that is no
/// debris. 590 171 (dark 1 × 17, the fixture at the housing's level, noise
/// σ 15.8 DN) holds debris 6 tips from the row that was measured "inside the
/// housing" and refused at 0.49 of the tip level; 620 290 (dark 1 × 12 on a
/// black fixture, 48 px tips) holds debris across the housing's edge, a
/// shoulder of the fixture set aside as part of a larger structure; both
/// passed with no extra. 590 079 and 650 307 (dark parts on dark textured
/// fixtures) hold none: a texture clump beside the housing's edge stands
/// 5.1–5.5 σ of the whole fixture's residual but under 4.5 σ of its own
/// neighbourhood's. Verdicts and extras must match the renderer's truth;
/// 620 290's reported centre lies on the debris' protruding part, about a
/// tip from the truth's area centroid, so its match radius is 1.5 tips.
#[test]
fn debris_on_a_dark_parts_fixture_is_found_and_its_texture_is_not() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pydarkfix-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path().to_path_buf();
    for (seed, debris) in [
        (590_171u64, 1usize),
        (620_290, 1),
        (590_079, 0),
        (650_307, 0),
    ] {
        let (recipe, t, v, img) = render_seed(&dir, seed);
        assert_eq!(v["factors"]["polarity"], "dark", "{seed}");
        assert_eq!(t.extras.len(), debris, "{seed}: the renderer's debris");
        let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
            .unwrap_or_else(|e| panic!("{seed}: {e}"));
        let tip = v["factors"]["tip_px"].as_f64().expect("tip_px");
        let c = truth::compare(&ins, &t, 15.0_f64.max(1.5 * tip));
        assert_eq!(
            (c.extras_found, c.extras_spurious),
            (debris, 0),
            "{seed}: extras {:?}",
            ins.extras
        );
        assert!(c.verdict_ok, "{seed}: {:?}", c.status_mismatches);
    }
}

/// Renders one seed with the Python renderer into `dir`: its recipe, truth,
/// truth as JSON and image path.
fn render_seed(dir: &Path, seed: u64) -> (Recipe, truth::Truth, serde_json::Value, PathBuf) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let st = Command::new("python3")
        .arg(root.join("tests/python/connector_render.py"))
        .arg(dir)
        .arg(seed.to_string())
        .arg("1")
        .status()
        .expect("python3 with numpy, opencv-python-headless and Pillow");
    assert!(st.success(), "the Python renderer failed");
    let text = std::fs::read_to_string(dir.join(format!("py-{seed:06}.json"))).expect("truth");
    let t = truth::Truth::from_json(&text).expect("truth");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let recipe = Recipe::load(&dir.join(&t.recipe)).expect("recipe");
    let img = dir.join(v["image"].as_str().expect("image name"));
    (recipe, t, v, img)
}

/// 590 268 (an independent renderer's 1 × 9 part whose last tip is
/// damaged, too small to place the grid, 13 px tips blurred by 1.2 px,
/// scale not given): the housing's blurred edge was read below its height,
/// "not found", and the grid centred on the eight pins found stood a pitch
/// off: the right verdict with four pin statuses wrong and every ok centre
/// 50 px out. The edge's height is now read across the blur
/// (`vision::housing`). 690 300 (a good 1 × 14 on a blotchy fixture): on
/// the lines where the housing's edge is faint, that height found the
/// texture's steps beyond it; taken with the sharp lines they moved the
/// edge 1.3 pitches out and a blotch became debris by the housing, so the
/// height decides only a side where no line finds a sharp edge. Every pin
/// status and the verdict must match the renderer's truth, with no extra
/// that is not there.
#[test]
fn a_blurred_housing_edge_places_a_part_and_texture_beyond_it_does_not() {
    // Removed when `tmp` drops, on a failed assertion too.
    let tmp = tempfile::Builder::new()
        .prefix("pinsight-pyhousing-")
        .tempdir()
        .expect("temp dir");
    for seed in [590_268u64, 690_300] {
        let (recipe, t, _, img) = render_seed(tmp.path(), seed);
        let ins = vision::inspect_path(&recipe, &img, &InspectOptions::default())
            .unwrap_or_else(|e| panic!("{seed}: {e}"));
        let c = truth::compare(&ins, &t, 15.0);
        assert!(c.verdict_ok, "{seed}: verdict wrong");
        assert!(
            c.status_mismatches.is_empty(),
            "{seed}: {:?}",
            c.status_mismatches
        );
        assert_eq!(c.extras_spurious, 0, "{seed}: {:?}", ins.extras);
    }
}
