use std::os::unix::fs::{MetadataExt, PermissionsExt};

use super::*;
use crate::write_atomic;

/// The sorted entry names of `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[test]
fn an_output_that_is_an_input_is_refused_by_path_link_and_inode() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("o.json");
    std::fs::write(&input, "in").unwrap();
    let hard = d.path().join("hard.json");
    std::fs::hard_link(&input, &hard).unwrap();
    let soft = d.path().join("soft.json");
    std::os::unix::fs::symlink(&input, &soft).unwrap();
    let dotted = d.path().join(".").join("o.json");
    for out in [&input, &hard, &soft, &dotted] {
        let e = check_paths(&[&input], &[Output::File(out)]).unwrap_err().to_string();
        assert!(e.contains("is the input") && !e.contains('\n'), "{e}");
    }
    // A directory output holding an input (report --calibration D/index.html --out D).
    let e = check_paths(&[&input], &[Output::Dir(d.path())]).unwrap_err().to_string();
    assert!(e.contains("holds the input"), "{e}");
    let e = check_paths(&[], &[Output::File(&input), Output::File(&hard)]).unwrap_err().to_string();
    assert!(e.contains("two outputs"), "{e}");
    assert_eq!(std::fs::read_to_string(&input).unwrap(), "in");
}

#[test]
fn non_regular_inputs_and_outputs_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("fifo");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let e = check_paths(&[&fifo], &[]).unwrap_err().to_string();
    assert!(e.contains("not a regular file: refused as an input"), "{e}");
    // read_json refuses it before opening (opening a FIFO would block).
    assert!(crate::read_json::<serde_json::Value>(&fifo, "x/1").unwrap_err().to_string().contains("not a regular"));
    for out in [fifo.as_path(), Path::new("/dev/null"), d.path()] {
        let e = write_atomic(out, b"x").unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo_like());
    let file = d.path().join("f");
    std::fs::write(&file, "f").unwrap();
    let e = check_paths(&[], &[Output::Dir(&file)]).unwrap_err().to_string();
    assert!(e.contains("not a directory"), "{e}");
    let dangling = d.path().join("dangling");
    std::os::unix::fs::symlink(d.path().join("nowhere"), &dangling).unwrap();
    assert!(write_atomic(&dangling, b"x").unwrap_err().to_string().contains("dangling"));
    assert!(!d.path().join("nowhere").exists());
}

trait FifoLike {
    fn is_fifo_like(&self) -> bool;
}
impl FifoLike for std::fs::FileType {
    fn is_fifo_like(&self) -> bool {
        use std::os::unix::fs::FileTypeExt;
        self.is_fifo()
    }
}

#[test]
fn a_replaced_file_keeps_its_mode_a_symlink_is_written_through_read_only_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let target = d.path().join("t.json");
    std::fs::write(&target, "old").unwrap();
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o600)).unwrap();
    let link = d.path().join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    write_atomic(&link, b"new").unwrap();
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    assert_eq!(std::fs::metadata(&target).unwrap().mode() & 0o777, 0o600);
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o444)).unwrap();
    let e = write_atomic(&target, b"newer").unwrap_err().to_string();
    assert!(e.contains("read-only"), "{e}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    assert_eq!(names(d.path()), ["link.json", "t.json"]);
}

#[test]
fn nested_temporaries_of_dead_processes_are_removed_and_a_set_writes_none() {
    let d = tempfile::tempdir().unwrap();
    // What a killed set of earlier versions left: a temporary of a temporary.
    for stale in ["..o.json.tmp99999999.tmp99999999", "...o.json.tmp99999997.tmp99999997.tmp99999997"] {
        std::fs::write(d.path().join(stale), "torn").unwrap();
    }
    // Not temporaries of o.json: kept.
    for kept in ["..o.json.tmp99999999", ".o.json.tmp", ".o.json.tmpx1", ".xo.json.tmp99999999"] {
        std::fs::write(d.path().join(kept), "someone's").unwrap();
    }
    let (a, b) = (d.path().join("o.json"), d.path().join("c.json"));
    write_file_set(&[&a, &b], |tmp| {
        write_atomic(&tmp[0], b"new")?;
        write_atomic(&tmp[1], b"new")?;
        // The set's writers write its temporaries in place: no temporary of a temporary.
        assert!(
            names(d.path()).iter().all(|n| !n.contains(".tmp")
                || n.matches(".tmp").count() == 1
                || n.starts_with("..o.json.tmp99999999")),
            "{:?}",
            names(d.path())
        );
        Ok(())
    })
    .unwrap();
    assert_eq!(
        names(d.path()),
        ["..o.json.tmp99999999", ".o.json.tmp", ".o.json.tmpx1", ".xo.json.tmp99999999", "c.json", "o.json"]
    );
}

