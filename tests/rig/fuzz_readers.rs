//! Byte-level fuzzing of every reader of outside files (issue 14): the MCAP
//! reader, the image decoder (and the inspection behind it), and the TOML
//! loaders (parameter file, channel map, recipe, study grid, methods
//! scenes, batch script). Each target mutates a seed corpus taken from
//! `fixtures/` (bit flips, interesting bytes, length fields set huge,
//! deleted, duplicated and inserted ranges, truncation, splices of two
//! seeds, and for text: numbers swapped for hostile ones) and feeds the
//! mutant to the reader. A mutant must give a value or an error, never a
//! panic, and no single input may take more than [`SLOW`].
//!
//! Each target runs for `PINSIGHT_FUZZ_SECS` seconds (3 by default, so CI
//! stays short; docs/reliability.md records the 600-second runs) from
//! `PINSIGHT_FUZZ_SEED`. The mutator is written here rather than taken
//! from `cargo fuzz`, which needs a nightly compiler that CI does not have;
//! it is a plain generator, so a failing input is written to
//! `target/fuzz-failures/` to be replayed.

use crate::common;
use common::Rng;
use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::rig::channel_map::ChannelMap;
use pinsight::rig::mcap_read::Source;
use pinsight::rig::{LoadOptions, load_source};
use pinsight::vision::{InspectOptions, Recipe};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The longest one input may take before the run counts as a hang.
const SLOW: Duration = Duration::from_secs(20);

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(fixtures().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn budget() -> Duration {
    let s: f64 = std::env::var("PINSIGHT_FUZZ_SECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3.0);
    Duration::from_secs_f64(s)
}

fn seed() -> u64 {
    std::env::var("PINSIGHT_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x0BAD_5EED_1234_5678)
}

const INTERESTING: &[u8] = &[
    0, 1, 0x7f, 0x80, 0xff, b'"', b'[', b']', b'=', b'\n', b'9', b'-', b'e', b'.', b'{', b'#',
];
const HOSTILE_NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "99999999999999999999",
    "-9223372036854775808",
    "0x7fffffff",
    "1_000_000_000",
    "[]",
    "[[]]",
    "\"\"",
];

/// One mutant of `seed` (another seed of the corpus may be spliced in).
fn mutate(rng: &mut Rng, corpus: &[Vec<u8>], text: bool) -> Vec<u8> {
    let mut b = corpus[rng.below(corpus.len())].clone();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let n = b.len();
        match rng.below(if text { 10 } else { 9 }) {
            0 if n > 0 => {
                let i = rng.below(n);
                b[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                b[i] = INTERESTING[rng.below(INTERESTING.len())];
            }
            2 if n > 8 => {
                // A length or count field set to something huge or zero.
                let i = rng.below(n - 8);
                let v: u64 = match rng.below(4) {
                    0 => u64::MAX,
                    1 => 0,
                    2 => u32::MAX as u64,
                    _ => rng.next() >> rng.below(64),
                };
                let w = if rng.below(2) == 0 { 4 } else { 8 };
                b[i..i + w].copy_from_slice(&v.to_le_bytes()[..w]);
            }
            3 if n > 0 => {
                let i = rng.below(n);
                let len = 1 + rng.below((n - i).min(256));
                b.drain(i..i + len);
            }
            4 if n > 0 => {
                let i = rng.below(n);
                let len = 1 + rng.below((n - i).min(256));
                let chunk: Vec<u8> = b[i..i + len].to_vec();
                let at = rng.below(n + 1);
                b.splice(at..at, chunk);
            }
            5 => {
                let at = rng.below(n + 1);
                let len = 1 + rng.below(32);
                let junk: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
                b.splice(at..at, junk);
            }
            6 if n > 0 => b.truncate(rng.below(n)),
            7 => {
                let other = &corpus[rng.below(corpus.len())];
                if !other.is_empty() && n > 0 {
                    let at = rng.below(n);
                    let from = rng.below(other.len());
                    b.truncate(at);
                    b.extend_from_slice(&other[from..]);
                }
            }
            8 if n > 0 => {
                // Many flips at once (a damaged sector).
                for _ in 0..1 + rng.below(64) {
                    let i = rng.below(n);
                    b[i] = rng.next() as u8;
                }
            }
            9 => {
                // Text: a number (or a value) swapped for a hostile one.
                let s = String::from_utf8_lossy(&b).into_owned();
                let starts: Vec<usize> = s
                    .char_indices()
                    .filter(|(i, c)| {
                        c.is_ascii_digit()
                            && (*i == 0 || !s.as_bytes()[i - 1].is_ascii_alphanumeric())
                    })
                    .map(|(i, _)| i)
                    .collect();
                if !starts.is_empty() {
                    let i = starts[rng.below(starts.len())];
                    let end = s[i..]
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
                        .map_or(s.len(), |e| i + e);
                    let repl = HOSTILE_NUMBERS[rng.below(HOSTILE_NUMBERS.len())];
                    b = format!("{}{}{}", &s[..i], repl, &s[end..]).into_bytes();
                }
            }
            _ => {}
        }
    }
    b
}

/// Runs `target` on mutants of `corpus` for the budget; returns the number
/// of inputs and of those the target accepted.
fn fuzz(
    name: &str,
    corpus: Vec<Vec<u8>>,
    text: bool,
    mut target: impl FnMut(&[u8]) -> bool,
) -> (usize, usize) {
    assert!(!corpus.is_empty());
    let mut rng = Rng(seed() ^ name.bytes().fold(0u64, |h, c| h.rotate_left(5) ^ c as u64) | 1);
    let start = Instant::now();
    let (mut n, mut accepted) = (0, 0);
    let mut slowest = Duration::ZERO;
    // The seeds themselves first: they must be accepted.
    for (i, s) in corpus.iter().enumerate() {
        assert!(target(s), "{name}: seed {i} of the corpus is refused");
    }
    while start.elapsed() < budget() || n < 20 {
        let input = mutate(&mut rng, &corpus, text);
        let t0 = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| target(&input)));
        let dt = t0.elapsed();
        slowest = slowest.max(dt);
        n += 1;
        let failure = match r {
            Err(_) => Some("panicked"),
            Ok(_) if dt > SLOW => Some("too slow"),
            Ok(ok) => {
                accepted += usize::from(ok);
                None
            }
        };
        if let Some(why) = failure {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-failures");
            let _ = std::fs::create_dir_all(&dir);
            let file = dir.join(format!("{name}-{n}.bin"));
            let _ = std::fs::write(&file, &input);
            panic!(
                "{name}: input {n} {why} ({:.1} s); written to {}",
                dt.as_secs_f64(),
                file.display()
            );
        }
    }
    println!(
        "{name}: {n} inputs in {:.1} s, {accepted} accepted, slowest {:.0} ms (seed {})",
        start.elapsed().as_secs_f64(),
        slowest.as_secs_f64() * 1e3,
        seed()
    );
    (n, accepted)
}

