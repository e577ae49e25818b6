//! Unit tests of `output::atomic` (beside it, so the module reads on its own).

use super::*;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn write_file_replaces_and_leaves_no_temporary() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("a.json");
    write_file(&p, b"old").unwrap();
    write_file(&p, b"new").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"new");
    assert_eq!(names(d.path()), vec!["a.json"]);
    // A folder that does not exist yet is created.
    let q = d.path().join("sub/b.csv");
    write_file(&q, b"x").unwrap();
    assert_eq!(std::fs::read(&q).unwrap(), b"x");
}

#[test]
fn report_dropped_before_commit_keeps_the_old_files() {
    let d = tempfile::tempdir().unwrap();
    let mut r = Report::new_in(d.path()).unwrap();
    r.add("a", b"1").unwrap();
    r.add("b", b"1").unwrap();
    r.commit().unwrap();
    let mut r = Report::new_in(d.path()).unwrap();
    r.add("a", b"2").unwrap();
    drop(r); // an error while producing "b"
    assert_eq!(std::fs::read(d.path().join("a")).unwrap(), b"1");
    assert_eq!(std::fs::read(d.path().join("b")).unwrap(), b"1");
    assert_eq!(names(d.path()), vec!["a", "b"]);
}

#[test]
fn commit_writes_every_file_and_names_them() {
    let d = tempfile::tempdir().unwrap();
    let mut r = Report::new_in(d.path()).unwrap();
    r.add("x.json", b"{}").unwrap();
    r.add("y.csv", b"a\n").unwrap();
    r.add("x.json", b"[]").unwrap();
    let files = r.commit().unwrap();
    assert_eq!(files, vec![d.path().join("y.csv"), d.path().join("x.json")]);
    assert_eq!(std::fs::read(d.path().join("x.json")).unwrap(), b"[]");
    assert_eq!(names(d.path()), vec!["x.json", "y.csv"]);
}

#[test]
fn names_that_leave_the_folder_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let mut r = Report::new_in(d.path()).unwrap();
    // (`a/b`, a file below the folder, is a report file since partitioned
    // data sets: `nested_files_replace_their_whole_top_folder`.)
    for bad in ["../x", "a/../b", "", "..", "/x"] {
        assert!(r.add(bad, b"1").is_err(), "{bad}");
    }
}

#[test]
fn stale_temporaries_of_dead_processes_are_swept() {
    let d = tempfile::tempdir().unwrap();
    // pid 0 is never a user process: its temporaries are stale.
    let stale = d.path().join(format!(".a{TMP_MARK}0.7"));
    std::fs::write(&stale, b"half").unwrap();
    let mine = temp_path(d.path(), "b");
    std::fs::write(&mine, b"busy").unwrap();
    let _r = Report::new_in(d.path()).unwrap();
    assert!(!stale.exists());
    assert!(mine.exists(), "a live process's temporary is kept");
}

#[test]
fn disk_full_names_the_file_and_the_space() {
    // A real full filesystem: /dev/full fails every write with ENOSPC
    // (Linux); we cannot create a temporary there, so check the error
    // mapping on the errno the kernel gives.
    let e = stage_error(
        Path::new("/out/yield.json"),
        Path::new("/"),
        2_500_000,
        std::io::Error::from_raw_os_error(28),
    );
    let msg = e.to_string();
    assert!(msg.contains("/out/yield.json"), "{msg}");
    assert!(msg.contains("needed 2500000 bytes"), "{msg}");
    assert!(matches!(e, OutputError::DiskFull { .. }));
}

#[test]
fn a_switch_keeps_everything_else_in_the_folder() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir_all(out.join("sub")).unwrap();
    std::fs::write(out.join("sub/keep.txt"), b"mine").unwrap();
    std::fs::write(out.join("notes.txt"), b"user").unwrap();
    std::fs::write(out.join("a.json"), b"old").unwrap();
    let mut r = Report::new_in(&out).unwrap();
    assert_eq!(r.mode(), CommitMode::Switch);
    r.add("a.json", b"new").unwrap();
    r.add("b.csv", b"x").unwrap();
    let (_, mode) = r.commit_with_mode().unwrap();
    assert_eq!(mode, CommitMode::Switch);
    assert_eq!(names(&out), vec!["a.json", "b.csv", "notes.txt", "sub"]);
    assert_eq!(std::fs::read(out.join("a.json")).unwrap(), b"new");
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"user");
    assert_eq!(std::fs::read(out.join("sub/keep.txt")).unwrap(), b"mine");
    // Nothing left beside the folder either.
    assert_eq!(names(d.path()), vec!["out"]);
}

