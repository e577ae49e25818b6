//! End to end: the real binary in a tmux session. Keys are sent with
//! `send-keys`, the screen is read with `capture-pane`. Every wait has a
//! timeout; the tmux server is private to the test and killed at the end.
//! Skips (with a message) only when tmux is not installed (`.ci/run`
//! installs it).

use std::process::{Command, Output};
use std::time::{Duration, Instant};

struct Tmux {
    sock: String,
}

impl Tmux {
    fn cmd(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.sock, "-f", "/dev/null"])
            .args(args)
            .output()
            .expect("running tmux")
    }
    fn keys(&self, keys: &[&str]) {
        let mut a = vec!["send-keys", "-t", "e2e"];
        a.extend_from_slice(keys);
        let o = self.cmd(&a);
        assert!(
            o.status.success(),
            "send-keys {keys:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    fn literal(&self, text: &str) {
        let o = self.cmd(&["send-keys", "-t", "e2e", "-l", text]);
        assert!(o.status.success());
    }
    fn screen(&self) -> String {
        String::from_utf8_lossy(&self.cmd(&["capture-pane", "-p", "-t", "e2e"]).stdout).into_owned()
    }
    /// Waits until the screen satisfies `ok`; panics with the screen after `secs`.
    fn wait(&self, what: &str, secs: f64, ok: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let s = self.screen();
            if ok(&s) {
                return s;
            }
            if start.elapsed() > Duration::from_secs_f64(secs) {
                panic!("timed out after {secs} s waiting for {what}; screen:\n{s}");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    fn wait_for(&self, text: &str, secs: f64) -> String {
        self.wait(&format!("`{text}`"), secs, |s| s.contains(text))
    }
    fn pane_state(&self) -> String {
        String::from_utf8_lossy(
            &self
                .cmd(&[
                    "list-panes",
                    "-t",
                    "e2e",
                    "-F",
                    "#{pane_dead} #{pane_dead_status}#{pane_dead_signal}",
                ])
                .stdout,
        )
        .trim()
        .to_string()
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.cmd(&["kill-server"]);
    }
}

fn tmux_available() -> bool {
    Command::new("tmux")
        .arg("-V")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn tui_in_tmux_switch_panes_help_edit_bad_input_quit() {
    if !tmux_available() {
        eprintln!(
            "SKIPPED: tmux is not installed (the CI script installs it); the end-to-end TUI test did not run"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let corrupt = dir.path().join("dropped.mcap");
    std::fs::write(&corrupt, b"\x89MCAP0\r\nthis is not a rig log").unwrap();
    let t = Tmux {
        sock: format!("pinsight-e2e-{}", std::process::id()),
    };
    let bin = env!("CARGO_BIN_EXE_pinsight");
    let started = t.cmd(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        "110",
        "-y",
        "32",
        &format!("env TERM=xterm-256color {bin}"),
    ]);
    assert!(
        started.status.success(),
        "{}",
        String::from_utf8_lossy(&started.stderr)
    );
    t.cmd(&["set-option", "-t", "e2e", "remain-on-exit", "on"]);
    // `pinsight` with no argument opens the demo; wait until the terminal
    // query is over (keys typed during it would be read as its reply).
    t.wait("the image protocol", 10.0, |s| {
        s.contains("1 Session") && s.contains("images:") && !s.contains("asking the terminal")
    });
    t.wait_for("model: clearance level", 20.0);
    // Every pane by number, then Tab wraps around.
    // The data panes show the demo's real data once the worker has run:
    // the log's channels, its 20 cycles against the model, the first
    // image's inspection (ground truth: fail, a damaged pin), the yield.
    for (k, text, secs) in [
        ("2", "displacement (mm)", 10.0),
        ("3", "envelope of 20 cycles", 30.0),
        ("4", "Parameters — preset paper", 10.0),
        ("5", "press r to run", 10.0),
        ("6", "verdict: FAIL", 30.0),
        ("7", "Wilson", 30.0),
        ("8", "Methods", 10.0),
    ] {
        t.keys(&[k]);
        t.wait_for(text, secs);
    }
    t.keys(&["6"]);
    let s = t.wait_for("damaged", 10.0);
    assert!(s.contains("h2x10-01.jpg (1/4)"), "{s}");
    t.keys(&["n"]);
    let s = t.wait_for("verdict: PASS", 30.0);
    assert!(s.contains("r1x8-00.jpg (2/4)"), "{s}");
    t.keys(&["7"]);
    t.wait_for("yield 25.0 %", 10.0);
    t.keys(&["3", "n"]);
    t.wait_for("stroke (mm) — cycle 0", 10.0);
    t.keys(&["8"]);
    t.wait_for("Charts (", 30.0); // the quick methods lab ran in the background
    // The Line pane: the demo log's 20 cycles against its process recipe.
    t.keys(&["9"]);
    t.wait_for("20 OK", 30.0);
    // The Trend pane: the demo's log is embedded (no file to calibrate), said so.
    t.keys(&["Tab"]);
    t.wait_for("no log could be calibrated", 10.0);
    t.keys(&["Tab"]);
    t.wait_for("Metadata", 10.0);
    // Help overlay.
    t.keys(&["?"]);
    t.wait_for("Help — every key", 10.0);
    t.keys(&["Escape"]);
    t.wait("help closed", 10.0, |s| !s.contains("Help — every key"));
    // Edit a parameter: an invalid value first, then a valid one.
    t.keys(&["4"]);
    t.wait_for("Parameters — preset paper", 10.0);
    let row = pinsight::panes::model::row_of_key("clearance_mm").unwrap();
    for _ in 0..row {
        t.keys(&["j"]);
    }
    t.keys(&["Enter", "C-u"]);
    t.literal("abc");
    t.keys(&["Enter"]);
    t.wait_for("invalid value for `clearance_mm`", 10.0);
    t.keys(&["C-u"]);
    t.literal("0.3");
    t.keys(&["Enter"]);
    t.wait_for("clearance_mm = 0.3", 10.0);
    t.wait_for("up to date", 30.0);
    assert!(t.screen().contains("0.3"));
    // A corrupt log opened by path: an error in the Session pane, no exit.
    t.keys(&["o"]);
    t.wait_for("path:", 10.0);
    t.literal(&corrupt.display().to_string());
    t.keys(&["Enter"]);
    t.keys(&["1"]);
    let s = t.wait_for("Load errors (1)", 20.0);
    assert!(s.contains("dropped.mcap"), "{s}");
    assert!(t.pane_state().starts_with('0'), "the TUI must still run");
    // A corrupt log dropped on the terminal (bracketed paste of its path).
    let bad = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/batch/corrupt.mcap");
    t.cmd(&["set-buffer", "-b", "drop", &bad.display().to_string()]);
    t.cmd(&["paste-buffer", "-p", "-b", "drop", "-t", "e2e"]);
    let s = t.wait_for("Load errors (2)", 20.0);
    assert!(s.contains("corrupt.mcap"), "{s}");
    assert!(t.pane_state().starts_with('0'), "the TUI must still run");
    // An unreadable image opened by path: listed as a load error, and the
    // Yield pane counts it as an error item beside the yield, never dropped.
    let empty = dir.path().join("unreadable.png");
    std::fs::write(&empty, b"").unwrap();
    t.keys(&["o"]);
    t.wait_for("path:", 10.0);
    t.literal(&empty.display().to_string());
    t.keys(&["Enter"]);
    t.wait_for("Load errors (3)", 20.0);
    t.keys(&["7"]);
    let s = t.wait_for("1 error(s)", 30.0);
    assert!(s.contains("yield 25.0 %"), "{s}");
    assert!(s.contains("unreadable.png"), "{s}");
    assert!(t.pane_state().starts_with('0'), "the TUI must still run");
    // Quit.
    t.keys(&["q"]);
    let start = Instant::now();
    let mut dead_since: Option<Instant> = None;
    loop {
        let st = t.pane_state();
        if st.starts_with('1') {
            // An exit status (or a signal) once tmux has it: it must be 0.
            if st.len() > 2 {
                assert_eq!(st, "1 0", "exit status");
                break;
            }
            // Some tmux runs mark the pane dead without ever filling in the
            // status; the process has ended either way.
            let since = *dead_since.get_or_insert_with(Instant::now);
            if since.elapsed() > Duration::from_secs(2) {
                eprintln!("note: tmux reported the pane dead without an exit status");
                break;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "q did not quit: {st}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The live line in the real terminal: `rig-sim` writes at 2× real time
/// while `pinsight tui --follow` shows it; the panes update, `F` pauses the
/// Signals window (it stays put while cycles keep coming) and resumes it,
/// and the burst of faulty connectors raises an alarm in the status line.
#[test]
fn tui_follows_a_live_line_pauses_resumes_and_shows_an_alarm() {
    if !tmux_available() {
        eprintln!("SKIPPED: tmux is not installed; the live end-to-end test did not run");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("run.mcap");
    let img = dir.path().join("img");
    let bin = env!("CARGO_BIN_EXE_pinsight");
    let mut sim = Command::new(bin)
        .args([
            "rig-sim",
            "--rpm",
            "1500",
            "--rate",
            "2x",
            "--duration",
            "40s",
        ])
        .args(["--faults", "burst@5s-8s", "--out"])
        .arg(&log)
        .arg("--images")
        .arg(&img)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t = Tmux {
        sock: format!("pinsight-e2e-live-{}", std::process::id()),
    };
    let started = t.cmd(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        "120",
        "-y",
        "36",
        &format!(
            "env TERM=xterm-256color {bin} tui --images halfblocks --pane signals --follow {} {}",
            log.display(),
            img.display()
        ),
    ]);
    assert!(started.status.success());
    t.cmd(&["set-option", "-t", "e2e", "remain-on-exit", "on"]);
    let cycles = |s: &str| -> Option<u64> {
        let i = s.find(" cycles · ")?;
        let head = &s[..i];
        let j = head.rfind(' ')?;
        head[j + 1..].parse().ok()
    };
    let window = |s: &str| -> Option<String> {
        let i = s.find("window: ")?;
        Some(s[i..].split('│').next()?.trim().to_string())
    };
    let s1 = t.wait("following with cycles", 20.0, |s| {
        s.contains("▶ FOLLOW") && cycles(s).is_some_and(|c| c > 10)
    });
    let n1 = cycles(&s1).unwrap();
    // Panes update: more cycles, the window moves with the newest data.
    let s2 = t.wait("more cycles", 10.0, |s| {
        cycles(s).is_some_and(|c| c > n1 + 20)
    });
    assert_ne!(window(&s1), window(&s2), "the Signals window follows");
    // F pauses: the window stays while cycles keep coming.
    t.keys(&["F"]);
    let p1 = t.wait_for("PAUSED", 5.0);
    let w = window(&p1);
    let np = cycles(&p1).unwrap();
    let p2 = t.wait("cycles while paused", 10.0, |s| {
        cycles(s).is_some_and(|c| c > np + 20)
    });
    assert!(p2.contains("PAUSED"));
    assert_eq!(window(&p2), w, "paused: the window stays");
    // End resumes.
    t.keys(&["End"]);
    let r = t.wait_for("▶ FOLLOW", 5.0);
    let r2 = t.wait("window moving again", 10.0, |s| window(s) != window(&r));
    assert!(r2.contains("▶ FOLLOW"));
    // The burst of faulty connectors: the yield alarm in the status line.
    let a = t.wait_for("ALARM", 30.0);
    assert!(a.contains("yield_below"), "{a}");
    // Vision shows the latest connector, Yield counts, Session lists the alarm.
    t.keys(&["6"]);
    t.wait_for("verdict:", 10.0);
    t.keys(&["7"]);
    t.wait_for("Wilson", 10.0);
    t.keys(&["1"]);
    t.wait("the Session pane's live box", 10.0, |s| {
        s.contains("Live") && s.contains("ALARM yield_below")
    });
    t.keys(&["q"]);
    t.wait("exit", 10.0, |_| t.pane_state().starts_with('1'));
    let _ = sim.kill();
    let _ = sim.wait();
}

/// Issue 18 items 6–7 as a new user meets them in a plain 80-column SSH
/// terminal: `NO_COLOR`, the technician's config file from
/// `$XDG_CONFIG_HOME` (quit remapped to `x`, a `[follow]` table), every
/// pane at 80×24 and again at 200×60 with its axis titles and units and
/// none of the labels the issue found cut, and `y` copying the selected
/// row through tmux (`set-clipboard on` keeps OSC 52 in a tmux buffer).
#[test]
fn every_pane_at_80x24_and_200x60_no_color_config_and_copy() {
    if !tmux_available() {
        eprintln!("SKIPPED: tmux is not installed; the readability test did not run");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let cfg_dir = dir.path().join("pinsight");
    std::fs::create_dir_all(&cfg_dir).unwrap();
    std::fs::write(
        cfg_dir.join("config.toml"),
        "mouse = false\n[keys]\nquit = \"x\"\n[follow]\nwindow_s = 300.0\n[alarms]\nbell = false\n",
    )
    .unwrap();
    let t = Tmux {
        sock: format!("pinsight-e2e-fit-{}", std::process::id()),
    };
    let bin = env!("CARGO_BIN_EXE_pinsight");
    let started = t.cmd(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        "80",
        "-y",
        "24",
        &format!(
            "env TERM=xterm-256color NO_COLOR=1 XDG_CONFIG_HOME={} {bin} tui --images halfblocks",
            dir.path().display()
        ),
    ]);
    assert!(
        started.status.success(),
        "{}",
        String::from_utf8_lossy(&started.stderr)
    );
    t.cmd(&["set-option", "-t", "e2e", "remain-on-exit", "on"]);
    t.cmd(&["set-option", "-s", "set-clipboard", "on"]);
    // The config was read: listed last on the Session pane, no finding.
    let s = t.wait_for("model: clearance level", 20.0);
    assert!(!s.contains("config:"), "no finding expected:\n{s}");
    t.keys(&["G"]);
    let s = t.wait_for("config.toml", 10.0);
    let row = s.lines().find(|l| l.contains("config.toml")).unwrap();
    assert!(
        row.contains("loaded") && row.contains("TUI config"),
        "{row}"
    );
    // Each pane: what must be on it (titles with units), at both sizes.
    let panes: [(&str, &[&str]); 10] = [
        ("1", &["Files (", "status"]),
        ("2", &["time (s)", "displacement (mm)", "force (N)"]),
        (
            "3",
            &[
                "stroke (mm)",
                "load-cell force (N)",
                "crank angle from TDC (°)",
            ],
        ),
        ("4", &["Parameters — preset paper", "rhs eval"]),
        ("5", &["factor clearance", "quantity stroke"]),
        ("6", &["verdict: FAIL", "Pins (20)"]),
        ("7", &["Wilson", "Worst pins"]),
        ("8", &["Charts (", "(mm)"]),
        ("9", &["Cycles of", "SPC"]),
        ("T", &["calibrated"]),
    ];
    for (w, h) in [(80u16, 24u16), (200, 60)] {
        if w != 80 {
            t.cmd(&[
                "resize-window",
                "-t",
                "e2e",
                "-x",
                &w.to_string(),
                "-y",
                &h.to_string(),
            ]);
        }
        for (key, texts) in panes {
            t.keys(&[key]);
            let s = t.wait(&format!("pane {key} at {w}×{h}: {texts:?}"), 60.0, |s| {
                texts.iter().all(|x| s.contains(x))
            });
            let lines: Vec<&str> = s.lines().collect();
            assert!(lines.len() <= h as usize, "{w}×{h}:\n{s}");
            for l in &lines {
                assert!(l.chars().count() <= w as usize, "{w}×{h}: `{l}`");
            }
            // The cut labels the issue found, and no escape left by NO_COLOR.
            for bad in ["rhs evaluati ", "preset paper (r", "\u{1b}["] {
                assert!(!s.contains(bad), "{w}×{h} pane {key}: `{bad}`:\n{s}");
            }
        }
    }
    // `y` on the Session pane copies the selected file row from the view
    // model (full path, tab-separated) through tmux's clipboard.
    t.keys(&["1", "g", "y"]);
    t.wait_for("copied", 10.0);
    t.wait("the tmux buffer", 10.0, |_| {
        String::from_utf8_lossy(&t.cmd(&["show-buffer"]).stdout).contains("run-1200-blocks.mcap")
    });
    let copied = String::from_utf8_lossy(&t.cmd(&["show-buffer"]).stdout).into_owned();
    assert!(
        copied.starts_with("path\tkind\tstatus\tdetail\tmessage\n"),
        "{copied:?}"
    );
    // Quit is remapped to `x`: `q` does nothing, `x` quits.
    t.keys(&["q"]);
    std::thread::sleep(Duration::from_millis(500));
    assert!(t.pane_state().starts_with('0'), "q must no longer quit");
    t.keys(&["x"]);
    t.wait("exit on x", 10.0, |_| t.pane_state().starts_with('1'));
}
