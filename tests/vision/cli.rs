//! `pinsight inspect` and `pinsight yield` end to end (the built binary).

use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}
fn img(n: &str) -> PathBuf {
    root().join("fixtures/interop/images").join(n)
}
fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pinsight"))
}

#[test]
fn inspect_prints_tables_json_and_overlays_with_exit_codes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = bin()
        .args(["inspect", "--recipe"])
        .arg(img("hdr-2x10.toml"))
        .arg(img("h2x10-02.png"))
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("PASS") && text.contains("area_ratio"),
        "{text}"
    );

    let out = bin()
        .args(["inspect", "--json", "--recipe"])
        .arg(img("hdr-2x10.toml"))
        .arg(img("h2x10-00.png"))
        .arg("--out")
        .arg(tmp.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "a failing connector exits 1");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v[0]["status"], "fail");
    let pins = v[0]["inspection"]["pins"].as_array().unwrap();
    assert_eq!(pins.len(), 20);
    assert!(
        pins.iter()
            .any(|p| p["status"] == "bent" && p["row"] == 1 && p["col"] == 7)
    );
    assert!(pins[0]["nominal_x_px"].is_number() && pins[0]["dx_mm"].is_number());
    let overlay = tmp.path().join("h2x10-00.overlay.png");
    let o = image::open(&overlay).unwrap();
    assert_eq!((o.width(), o.height()), (1024, 768));
    assert!(tmp.path().join("inspection.json").exists());

    // An unreadable image: exit 3, the reason on stdout, the others still done.
    let bad = tmp.path().join("empty.png");
    std::fs::write(&bad, b"").unwrap();
    let out = bin()
        .args(["inspect", "--recipe"])
        .arg(img("hdr-2x10.toml"))
        .arg(&bad)
        .arg(img("h2x10-02.png"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("empty.png: ERROR empty file") && text.contains("PASS"),
        "{text}"
    );
}

#[test]
fn yield_writes_json_csv_markdown_and_charts() {
    let tmp = tempfile::tempdir().unwrap();
    let log = root().join("fixtures/interop/logs/run-2000-images.mcap");
    let out = bin()
        .arg("yield")
        .arg(&log)
        .arg(img("r1x8-00.jpg"))
        .args(["--recipe"])
        .arg(img("hdr-2x10.toml"))
        .args(["--recipe"])
        .arg(img("rnd-1x8.toml"))
        .args(["--by", "speed", "--out"])
        .arg(tmp.path())
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "yield.json",
        "items.csv",
        "pins.csv",
        "yield.md",
        "pareto.png",
        "yield_by_speed.png",
    ] {
        assert!(tmp.path().join(f).exists(), "{f}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("yield.json")).unwrap())
            .unwrap();
    let r = &v["report"];
    // Truth: 5 of the 10 log images pass; r1x8-00 passes.
    assert_eq!(r["inspected"], 11);
    assert_eq!(r["passed"], 6);
    assert_eq!(r["errors"], 0);
    assert_eq!(r["by_speed"][0]["key"], "2000 rpm");
    let items = std::fs::read_to_string(tmp.path().join("items.csv")).unwrap();
    assert_eq!(items.lines().count(), 12);
    let md = std::fs::read_to_string(tmp.path().join("yield.md")).unwrap();
    assert!(md.contains("Wilson") && md.contains("Pareto") && md.contains("![pareto](pareto.png)"));
}