#[test]
fn the_users_subfolders_are_in_the_new_folder_at_the_exchange() {
    // A kill right after the exchange must not leave the user's subfolder
    // only in the old folder moved aside: the staged folder holds its
    // whole tree (hard links of the files, new folders) before the switch.
    use std::os::unix::fs::MetadataExt;
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir_all(out.join("sub/deeper")).unwrap();
    std::fs::write(out.join("sub/keep.txt"), b"mine").unwrap();
    std::fs::write(out.join("sub/deeper/more.txt"), b"also").unwrap();
    std::os::unix::fs::symlink("keep.txt", out.join("sub/link")).unwrap();
    let ino = std::fs::metadata(out.join("sub/deeper/more.txt"))
        .unwrap()
        .ino();
    let mut r = Report::new_in(&out).unwrap();
    r.add("a.json", b"new").unwrap();
    let stage = r.stage.clone();
    let mut carried = 0;
    for e in std::fs::read_dir(&out).unwrap() {
        let e = e.unwrap();
        assert!(carry(&e, &stage.join(e.file_name()), &mut carried));
    }
    assert_eq!(carried, 5, "sub, keep.txt, deeper, more.txt, link");
    let staged = stage.join("sub/deeper/more.txt");
    assert_eq!(std::fs::metadata(&staged).unwrap().ino(), ino);
    assert!(
        std::fs::symlink_metadata(stage.join("sub/link"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    drop(r);
    // And through a whole commit: same files, same inodes, nothing beside.
    let mut r = Report::new_in(&out).unwrap();
    r.add("a.json", b"new").unwrap();
    assert_eq!(r.commit_with_mode().unwrap().1, CommitMode::Switch);
    assert_eq!(
        std::fs::read(out.join("sub/deeper/more.txt")).unwrap(),
        b"also"
    );
    assert_eq!(
        std::fs::metadata(out.join("sub/deeper/more.txt"))
            .unwrap()
            .ino(),
        ino
    );
    assert_eq!(
        std::fs::read_link(out.join("sub/link")).unwrap(),
        Path::new("keep.txt")
    );
    assert_eq!(names(d.path()), vec!["out"]);
}

#[test]
fn an_old_folder_left_by_a_killed_switch_gives_back_what_is_missing() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("a.json"), b"new").unwrap();
    // What a switch killed before moving the subfolder back leaves:
    // the old folder, no marker, under pid 0 (never alive).
    let old = d.path().join(format!(".out{TMP_MARK}0.3"));
    std::fs::create_dir_all(old.join("sub")).unwrap();
    std::fs::write(old.join("sub/keep.txt"), b"mine").unwrap();
    std::fs::write(old.join("a.json"), b"old").unwrap();
    // And a staging folder killed while staging (it holds its marker).
    let stage = d.path().join(format!(".out{TMP_MARK}0.4"));
    make_stage(&stage).unwrap();
    std::fs::write(stage.join("a.json"), b"half").unwrap();
    let r = Report::new_in(&out).unwrap();
    drop(r);
    assert_eq!(names(d.path()), vec!["out"]);
    assert_eq!(names(&out), vec!["a.json", "sub"]);
    assert_eq!(std::fs::read(out.join("a.json")).unwrap(), b"new");
    assert_eq!(std::fs::read(out.join("sub/keep.txt")).unwrap(), b"mine");
}

#[test]
fn the_current_directory_is_never_switched() {
    let cwd = std::env::current_dir().unwrap().canonicalize().unwrap();
    assert!(holds_cwd(&cwd));
    assert!(holds_cwd(cwd.parent().unwrap()));
    let d = tempfile::tempdir().unwrap();
    assert!(!holds_cwd(&d.path().canonicalize().unwrap()));
}

#[test]
fn a_link_is_followed_and_kept() {
    let d = tempfile::tempdir().unwrap();
    let target = d.path().join("real.csv");
    std::fs::write(&target, "old").unwrap();
    let link = d.path().join("link.csv");
    std::os::unix::fs::symlink("real.csv", &link).unwrap();
    write_file(&link, b"new").unwrap();
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    assert_eq!(names(d.path()), ["link.csv", "real.csv"]);
}

#[test]
fn permissions_of_the_replaced_file_are_kept() {
    use std::os::unix::fs::PermissionsExt;
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("a.json");
    std::fs::write(&f, "old").unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
    write_file(&f, b"new").unwrap();
    let mode = std::fs::metadata(&f).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
}

#[test]
fn a_named_pipe_is_written_through_not_replaced() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("pipe");
    rustix::fs::mknodat(
        rustix::fs::CWD,
        &fifo,
        rustix::fs::FileType::Fifo,
        rustix::fs::Mode::from_raw_mode(0o600),
        0,
    )
    .unwrap();
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    write_file(&fifo, b"through the pipe").unwrap();
    assert_eq!(reader.join().unwrap(), b"through the pipe");
    let ft = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(std::os::unix::fs::FileTypeExt::is_fifo(&ft));
    assert_eq!(names(d.path()), ["pipe"]);
}

