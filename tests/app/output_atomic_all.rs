//! Atomicity of every writer other than `yield` (which
//! `tests/app/output_atomic.rs` covers in depth), through the real binary:
//! `sweep`, `overlay`, `inspect` and `methods` reports (several files),
//! and the single files of `calibrate --out`, `simulate --csv` and
//! `render -o`. For each: a complete run A sits in the folder with a file
//! of the user's; run B (different options, so different content) is
//! killed with SIGKILL or SIGINT after seeded delays. The folder must then
//! hold A's files or B's, all from one run, the user's file untouched; the
//! next run leaves no temporary behind, in the folder or beside it.
//!
//! Which files can be compared byte for byte is found, not listed: run A
//! twice, and a file that differs between the two (wall times in a JSON)
//! is only checked to be well formed.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(p)
        .display()
        .to_string()
}

const NOTES: &str = "notes.txt";

struct Case {
    name: &'static str,
    /// Arguments of runs A and B; `{OUT}` is replaced by the output path.
    a: Vec<String>,
    b: Vec<String>,
    /// The output is one file in the folder (else the folder itself).
    file: Option<&'static str>,
}

fn args(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn cases() -> Vec<Case> {
    let log = repo("fixtures/logs/synth-1800-ripple-dropouts-blocks.mcap");
    let vision = repo("fixtures/vision");
    let recipe = repo("fixtures/vision/hdr-2x10.toml");
    let scenes = repo("fixtures/methods/two-scenes.toml");
    vec![
        Case {
            name: "sweep",
            a: args(&[
                "sweep",
                "--clearances",
                "0.1,0.3",
                "--speeds",
                "1200",
                "--materials",
                "alloy_steel,aluminium",
                "--warmup",
                "0",
                "--revs",
                "1",
                "--out",
                "{OUT}",
            ]),
            b: args(&[
                "sweep",
                "--clearances",
                "0.1,0.3",
                "--speeds",
                "1500",
                "--materials",
                "alloy_steel,aluminium",
                "--warmup",
                "0",
                "--revs",
                "1",
                "--out",
                "{OUT}",
            ]),
            file: None,
        },
        Case {
            name: "overlay",
            a: args(&[
                "overlay", &log, "--revs", "8", "--warmup", "1", "--out", "{OUT}",
            ]),
            b: args(&[
                "overlay", &log, "--revs", "8", "--warmup", "1", "--points", "360", "--out",
                "{OUT}",
            ]),
            file: None,
        },
        Case {
            name: "inspect",
            a: args(&[
                "inspect",
                &vision,
                "-r",
                &recipe,
                "--magnify",
                "10",
                "--out",
                "{OUT}",
            ]),
            b: args(&[
                "inspect",
                &vision,
                "-r",
                &recipe,
                "--magnify",
                "25",
                "--out",
                "{OUT}",
            ]),
            file: None,
        },
        Case {
            name: "methods",
            a: args(&["methods", "--out", "{OUT}"]),
            b: args(&["methods", "--scenes", &scenes, "--out", "{OUT}"]),
            file: None,
        },
        Case {
            name: "calibrate",
            a: args(&[
                "calibrate",
                &log,
                "--revs",
                "8",
                "--points",
                "180",
                "--out",
                "{OUT}",
            ]),
            b: args(&[
                "calibrate",
                &log,
                "--revs",
                "8",
                "--points",
                "360",
                "--out",
                "{OUT}",
            ]),
            file: Some("calibrated.toml"),
        },
        Case {
            name: "simulate",
            a: args(&["simulate", "--revs", "2", "--csv", "{OUT}"]),
            b: args(&["simulate", "--revs", "3", "--csv", "{OUT}"]),
            file: Some("curves.csv"),
        },
        Case {
            name: "render",
            a: args(&["render", "study", "--format", "json", "-o", "{OUT}"]),
            b: args(&[
                "render", "study", "--format", "json", "--revs", "2", "-o", "{OUT}",
            ]),
            file: Some("study.json"),
        },
    ]
}

fn command(argv: &[String], out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pinsight"));
    for a in argv {
        if a == "{OUT}" {
            c.arg(out);
        } else {
            c.arg(a);
        }
    }
    c.stdout(Stdio::null()).stderr(Stdio::null());
    c
}

/// Runs to the end; the run must not be an error (2).
fn complete(argv: &[String], out: &Path) {
    let st = command(argv, out).status().unwrap();
    assert!(st.code().is_some_and(|c| c != 2), "{argv:?}: {st:?}");
}

/// Visible files of a folder and their bytes.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

fn wellformed(name: &str, bytes: &[u8]) -> bool {
    if name.ends_with(".json") {
        serde_json::from_slice::<serde_json::Value>(bytes).is_ok()
    } else if name.ends_with(".png") {
        image::load_from_memory(bytes).is_ok()
    } else {
        std::str::from_utf8(bytes).is_ok()
    }
}

fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

fn run_case(case: &Case, trials: usize) -> (usize, usize) {
    let tmp = tempfile::tempdir().unwrap();
    let place = |dir: &Path| match case.file {
        Some(f) => dir.join(f),
        None => dir.to_path_buf(),
    };
    // References: A twice (to find the files that vary run to run), B once
    // (timed, to place the kills).
    let refs: Vec<PathBuf> = ["a1", "a2", "b"]
        .iter()
        .map(|n| tmp.path().join(n))
        .collect();
    for r in &refs {
        std::fs::create_dir_all(r).unwrap();
    }
    complete(&case.a, &place(&refs[0]));
    complete(&case.a, &place(&refs[1]));
    let t0 = Instant::now();
    complete(&case.b, &place(&refs[2]));
    let full = t0.elapsed().max(Duration::from_millis(5));
    let (a, a2, b) = (snapshot(&refs[0]), snapshot(&refs[1]), snapshot(&refs[2]));
    let volatile: BTreeSet<String> = a
        .iter()
        .filter(|(n, v)| a2.get(*n) != Some(v))
        .map(|(n, _)| n.clone())
        .collect();
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{}: A and B write different file sets",
        case.name
    );
    assert!(
        a.iter().any(|(n, v)| !volatile.contains(n) && b[n] != *v),
        "{}: A and B cannot be told apart (volatile: {volatile:?})",
        case.name
    );

    let out_dir = tmp.path().join("out");
    let mut s: u64 = 0x5eed_0014 ^ case.name.len() as u64;
    let mut outcomes = (0, 0);
    for trial in 0..trials {
        std::fs::remove_dir_all(&out_dir).ok();
        std::fs::create_dir_all(&out_dir).unwrap();
        std::fs::write(out_dir.join(NOTES), b"user notes").unwrap();
        // A's complete output, as its reference run wrote it (a run of A
        // here would write the same files; the run that sweeps after the
        // kill below is a real one).
        for (name, bytes) in &a {
            std::fs::write(out_dir.join(name), bytes).unwrap();
        }
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let frac = (s >> 11) as f64 / (1u64 << 53) as f64;
        let delay = if trial % 2 == 0 {
            full.mul_f64(1.1 * frac)
        } else {
            full.mul_f64(0.8 + 0.3 * frac)
        };
        let mut child = command(&case.b, &place(&out_dir)).spawn().unwrap();
        std::thread::sleep(delay);
        let sig = if trial % 4 < 2 { "-KILL" } else { "-INT" };
        let _ = Command::new("kill")
            .arg(sig)
            .arg(child.id().to_string())
            .status();
        let _ = child.wait();
        let ctx = format!("{} trial {trial} ({sig} after {delay:?})", case.name);
        let mut now = snapshot(&out_dir);
        assert_eq!(
            now.remove(NOTES).as_deref(),
            Some(&b"user notes"[..]),
            "{ctx}: the user's file"
        );
        assert_eq!(
            now.keys().collect::<Vec<_>>(),
            a.keys().collect::<Vec<_>>(),
            "{ctx}: file set changed"
        );
        let mut versions = BTreeSet::new();
        for (name, bytes) in &now {
            assert!(wellformed(name, bytes), "{ctx}: {name} is not well formed");
            if volatile.contains(name) {
                continue;
            }
            let from_a = *bytes == a[name];
            let from_b = *bytes == b[name];
            assert!(from_a || from_b, "{ctx}: {name} is neither A's nor B's");
            if from_a != from_b {
                versions.insert(if from_a { "A" } else { "B" });
            }
        }
        assert!(versions.len() <= 1, "{ctx}: a mix of A and B files");
        if versions.contains("B") {
            outcomes.1 += 1;
        } else {
            outcomes.0 += 1;
        }
        // The next run sweeps what the killed one left.
        complete(&case.a, &place(&out_dir));
        assert!(
            hidden(&out_dir).is_empty(),
            "{ctx}: temporaries left: {:?}",
            hidden(&out_dir)
        );
        assert!(
            hidden(tmp.path()).is_empty(),
            "{ctx}: left beside: {:?}",
            hidden(tmp.path())
        );
    }
    (outcomes.0, outcomes.1)
}

/// Kills run B of one case `PINSIGHT_KILL_TRIALS` times (8 by default).
/// One test per case, so that the cases run on the test harness's threads
/// side by side rather than one after another.
fn check(name: &str) {
    let trials: usize = std::env::var("PINSIGHT_KILL_TRIALS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(8);
    let case = cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no case {name}"));
    let (a, b) = run_case(&case, trials);
    eprintln!("{name}: {trials} kills, {a} left A's output, {b} B's");
}

/// One test per case, named after it, and the list of the cases tested.
macro_rules! case_tests {
    ($($name:ident),* $(,)?) => {
        /// The cases that have a test below.
        const TESTED: &[&str] = &[$(stringify!($name)),*];

        mod leaves_the_old_or_the_new_output {
            $(
                #[test]
                fn $name() {
                    super::check(stringify!($name));
                }
            )*
        }
    };
}

case_tests!(
    sweep, overlay, inspect, methods, calibrate, simulate, render
);

#[test]
fn every_case_has_its_test() {
    let names: Vec<&str> = cases().iter().map(|c| c.name).collect();
    assert_eq!(names, TESTED, "add each new case to case_tests!");
}
