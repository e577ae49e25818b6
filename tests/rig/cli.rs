//! `pinsight log` end to end: text, JSON, exit codes, channel maps.

use crate::common;

use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/interop/logs")
        .join(name)
}

use common::run as pinsight;

#[test]
fn text_report_of_a_faulty_log() {
    let f = fixture("run-1200-gaps.mcap");
    let (code, out, _) = pinsight(&["log", f.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(out.contains("ok_with_warnings"));
    assert!(out.contains("gap of 50.1 ms (500 samples missing)"));
    assert!(out.contains("12 written as the token NaN, 8 as null"));
    assert!(out.contains("jumps back by 5.000 ms"));
    assert!(out.contains("20 complete (12 usable)"));
    assert!(out.contains("/rig/spindle         angle, speed"));
}

#[test]
fn json_report_and_exit_codes() {
    let t = fixture("run-1200-truncated.mcap");
    let (code, out, _) = pinsight(&["log", "--json", t.to_str().unwrap()]);
    assert_eq!(code, 1, "partial → 1");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["load_status"], "partial");
    assert_eq!(v["counts"]["messages"], 17321);
    assert_eq!(v["cycles"]["count"], 13);
    assert!(
        v["findings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["code"] == "truncated")
    );

    let missing = fixture("does-not-exist.mcap");
    let z = fixture("run-1200-zstd.mcap");
    let (code, out, err) = pinsight(&[
        "log",
        "--json",
        missing.to_str().unwrap(),
        z.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "unreadable file → 2, the other still reported");
    assert!(err.contains("does-not-exist.mcap"));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["status"], "ok");
}

#[test]
fn channel_map_and_metadata_override() {
    let f = fixture("run-1200-renamed.mcap");
    let m = fixture("run-1200-renamed.channels.toml");
    let (code, out, _) = pinsight(&["log", f.to_str().unwrap()]);
    assert_eq!(code, 1, "nothing mapped → error status");
    assert!(out.contains("--channels"));
    let (code, out, _) = pinsight(&[
        "log",
        "--channels",
        m.to_str().unwrap(),
        "--meta",
        "standoff_mm=13.9",
        f.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("20 complete") && out.contains("from the crank angle"));
    assert!(
        out.contains("overridden by the session: standoff_mm")
            && out.contains("standoff 13.9 mm (metadata)")
    );
    let (code, _, err) = pinsight(&[
        "log",
        "--channels",
        f.to_str().unwrap(),
        f.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("channel map"), "{err}");
}
