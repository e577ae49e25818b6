//! Tests of batch scripts (parsing, steps, checks, cancellation), kept
//! beside `script.rs` in their own file.

use super::*;

#[test]
fn bad_scripts_and_steps_are_reported_not_fatal() {
    let dir = tempfile::tempdir().unwrap();
    assert!(run_text("x = 1", "s", dir.path(), dir.path()).is_err());
    assert!(run_text("= nope", "s", dir.path(), dir.path()).is_err());
    let script = r#"
        [[step]]
        kind = "teleport"
        [[step]]
        kind = "set"
        values = { clearance_mm = -3 }
        [[step]]
        kind = "load"
        path = "missing.mcap"
        [[step]]
        kind = "load"
        path = "missing.mcap"
        expect_errors = 1
        [[step]]
        kind = "set"
        values = { clearance_mm = 0.2 }
        level = "ideal"
        [[step]]
        kind = "check"
        pane = "model"
        figure = "rows.len"
        op = ">="
        value = 30
        [[step]]
        kind = "check"
        pane = "model"
        figure = "level"
        op = "=="
        value = "ideal"
        [[step]]
        kind = "check"
        pane = "model"
        figure = "summary.no_such_figure"
        op = "<"
        value = 1
        [[step]]
        kind = "check"
        pane = "session"
        figure = "errors.len"
        op = "=="
        value = 2
    "#;
    let r = run_text(script, "s", dir.path(), dir.path()).unwrap();
    let o: Vec<Outcome> = r.steps.iter().map(|s| s.outcome).collect();
    assert_eq!(
        o,
        vec![
            Outcome::Error,
            Outcome::Error,
            Outcome::Error,
            Outcome::Ok,
            Outcome::Ok,
            Outcome::Pass,
            Outcome::Pass,
            Outcome::Fail,
            Outcome::Pass,
        ],
        "{}",
        r.table()
    );
    assert!(
        r.steps[1].detail.contains("clearance_mm"),
        "{}",
        r.steps[1].detail
    );
    assert!(
        r.steps[7].detail.contains("no `no_such_figure`"),
        "{}",
        r.steps[7].detail
    );
    assert!(!r.success());
    assert_eq!((r.checks_passed, r.checks_failed, r.step_errors), (3, 1, 3));
    assert!(r.table().contains("FAILED"));
}

#[test]
fn a_cancelled_run_stops_before_the_next_step_and_lists_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let script = r#"
        [[step]]
        kind = "set"
        level = "ideal"
        [[step]]
        kind = "export"
        pane = "model"
        path = "../escape.json"
    "#;
    let p = Progress::hidden();
    let r = run_text_cancellable(script, "s", dir.path(), dir.path(), &p).unwrap();
    assert_eq!(r.steps[1].outcome, Outcome::Error);
    assert!(
        r.steps[1].detail.contains("leaves the output folder"),
        "{}",
        r.steps[1].detail
    );
    assert!(!dir.path().parent().unwrap().join("escape.json").exists());
    p.cancel();
    let r = run_text_cancellable(script, "s", dir.path(), dir.path(), &p).unwrap();
    assert!(r.interrupted && r.steps.is_empty() && !r.success());
    assert!(r.table().contains("interrupted"), "{}", r.table());
    assert!(r.table().contains("files written: none"), "{}", r.table());
}

#[test]
fn ctrl_c_inside_a_study_step_stops_the_study() {
    // 5 × 4 × 5 = 100 cases of 20 revolutions: many seconds of work. A
    // cancel 100 ms in stops the cases not yet started (recorded as
    // "cancelled") and the run after this step.
    let dir = tempfile::tempdir().unwrap();
    let script = r#"
        [[step]]
        kind = "set"
        study = { clearances_mm = [0.1, 0.2, 0.3, 0.4, 0.5], speeds_rpm = [1000, 1200, 1500, 1800], warmup = 10, revs = 10 }
        [[step]]
        kind = "run"
        what = "study"
        [[step]]
        kind = "run"
        what = "model"
    "#;
    let p = Progress::hidden();
    let canceller = {
        let p = p.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(100));
            p.cancel();
        })
    };
    let r = run_text_cancellable(script, "s", dir.path(), dir.path(), &p).unwrap();
    canceller.join().unwrap();
    assert_eq!(r.steps.len(), 2, "{}", r.table());
    assert!(r.interrupted);
    assert_eq!(r.steps[1].outcome, Outcome::Error, "{}", r.table());
    assert!(
        r.steps[1].detail.contains("cancelled"),
        "{}",
        r.steps[1].detail
    );
}