#[test]
fn a_folder_is_not_a_file_and_a_file_is_not_a_folder() {
    let d = tempfile::tempdir().unwrap();
    let e = write_file(d.path(), b"x").unwrap_err().to_string();
    assert!(e.contains("is a folder"), "{e}");
    let f = d.path().join("plain");
    std::fs::write(&f, "mine").unwrap();
    let e = Report::new_in(&f).unwrap_err().to_string();
    assert!(e.contains("not a folder") && e.contains("plain"), "{e}");
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "mine");
}

#[test]
fn a_report_into_a_linked_folder_keeps_the_link() {
    let d = tempfile::tempdir().unwrap();
    let real = d.path().join("real");
    std::fs::create_dir(&real).unwrap();
    std::fs::write(real.join("old.txt"), "keep").unwrap();
    let link = d.path().join("out");
    std::os::unix::fs::symlink("real", &link).unwrap();
    let mut r = Report::new_in(&link).unwrap();
    r.add("a.json", b"{}").unwrap();
    r.commit().unwrap();
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(names(&real), ["a.json", "old.txt"]);
    assert_eq!(names(d.path()), ["out", "real"]);
}

#[test]
fn nested_files_replace_their_whole_top_folder() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let mut r = Report::new_in(&out).unwrap();
    r.add("a.json", b"1").unwrap();
    r.add("images/part=A/lot=1/data.parquet", b"old-1").unwrap();
    r.add("images/part=A/lot=2/data.parquet", b"old-2").unwrap();
    r.commit().unwrap();
    std::fs::write(out.join("user.txt"), b"mine").unwrap();
    // The second run has only lot 1: lot 2 of the first must not survive.
    let mut r = Report::new_in(&out).unwrap();
    r.add("images/part=A/lot=1/data.parquet", b"new-1").unwrap();
    r.commit().unwrap();
    assert_eq!(
        std::fs::read(out.join("images/part=A/lot=1/data.parquet")).unwrap(),
        b"new-1"
    );
    assert!(!out.join("images/part=A/lot=2").exists());
    assert_eq!(std::fs::read(out.join("a.json")).unwrap(), b"1");
    assert_eq!(std::fs::read(out.join("user.txt")).unwrap(), b"mine");
    assert_eq!(names(&out), vec!["a.json", "images", "user.txt"]);
}

#[test]
fn nested_names_are_plain_and_a_file_is_not_a_folder() {
    let d = tempfile::tempdir().unwrap();
    let mut r = Report::new_in(d.path()).unwrap();
    for bad in ["../x", "a/../b", "a//b", "/abs", "a/", "a/./b"] {
        assert!(r.add(bad, b"x").is_err(), "{bad}");
    }
    r.add("t", b"x").unwrap();
    assert!(r.add("t/inner", b"x").is_err());
}

#[test]
fn removed_entries_go_in_either_commit_mode() {
    let d = tempfile::tempdir().unwrap();
    // Switch mode (a folder of its own) and renames (the current folder
    // cannot be switched; tested through the mode the report chose).
    let out = d.path().join("out");
    let mut r = Report::new_in(&out).unwrap();
    r.add("pins/part=A/data.parquet", b"p").unwrap();
    r.add("keep.csv", b"k").unwrap();
    r.commit().unwrap();
    let mut r = Report::new_in(&out).unwrap();
    r.add("pins.parquet", b"one file now").unwrap();
    r.remove("pins");
    r.remove("pins.parquet"); // staged too: written, not removed
    let (_, mode) = r.commit_with_mode().unwrap();
    assert_eq!(mode, CommitMode::Switch);
    assert_eq!(names(&out), vec!["keep.csv", "pins.parquet"]);
    assert_eq!(
        std::fs::read(out.join("pins.parquet")).unwrap(),
        b"one file now"
    );
    // Renames mode: a report into a folder that cannot be switched (it
    // holds more entries than a switch carries is slow to build; use the
    // renames path directly).
    let mut r = Report::new_in(&out).unwrap();
    r.mode = CommitMode::Renames;
    r.add("pins/part=B/data.parquet", b"q").unwrap();
    r.remove("pins.parquet");
    r.commit().unwrap();
    assert_eq!(names(&out), vec!["keep.csv", "pins"]);
    assert_eq!(names(&out.join("pins")), vec!["part=B"]);
}