#[test]
fn a_name_too_long_for_its_temporary_still_writes_and_cleans_up() {
    let d = tempfile::tempdir().unwrap();
    // 250 bytes: the name fits, `.NAME.tmpPID` would not (255 bytes at most).
    let (long_a, long_b) = (format!("{}a.json", "x".repeat(244)), format!("{}b.json", "x".repeat(244)));
    let (a, b) = (d.path().join(&long_a), d.path().join(&long_b));
    write_atomic(&a, b"one").unwrap();
    write_file_set(&[&a, &b], |tmp| {
        assert!(tmp.iter().all(|t| t.file_name().unwrap().len() <= MAX_NAME_BYTES));
        // Two names alike in their first bytes still get two temporaries.
        assert_ne!(tmp[0], tmp[1]);
        tmp.iter().try_for_each(|t| write_atomic(t, b"two"))
    })
    .unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), b"two");
    // A killed run's temporary of the long name is found by the next write.
    let stale = temp_of(d.path(), std::ffi::OsStr::new(&long_a), 99_999_999);
    std::fs::write(&stale, "torn").unwrap();
    write_atomic(&a, b"three").unwrap();
    assert_eq!(names(d.path()), [long_a, long_b]);
}

#[test]
fn temporaries_of_dead_processes_are_removed_by_the_next_write() {
    let d = tempfile::tempdir().unwrap();
    // No process has a pid this large (Linux's pid_max is at most 2^22).
    let stale = d.path().join(".a.json.tmp99999999");
    std::fs::write(&stale, "torn").unwrap();
    let stale_dir = d.path().join(".set.tmp99999998");
    std::fs::create_dir(&stale_dir).unwrap();
    let other = d.path().join(".b.json.tmp99999999");
    std::fs::write(&other, "another output's").unwrap();
    write_atomic(&d.path().join("a.json"), b"{}").unwrap();
    // A set directory's writer (the etlcal binary's) removes its stale directories so.
    remove_stale_temps(d.path(), std::ffi::OsStr::new("set"));
    assert_eq!(names(d.path()), [".b.json.tmp99999999", "a.json"]);
    // This process's own temporary is never taken for stale.
    let own = temp_sibling(d.path(), std::ffi::OsStr::new("c.json"));
    std::fs::write(&own, "mine").unwrap();
    remove_stale_temps(d.path(), std::ffi::OsStr::new("c.json"));
    assert!(own.exists());
}

#[test]
fn a_file_set_is_renamed_last_and_left_out_whole_on_error() {
    let d = tempfile::tempdir().unwrap();
    let (a, b) = (d.path().join("o.json"), d.path().join("sub").join("c.json"));
    std::fs::create_dir(d.path().join("sub")).unwrap();
    for p in [&a, &b] {
        std::fs::write(p, "old").unwrap();
    }
    let e = write_file_set(&[&a, &b], |tmp| {
        write_atomic(&tmp[0], b"new")?;
        Err::<(), _>(Error::Output { path: b.clone(), source: std::io::Error::other("No space left on device") })
    });
    assert!(e.is_err());
    assert_eq!([std::fs::read_to_string(&a).unwrap(), std::fs::read_to_string(&b).unwrap()], ["old", "old"]);
    assert_eq!(names(d.path()), ["o.json", "sub"]);
    write_file_set(&[&a, &b], |tmp| tmp.iter().try_for_each(|t| write_atomic(t, b"new"))).unwrap();
    assert_eq!([std::fs::read_to_string(&a).unwrap(), std::fs::read_to_string(&b).unwrap()], ["new", "new"]);
    assert_eq!(names(&d.path().join("sub")), ["c.json"]);
    let dotted = d.path().join(".").join("o.json");
    let e = write_file_set(&[&a, &dotted], |_| Ok(())).unwrap_err().to_string();
    assert!(e.contains("two outputs"), "{e}");
}