#[test]
fn mcap_reader() {
    let corpus = vec![
        read("logs/synth-1800-ripple-dropouts-blocks.mcap"),
        read("interop/logs/run-1200-blocks.mcap"),
        read("interop/logs/run-1800-noforce.mcap"),
    ];
    let (n, _) = fuzz("mcap", corpus, false, |b| {
        let src = Source::from_vec("fuzz.mcap", b.to_vec());
        // A damaged log loads what it can with findings, or is an error.
        load_source(&src, &LoadOptions::default(), &Progress::hidden()).is_ok()
    });
    assert!(n >= 20);
}

/// Small encoded images in every format the decoder reads, so mutations
/// land in headers as often as in pixels.
fn image_corpus() -> Vec<Vec<u8>> {
    use image::{DynamicImage, ImageFormat, Luma, Rgb};
    let mut out = Vec::new();
    let grey = image::ImageBuffer::from_fn(48, 40, |x, y| Luma([((x * 5 + y * 3) % 256) as u8]));
    let rgb = image::ImageBuffer::from_fn(40, 32, |x, y| Rgb([(x * 6) as u8, (y * 7) as u8, 90]));
    let g16 = image::ImageBuffer::from_fn(32, 32, |x, y| Luma([(x * 2000 + y * 17) as u16]));
    for (img, fmts) in [
        (
            DynamicImage::ImageLuma8(grey),
            &[
                ImageFormat::Png,
                ImageFormat::Jpeg,
                ImageFormat::Bmp,
                ImageFormat::Tiff,
            ][..],
        ),
        (
            DynamicImage::ImageRgb8(rgb),
            &[ImageFormat::Png, ImageFormat::Jpeg, ImageFormat::Tiff][..],
        ),
        (
            DynamicImage::ImageLuma16(g16),
            &[ImageFormat::Png, ImageFormat::Tiff][..],
        ),
    ] {
        for f in fmts {
            let mut c = std::io::Cursor::new(Vec::new());
            img.write_to(&mut c, *f).unwrap();
            out.push(c.into_inner());
        }
    }
    out
}

