//! Shared helpers of the integration tests: the demo session with its
//! results (TUI and batch tests), a replayable random generator (fuzz tests).
#![allow(dead_code)]

use pinsight::panes::Session;
use pinsight::sim::sweep::SweepGrid;

/// The demo session with every result the panes show computed in line:
/// the model (paper preset, clearance level), a small study (2 × 2 × 2
/// cases, 1 + 1 revolutions), the first image's inspection, the batch
/// yield, the overlay of the demo log (and, with methods, the quick
/// methods lab).
pub fn full_session() -> Session {
    let mut s = Session::demo();
    s.display = Some("test display".into());
    s.run_model_now();
    assert!(s.model_error.is_none(), "{:?}", s.model_error);
    s.study_setup.grid = SweepGrid {
        clearances_mm: vec![0.1, 0.5],
        speeds_rpm: vec![1200.0, 1800.0],
        materials: vec!["alloy_steel".into(), "aluminium".into()],
    };
    s.study_setup.warmup = 1.0;
    s.study_setup.revs = 1.0;
    s.run_study_now();
    s.inspect_now(0);
    s.run_yield_now();
    s.run_overlay_now(0);
    s
}

/// `full_session` plus the methods lab (seconds).
pub fn full_session_with_methods() -> Session {
    let mut s = full_session();
    s.run_methods_now();
    s
}

/// A small deterministic generator (xorshift64*) for the fuzz tests, so a
/// failing random run is replayed from its seed (seed ≠ 0).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in 0..n (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The environment variables by which a job array's engines name a shard
/// (pinsight's own, Kubernetes Indexed Jobs, Slurm arrays).
pub const SHARD_ENV: [&str; 6] = [
    "PINSIGHT_SHARD",
    "PINSIGHT_SHARDS",
    "JOB_COMPLETION_INDEX",
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
];

/// The binary without [`SHARD_ENV`]: a test run inside a CI job array must
/// not shard itself.
pub fn pinsight_unsharded() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_pinsight"));
    for v in SHARD_ENV {
        c.env_remove(v);
    }
    c
}

/// Every file below `dir` (recursively), by its path relative to `dir`:
/// what the shard-and-merge tests compare byte for byte.
pub fn tree(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(
        root: &std::path::Path,
        d: &std::path::Path,
        out: &mut std::collections::BTreeMap<String, Vec<u8>>,
    ) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// `a` and `b` hold the same files with the same bytes.
pub fn assert_same_tree(a: &std::path::Path, b: &std::path::Path) {
    let (ta, tb) = (tree(a), tree(b));
    assert_eq!(
        ta.keys().collect::<Vec<_>>(),
        tb.keys().collect::<Vec<_>>(),
        "{} and {} hold different files",
        a.display(),
        b.display()
    );
    for (name, bytes) in &ta {
        assert!(
            bytes == &tb[name],
            "{name} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// The process exited with one of `codes` (its stderr shown otherwise).
pub fn exit_in(o: &std::process::Output, codes: &[i32]) {
    assert!(
        o.status.code().is_some_and(|c| codes.contains(&c)),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs the binary (unsharded) in the crate's folder, where the fixture
/// paths are relative to: (exit code, stdout, stderr).
pub fn run(args: &[&str]) -> (i32, String, String) {
    let out = pinsight_unsharded()
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run pinsight");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The image a truth file `NAME.json` describes: the file beside it with
/// the same stem and another extension.
pub fn image_beside(truth_json: &std::path::Path) -> std::path::PathBuf {
    let stem = truth_json.file_stem().unwrap().to_owned();
    std::fs::read_dir(truth_json.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_stem() == Some(stem.as_os_str()) && p.extension().is_some_and(|x| x != "json")
        })
        .unwrap_or_else(|| panic!("no image beside {}", truth_json.display()))
}

/// The truth files (`*.json`) in `dir`, sorted.
pub fn truth_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    v.sort();
    v
}

/// One case of the randomised envelope (`vision::synth_envelope`, exact
/// truth from the generator's drawing): drawn, rendered and inspected with
/// the default options; an error instead of a verdict panics, naming the
/// seed.
pub fn envelope_case(
    seed: u64,
) -> (
    pinsight::vision::synth_envelope::EnvelopeCase,
    pinsight::vision::synth_envelope::Rendered,
    pinsight::vision::Inspection,
) {
    let case = pinsight::vision::synth_envelope::EnvelopeCase::draw(seed);
    let r = case.render().expect("the generator renders every draw");
    let ins = pinsight::vision::inspect_gray(
        &case.recipe,
        &r.gray,
        r.info.clone(),
        &pinsight::vision::InspectOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{seed}: an error, not a verdict: {e}"));
    (case, r, ins)
}

/// [`envelope_case`] whose verdict must be right (a wrong one panics,
/// naming the seed and the pins): the inspection and how many pin statuses
/// are wrong.
pub fn envelope_verdict_right(seed: u64) -> (pinsight::vision::Inspection, usize) {
    let (case, r, ins) = envelope_case(seed);
    let c = r.compare(&case.factors, &ins);
    assert!(
        c.verdict_ok,
        "{seed}: verdict wrong: {:?}",
        c.status_mismatches
    );
    (ins, c.status_mismatches.len())
}

/// Asserts every envelope case's verdict and every pin status right.
pub fn every_status_right(seeds: &[u64]) {
    for &seed in seeds {
        let (_, wrong) = envelope_verdict_right(seed);
        assert_eq!(wrong, 0, "{seed}: {wrong} pin statuses wrong");
    }
}

/// Asserts that the inspection's notes (its `warnings`) hold one containing
/// `needle`: the report says what the inspection did or doubts.
pub fn assert_note(ins: &pinsight::vision::Inspection, needle: &str) {
    assert!(
        ins.warnings.iter().any(|w| w.contains(needle)),
        "no note containing {needle:?}: {:?}",
        ins.warnings
    );
}
