//! The follower's tests (beside it: `follower.rs` is at the house's 800-line mark).

use super::*;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// A rig writing at 8× for `duration_s` s, a new file every 2 s, into `dir`.
fn rotating_rig(dir: &std::path::Path, duration_s: f64) -> crate::live::sim::SimOptions {
    crate::live::sim::SimOptions {
        out: dir.join("run.mcap"),
        rpm: 1500.0,
        rate: 8.0,
        duration_s,
        rotate_s: Some(2.0),
        spindle_hz: 1000.0,
        force_hz: 2000.0,
        displacement_hz: 2000.0,
        ..Default::default()
    }
}

/// Runs the rig while `f` follows it, then polls until all is finished;
/// `each` sees the follower after every poll while the rig writes.
fn follow_to_end(
    f: &mut Follower,
    opts: crate::live::sim::SimOptions,
    mut each: impl FnMut(&Follower),
) -> crate::live::sim::SimReport {
    let rig =
        std::thread::spawn(move || crate::live::sim::run(&opts, &AtomicBool::new(false)).unwrap());
    while !rig.is_finished() {
        f.poll(None);
        each(f);
        std::thread::sleep(Duration::from_millis(20));
    }
    let report = rig.join().unwrap();
    for _ in 0..100 {
        f.poll(None);
        if f.all_finished() && !f.behind() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(f.all_finished());
    report
}

#[test]
fn rotated_logs_once_finished_are_let_go_but_still_listed() {
    let d = tempfile::tempdir().unwrap();
    let first = d.path().join("run-001.mcap");
    let mut f = Follower::new(FollowInputs {
        paths: vec![first],
        ..Default::default()
    });
    let mut most_logs = 0;
    let report = follow_to_end(&mut f, rotating_rig(d.path(), 8.0), |f| {
        most_logs = most_logs.max(f.logs.len())
    });
    assert!(report.files.len() >= 4, "{:?}", report.files);
    // Every file listed once, finished; only the newest still held.
    let s = f.summary();
    assert_eq!(s.logs.len(), report.files.len(), "{:?}", s.logs);
    assert!(
        s.logs.iter().all(|l| l.state == FileState::Finished),
        "{:?}",
        s.logs
    );
    assert_eq!(f.logs.len(), 1);
    assert!(
        most_logs <= 2,
        "at most the finishing and the new file: {most_logs}"
    );
}

#[test]
fn a_finished_log_found_again_in_its_folder_is_not_followed_again() {
    // A folder of a rig's rotated logs, all still on disk (no archive job).
    // Once the folder's tail has forgotten their names (its window is
    // 120 s; forgotten at once here), a whole listing finds the finished
    // logs again: they must not be read again from the start (their cycles
    // would count twice).
    let d = tempfile::tempdir().unwrap();
    let mut f = Follower::new(FollowInputs {
        paths: vec![d.path().to_path_buf()],
        ..Default::default()
    });
    let report = follow_to_end(&mut f, rotating_rig(d.path(), 6.0), |_| {});
    assert!(report.files.len() >= 3, "{:?}", report.files);
    let before = f.summary();
    assert!(before.cycles > 0);
    assert_eq!(before.logs.len(), report.files.len());
    for d in &mut f.folders {
        d.tail.forget_all();
    }
    for _ in 0..5 {
        f.poll(None);
    }
    let after = f.summary();
    assert_eq!(after.cycles, before.cycles, "cycles counted again");
    assert_eq!(after.logs.len(), before.logs.len(), "{:?}", after.logs);
}
