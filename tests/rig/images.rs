//! The image extractor against the interop log's ground truth (sha256 of
//! every embedded image, its cycle, frame_id, format and log_time).

use pinsight::rig::images::{read_image, read_images, read_images_with_report};
use pinsight::rig::{LoadOptions, LoadStatus, load};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/interop/logs")
        .join(name)
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

#[test]
fn images_match_truth() {
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("run-2000-images.truth.json")).unwrap(),
    )
    .unwrap();
    let want = truth["images"].as_array().unwrap();
    let (meta, images) = read_images(&fixture("run-2000-images.mcap")).unwrap();
    assert_eq!(meta.part_number.as_deref(), Some("HDR-2x10-2.54"));
    assert_eq!(meta.motor_rpm, Some(2000.0));
    assert_eq!(images.len(), want.len());
    assert_eq!(images.len(), 10);
    for (img, w) in images.iter().zip(want) {
        assert_eq!(img.cycle, w["cycle_index"].as_u64());
        assert_eq!(img.frame_id, w["frame_id"].as_str().unwrap());
        assert_eq!(img.format, w["format"].as_str().unwrap());
        assert_eq!(img.log_time_ns, w["log_time_ns"].as_u64().unwrap());
        assert_eq!(img.data.len() as u64, w["bytes"].as_u64().unwrap());
        assert_eq!(
            hex(&Sha256::digest(&img.data)),
            w["sha256"].as_str().unwrap()
        );
    }
    let r = read_images_with_report(&fixture("run-2000-images.mcap")).unwrap();
    assert_eq!(r.status, LoadStatus::Ok);
}

#[test]
fn load_lists_images_and_reads_one_lazily() {
    let path = fixture("run-2000-images.mcap");
    let log = load(
        &path,
        &LoadOptions::default(),
        &pinsight::progress::Progress::hidden(),
    )
    .unwrap();
    assert_eq!(log.images.len(), 10);
    let (_, all) = read_images(&path).unwrap();
    let one = read_image(&path, &log.images[7]).unwrap();
    assert_eq!(one.data, all[7].data);
    assert_eq!(one.cycle, Some(7));
    assert!(
        log.images
            .iter()
            .all(|i| i.topic == "/camera/connector" && i.error.is_none())
    );
}

#[test]
fn logs_without_images_give_none_and_bad_files_an_error() {
    let (_, images) = read_images(&fixture("run-1200-zstd.mcap")).unwrap();
    assert!(images.is_empty());
    let e = read_images(&fixture("run-1200-renamed.channels.toml")).unwrap_err();
    assert!(e.to_string().contains("not an MCAP file"), "{e}");
    let e = read_images(&fixture("no-such-file.mcap")).unwrap_err();
    assert!(e.to_string().contains("no-such-file.mcap"), "{e}");
}