#[test]
fn image_decoder() {
    let (n, _) = fuzz("image", image_corpus(), false, |b| {
        pinsight::vision::image_io::decode_bytes(b).is_ok()
    });
    assert!(n >= 20);
}

#[test]
fn image_inspection() {
    // Whole fixture images through decode and inspection: a damaged image
    // is a verdict or an error naming the problem.
    let corpus = vec![
        read("vision/syn-2x10-q85.jpg"),
        read("vision/syn-2x8-auto.png"),
        read("interop/images/h2x5d-04.bmp"),
    ];
    let recipes = [
        Recipe::load(&fixtures().join("vision/hdr-2x10.toml")).unwrap(),
        Recipe::load(&fixtures().join("vision/hdr-2x8-auto.toml")).unwrap(),
    ];
    let (n, _) = fuzz("inspect", corpus, false, |b| {
        let mut any = false;
        for r in &recipes {
            any |= pinsight::vision::inspect_bytes(r, b, &InspectOptions::default()).is_ok();
        }
        any
    });
    assert!(n >= 20);
}

fn text_corpus(files: &[&str], extra: &[&str]) -> Vec<Vec<u8>> {
    files
        .iter()
        .map(|f| read(f))
        .chain(extra.iter().map(|s| s.as_bytes().to_vec()))
        .collect()
}

fn utf8(b: &[u8]) -> Option<&str> {
    std::str::from_utf8(b).ok()
}

#[test]
fn parameter_file() {
    let full = Params::paper().to_toml();
    let corpus = text_corpus(&["batch/worn-joint.toml"], &[&full]);
    fuzz("params", corpus, true, |b| {
        utf8(b).is_some_and(|t| Params::from_toml_str(t).is_ok_and(|p| p.validate().is_ok()))
    });
}

#[test]
fn channel_map() {
    let corpus = text_corpus(&["interop/logs/run-1200-renamed.channels.toml"], &[]);
    fuzz("channels", corpus, true, |b| {
        utf8(b).is_some_and(|t| ChannelMap::from_toml_str(t, "fuzz.toml").is_ok())
    });
}

#[test]
fn recipe() {
    let corpus = text_corpus(
        &[
            "vision/hdr-2x10.toml",
            "vision/hdr-2x5-dark.toml",
            "vision/hdr-2x8-auto.toml",
            "vision/rnd-1x8.toml",
            "vision/side-1x6.toml",
        ],
        &[],
    );
    fuzz("recipe", corpus, true, |b| {
        utf8(b).is_some_and(|t| Recipe::from_toml_str(t, "fuzz.toml").is_ok())
    });
}

#[test]
fn study_grid_and_scenes() {
    let grid = "clearances_mm = [0.1, 0.3, 0.5]\nspeeds_rpm = [1200, 1800]\nmaterials = [\"alloy_steel\", \"aluminium\"]\n";
    fuzz("grid", vec![grid.as_bytes().to_vec()], true, |b| {
        utf8(b).is_some_and(|t| pinsight::sim::sweep::SweepGrid::from_toml_str(t).is_ok())
    });
    let scenes = "[[scene]]\nname = \"worn\"\npreset = \"paper\"\nset = [\"clearance_mm=0.3\", \"motor_rpm=1500\"]\n\n[[scene]]\nname = \"flores\"\npreset = \"flores\"\nset = []\n";
    fuzz("scenes", vec![scenes.as_bytes().to_vec()], true, |b| {
        utf8(b).is_some_and(|t| pinsight::methods::dynamics::scenes_from_toml(t).is_ok())
    });
}

