//! The set writer's promises: whole or not at all, the mode kept, a user's file never
//! thrown away, stale temporaries removed.

use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::PathBuf;

use super::*;

fn names(dir: &Path) -> Vec<String> {
    top_level_names(dir).unwrap()
}

#[test]
fn a_set_replaces_the_earlier_set_whole_or_not_at_all() {
    let d = tempfile::tempdir().unwrap();
    let set = d.path().join("out");
    let write = |tag: &'static str, fail: bool| {
        write_dir_set(&set, &["a", "sub"], move |s| {
            write_atomic(&s.join("a"), tag.as_bytes())?;
            std::fs::create_dir(s.join("sub")).unwrap();
            if fail {
                return Err(Error::invalid("test", "failed half-way"));
            }
            write_atomic(&s.join("sub").join("b"), tag.as_bytes())
        })
    };
    write("one", false).unwrap();
    std::fs::set_permissions(&set, std::fs::Permissions::from_mode(0o750)).unwrap();
    assert!(write("two", true).is_err());
    assert_eq!(std::fs::read_to_string(set.join("sub/b")).unwrap(), "one");
    write("three", false).unwrap();
    assert_eq!(std::fs::read_to_string(set.join("a")).unwrap(), "three");
    assert_eq!(std::fs::read_to_string(set.join("sub/b")).unwrap(), "three");
    assert_eq!(std::fs::metadata(&set).unwrap().mode() & 0o777, 0o750);
    assert_eq!(names(&set), [SET_MANIFEST, "a", "sub"]);
    assert_eq!(names(d.path()), ["out"]);
    // A file of the user's in the directory is never thrown away; a trailing slash is fine.
    std::fs::write(set.join("notes.txt"), "mine").unwrap();
    let slash = PathBuf::from(format!("{}/", set.display()));
    let e = write_dir_set(&slash, &["a"], |_| Ok(())).unwrap_err().to_string();
    assert!(e.contains("holds notes.txt") && e.contains("new or empty directory"), "{e}");
    std::fs::remove_file(set.join("notes.txt")).unwrap();
    // Names of the earlier set (its manifest) may go: "sub" is not in this set.
    write_dir_set(&slash, &["a"], |s| write_atomic(&s.join("a"), b"four")).unwrap();
    assert_eq!(names(&set), [SET_MANIFEST, "a"]);
}

#[test]
fn temporaries_of_dead_processes_are_removed_by_the_next_set() {
    let d = tempfile::tempdir().unwrap();
    // No process has a pid this large (Linux's pid_max is at most 2^22).
    let stale_dir = d.path().join(".set.tmp99999998");
    std::fs::create_dir(&stale_dir).unwrap();
    std::fs::write(stale_dir.join("x"), "torn").unwrap();
    let other = d.path().join(".b.json.tmp99999999");
    std::fs::write(&other, "another output's").unwrap();
    write_dir_set(&d.path().join("set"), &["x"], |s| write_atomic(&s.join("x"), b"x")).unwrap();
    assert_eq!(names(d.path()), [".b.json.tmp99999999", "set"]);
    assert_eq!(names(&d.path().join("set")), [SET_MANIFEST, "x"]);
}

#[test]
fn a_set_over_a_file_or_a_root_is_refused_and_nothing_is_written() {
    let d = tempfile::tempdir().unwrap();
    let file = d.path().join("f");
    std::fs::write(&file, "mine").unwrap();
    let ran = std::cell::Cell::new(false);
    let run = |_: &Path| {
        ran.set(true);
        Ok(())
    };
    let e = write_dir_set(&file, &["a"], run).unwrap_err().to_string();
    assert!(e.contains("exists and is not a directory"), "{e}");
    let e = write_dir_set(Path::new("/"), &["a"], run).unwrap_err().to_string();
    assert!(e.contains("/: not a file path"), "{e}");
    assert!(!ran.get());
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    assert_eq!(names(d.path()), ["f"]);
}
