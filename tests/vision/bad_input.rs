//! Bad input never panics and never stops a batch: each case is a clear
//! per-image error naming the problem, and the other images are still
//! inspected and reported.

use pinsight::progress::Progress;
use pinsight::vision::batch::{self, ItemStatus, RecipeBook};
use pinsight::vision::{ErrorKind, InspectOptions, Recipe};
use std::path::{Path, PathBuf};

fn interop(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/interop/images")
        .join(name)
}

fn png(img: image::DynamicImage) -> Vec<u8> {
    let mut c = std::io::Cursor::new(Vec::new());
    img.write_to(&mut c, image::ImageFormat::Png).unwrap();
    c.into_inner()
}

/// A PNG whose header claims `w` × `h` and whose data stream is tiny.
fn lying_png(w: u32, h: u32) -> Vec<u8> {
    fn crc(d: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in d {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    (c >> 1) ^ 0xedb8_8320
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    for (tag, body) in [
        (
            b"IHDR",
            [
                w.to_be_bytes().as_slice(),
                h.to_be_bytes().as_slice(),
                &[8, 0, 0, 0, 0],
            ]
            .concat(),
        ),
        (b"IDAT", b"\x78\x9c\x03\x00\x00\x00\x00\x01".to_vec()),
        (b"IEND", Vec::new()),
    ] {
        out.extend_from_slice(&(body.len() as u32).to_be_bytes());
        let mut chunk = tag.to_vec();
        chunk.extend_from_slice(&body);
        out.extend_from_slice(&chunk);
        out.extend_from_slice(&crc(&chunk).to_be_bytes());
    }
    out
}

#[test]
fn each_bad_image_is_its_own_clear_error_and_the_batch_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let good = std::fs::read(interop("h2x10-02.png")).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let p = d.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let cases: Vec<(PathBuf, ErrorKind, &str)> = vec![
        (write("a_zero.png", &[]), ErrorKind::Empty, "empty file"),
        (
            write("b_truncated.png", &good[..good.len() / 3]),
            ErrorKind::Decode,
            "truncated",
        ),
        (
            write("c_text.png", b"this is not an image at all"),
            ErrorKind::NotImage,
            "not a recognised image",
        ),
        (
            write(
                "d_one_pixel.png",
                &png(image::DynamicImage::ImageLuma8(image::GrayImage::new(1, 1))),
            ),
            ErrorKind::TooSmall,
            "1 × 1 px",
        ),
        (
            write("e_huge.png", &lying_png(200_000, 100_000)),
            ErrorKind::TooLarge,
            "200000 × 100000",
        ),
        (
            write(
                "f_black.png",
                &png(image::DynamicImage::ImageLuma8(image::GrayImage::new(
                    640, 480,
                ))),
            ),
            ErrorKind::NoContrast,
            "no contrast",
        ),
        // A 2 × 20 header inspected with the 2 × 10 recipe.
        (
            interop("h2x20-01.jpg"),
            ErrorKind::WrongPart,
            "does not match recipe",
        ),
        // A side view inspected with a top-view recipe.
        (interop("s1x10-00.png"), ErrorKind::NoPins, "no pins found"),
        (interop("h2x10-02.png"), ErrorKind::Io, ""),
    ];
    let inputs: Vec<PathBuf> = cases.iter().map(|c| c.0.clone()).collect();
    let (items, pre) = batch::collect_items(&inputs);
    assert!(pre.is_empty());
    let book = RecipeBook::new(vec![Recipe::load(&interop("hdr-2x10.toml")).unwrap()]);
    let results = batch::run_batch(
        &items,
        &book,
        &InspectOptions::default(),
        &Progress::hidden(),
    );
    assert_eq!(results.len(), cases.len());
    for (r, (path, kind, words)) in results.iter().zip(&cases) {
        assert_eq!(r.name, path.display().to_string());
        if words.is_empty() {
            assert_eq!(r.status, ItemStatus::Pass, "the good image still passes");
            continue;
        }
        assert_eq!(r.status, ItemStatus::Error, "{}", r.name);
        let e = r.error.as_ref().unwrap();
        assert_eq!(e.kind, *kind, "{}: {}", r.name, e.message);
        assert!(
            e.message.contains(words),
            "{}: '{}' should say '{words}'",
            r.name,
            e.message
        );
    }
}

#[test]
fn side_image_with_top_recipe_and_top_image_with_side_recipe() {
    let side = Recipe::load(&interop("side-1x10.toml")).unwrap();
    let e =
        pinsight::vision::inspect_path(&side, &interop("h2x10-00.png"), &InspectOptions::default())
            .unwrap_err();
    assert!(
        matches!(
            e.kind(),
            ErrorKind::NoHousing | ErrorKind::WrongPart | ErrorKind::NoPins
        ),
        "{e}"
    );
}

#[test]
fn invalid_recipe_is_a_per_image_error_naming_the_recipe() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = tmp.path().join("bad.toml");
    std::fs::write(&bad, "part_number = \"X\"\nview = \"top\"\nrows = 0\n").unwrap();
    let book = RecipeBook::load(&[bad]);
    assert_eq!(book.invalid.len(), 1);
    let (items, _) = batch::collect_items(&[interop("h2x10-00.png"), interop("r1x8-00.jpg")]);
    let results = batch::run_batch(
        &items,
        &book,
        &InspectOptions::default(),
        &Progress::hidden(),
    );
    assert_eq!(results.len(), 2);
    for r in &results {
        assert_eq!(r.status, ItemStatus::Error);
        let e = r.error.as_ref().unwrap();
        assert_eq!(e.kind, ErrorKind::Recipe);
        assert!(
            e.message.contains("invalid recipe") && e.message.contains("bad.toml"),
            "{}",
            e.message
        );
    }
}

#[test]
fn rig_log_naming_another_part_is_wrong_part() {
    let log =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/logs/run-2000-images.mcap");
    let (items, _) = batch::collect_items(&[log]);
    let book = RecipeBook::new(vec![Recipe::load(&interop("rnd-1x8.toml")).unwrap()]);
    let results = batch::run_batch(
        &items[..2],
        &book,
        &InspectOptions::default(),
        &Progress::hidden(),
    );
    for r in &results {
        let e = r.error.as_ref().unwrap();
        assert_eq!(e.kind, ErrorKind::WrongPart);
        assert!(e.message.contains("HDR-2x10-2.54"), "{}", e.message);
    }
}
