//! Atomicity of the multi-file reports through the real binary: a
//! complete earlier report sits in `--out`; the same command (with an
//! option that changes the report) is killed with SIGKILL or SIGINT after
//! seeded delays; the folder must then hold the old complete report or the
//! new complete one — same file set, every JSON parses, every PNG decodes,
//! every file equal to the old or the new version and all from the same
//! version. The next run sweeps the temporaries a killed run left.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// `pinsight yield` over the fixture images, grouped `by`.
fn yield_cmd(out: &Path, by: &str) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pinsight"));
    c.arg("yield")
        .arg(repo("fixtures/vision"))
        .args(["--recipe"])
        .arg(repo("fixtures/vision/hdr-2x10.toml"))
        .args(["--by", by, "--jobs", "1", "--out"])
        .arg(out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    c
}

/// The user's own file and folder that live in the output folder too.
const NOTES: &str = "notes.txt";
const KEEP: &str = "keep";

/// Visible files of a folder and their bytes (temporaries are hidden; the
/// user's subfolder is checked on its own).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .filter(|e| e.file_name() != KEEP)
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// Every file parses as its kind: JSON, PNG, UTF-8 text.
fn assert_wellformed(files: &BTreeMap<String, Vec<u8>>, ctx: &str) {
    for (name, bytes) in files {
        if name.ends_with(".json") {
            serde_json::from_slice::<serde_json::Value>(bytes)
                .unwrap_or_else(|e| panic!("{ctx}: {name} is not JSON: {e}"));
        } else if name.ends_with(".png") {
            image::load_from_memory(bytes)
                .unwrap_or_else(|e| panic!("{ctx}: {name} is not a PNG: {e}"));
        } else {
            std::str::from_utf8(bytes).unwrap_or_else(|e| panic!("{ctx}: {name}: {e}"));
        }
    }
}

/// The `group_by` the yield.json of a snapshot was made with.
fn group_by(files: &BTreeMap<String, Vec<u8>>) -> String {
    let v: serde_json::Value = serde_json::from_slice(&files["yield.json"]).unwrap();
    v["report"]["group_by"].as_str().unwrap().to_string()
}

#[test]
fn killed_yield_leaves_the_old_or_the_new_report() {
    let tmp = tempfile::tempdir().unwrap();
    // The new report's reference, written once in full (and timed).
    let new_ref = tmp.path().join("new");
    let t0 = Instant::now();
    assert!(yield_cmd(&new_ref, "part").status().unwrap().code() != Some(2));
    let full = t0.elapsed();
    let new = snapshot(&new_ref);
    assert_wellformed(&new, "reference");
    let out = tmp.path().join("out");
    // Seeded delays over the whole run (SplitMix-like LCG, fixed seed).
    let mut s: u64 = 0x5eed_0014;
    let mut outcomes = (0, 0);
    let trials = 24;
    for trial in 0..trials {
        std::fs::remove_dir_all(&out).ok();
        std::fs::create_dir_all(out.join(KEEP)).unwrap();
        std::fs::write(out.join(KEEP).join("a.txt"), b"sub").unwrap();
        std::fs::write(out.join(NOTES), b"user notes").unwrap();
        assert!(yield_cmd(&out, "lot").status().unwrap().code() != Some(2));
        let old = snapshot(&out);
        assert_eq!(group_by(&old), "lot");
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let frac = (s >> 11) as f64 / (1u64 << 53) as f64;
        // Half the kills anywhere in the run, half around its end, where
        // the files are put in place.
        let delay = if trial % 4 < 2 {
            full.mul_f64(1.2 * frac)
        } else {
            full.mul_f64(0.85 + 0.25 * frac)
        };
        let mut child = yield_cmd(&out, "part").spawn().unwrap();
        std::thread::sleep(delay);
        let sig = if trial % 2 == 0 { "-KILL" } else { "-INT" };
        let _ = Command::new("kill")
            .arg(sig)
            .arg(child.id().to_string())
            .status();
        let _ = child.wait();
        let now = snapshot(&out);
        let ctx = format!("trial {trial} ({sig} after {delay:?})");
        assert_wellformed(&now, &ctx);
        let names = |m: &BTreeMap<String, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&now), names(&old), "{ctx}: file set changed");
        let version = group_by(&now);
        let reference = if version == "lot" { &old } else { &new };
        if version == "lot" {
            outcomes.0 += 1;
        } else {
            outcomes.1 += 1;
        }
        assert_eq!(now[NOTES], b"user notes", "{ctx}: the user's file");
        assert_eq!(
            std::fs::read(out.join(KEEP).join("a.txt")).ok().as_deref(),
            Some(&b"sub"[..]),
            "{ctx}: the user's subfolder"
        );
        for (name, bytes) in &now {
            // yield.json holds per-item timings; the rest is deterministic.
            if name != "yield.json" && name != NOTES {
                assert!(
                    bytes == &reference[name],
                    "{ctx}: {name} is not the {version} version: a mix"
                );
            }
        }
        // The next run sweeps what the killed one left.
        assert!(yield_cmd(&out, "lot").status().unwrap().code() != Some(2));
        let hidden: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .filter_map(|e| {
                let n = e.unwrap().file_name().to_string_lossy().into_owned();
                n.starts_with('.').then_some(n)
            })
            .collect();
        assert!(hidden.is_empty(), "{ctx}: temporaries left: {hidden:?}");
        let beside: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(beside.is_empty(), "{ctx}: left beside --out: {beside:?}");
        assert_eq!(
            std::fs::read(out.join(KEEP).join("a.txt")).ok().as_deref(),
            Some(&b"sub"[..]),
            "{ctx}: the user's subfolder after the next run"
        );
    }
    eprintln!(
        "{trials} kills: {} left the old report, {} the new one",
        outcomes.0, outcomes.1
    );
}