#[test]
fn batch_script() {
    // Steps that do not run the model or a study (a mutant may still ask
    // for one; the work budget bounds it): load, set, checks and exports
    // of panes that compute nothing by themselves.
    let script = format!(
        "size = \"60x20\"\n\
         [[step]]\nkind = \"load\"\npaths = [\"{}\"]\nexpect_errors = 0\n\
         [[step]]\nkind = \"set\"\npreset = \"paper\"\nvalues = {{ clearance_mm = 0.3, motor_rpm = 1500 }}\nlevel = \"kinematic\"\n\
         [[step]]\nkind = \"check\"\nname = \"cases\"\npane = \"study\"\nfigure = \"cases_total\"\nop = \">=\"\nvalue = 0\n\
         [[step]]\nkind = \"export\"\npane = \"study\"\nformat = \"json\"\npath = \"study.json\"\nui = {{ \"study.factor\" = \"speed\" }}\n",
        fixtures().join("vision/hdr-2x10.toml").display()
    );
    let out = tempfile::tempdir().unwrap();
    let base = fixtures();
    fuzz("batch", vec![script.into_bytes()], true, |b| {
        utf8(b).is_some_and(|t| {
            pinsight::batch::script::run_text(t, "fuzz.toml", &base, out.path())
                .is_ok_and(|r| r.success())
        })
    });
}

/// The protobuf and CDR walkers (issue 17) on mutated messages: the seeds
/// are real messages of the twins written by the official Python writers
/// (spindle, force, cycle, image), each mutant run through every codec.
#[test]
fn binary_messages() {
    use pinsight::rig::decode::binary::{BinaryCodec, Slots};
    use pinsight::rig::mcap_read::{ChannelDef, SchemaDef};
    let mut codecs = Vec::new();
    let mut corpus = Vec::new();
    for (file, paths) in [
        (
            "twins/run-2000-images.pb.mcap",
            vec!["angle_rad", "speed_rpm", "force_n", "index"],
        ),
        (
            "twins/run-2000-images.ros2.mcap",
            vec!["position[name=crank]", "wrench.force.z", "data"],
        ),
        (
            "twins/run-1200-blocks.pb.mcap",
            vec!["force_n", "displacement_mm"],
        ),
    ] {
        let bytes = read(file);
        let mut seen = std::collections::BTreeSet::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            if !seen.insert(m.channel.id) {
                continue;
            }
            let s = m.channel.schema.as_ref().unwrap();
            let ch = ChannelDef {
                id: m.channel.id,
                schema_id: s.id,
                topic: m.channel.topic.clone(),
                message_encoding: m.channel.message_encoding.clone(),
            };
            let sd = SchemaDef {
                id: s.id,
                name: s.name.clone(),
                encoding: s.encoding.clone(),
                data: s.data.to_vec(),
            };
            let codec = if s.name.contains("CompressedImage") {
                BinaryCodec::for_images(&ch, Some(&sd))
            } else {
                let p: Vec<&str> = paths
                    .iter()
                    .copied()
                    .filter(|p| BinaryCodec::for_signals(&ch, Some(&sd), &[p]).is_ok())
                    .collect();
                BinaryCodec::for_signals(&ch, Some(&sd), &p)
            };
            codecs.push(codec.unwrap());
            corpus.push(m.data.to_vec());
        }
    }
    assert!(codecs.len() >= 8, "{}", codecs.len());
    let mut slots = Slots::default();
    let (n, _) = fuzz("binary", corpus, false, |b| {
        let mut any = false;
        for (i, c) in codecs.iter().enumerate() {
            if c.decode(b, &mut slots).is_ok() {
                any = true;
                // Reading every signal of a decoded message must not panic.
                for k in 0..4 {
                    let _ = c.signal(k, &slots);
                }
                let _ = (i, c.image(&slots));
            }
        }
        any
    });
    assert!(n >= 20);
}
