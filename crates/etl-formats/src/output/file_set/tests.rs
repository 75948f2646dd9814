use super::*;

/// The commit's steps for a set of two outputs, in order.
const STEPS: [Step; 7] = [
    Step::Written,
    Step::Marked(1),
    Step::Committed,
    Step::Renamed(0),
    Step::Renamed(1),
    Step::Unmarked(1),
    Step::Unmarked(0),
];

/// The two outputs of the set under `dir`, in two directories (as `calibrate --out
/// one/c.json --observations-out two/o.json`).
fn outputs(dir: &Path) -> [PathBuf; 2] {
    [dir.join("one").join("c.json"), dir.join("two").join("o.json")]
}

/// The child of [`a_kill_at_any_step_of_the_commit_leaves_one_whole_set`] (does nothing in
/// an ordinary test run): writes the set and kills itself (SIGKILL) after the step
/// `ETLCAL_TEST_SET_STOP`.
#[test]
fn child_writes_the_set_and_is_killed() {
    let (Ok(dir), Ok(stop)) = (std::env::var("ETLCAL_TEST_SET_DIR"), std::env::var("ETLCAL_TEST_SET_STOP")) else {
        return;
    };
    let stop: usize = stop.parse().unwrap();
    let [c, o] = outputs(Path::new(&dir));
    let mut at = 0;
    let _ = write_file_set_observed(
        &[&c, &o],
        |tmp| {
            std::fs::write(&tmp[0], "new-c").unwrap();
            std::fs::write(&tmp[1], "new-o").unwrap();
            Ok(())
        },
        &mut |step| {
            assert_eq!(step, STEPS[at]);
            if at == stop {
                let pid = std::process::id().to_string();
                let _ = std::process::Command::new("kill").args(["-9", &pid]).status();
                std::thread::sleep(std::time::Duration::from_secs(60));
            }
            at += 1;
        },
    );
}

/// Runs [`child_writes_the_set_and_is_killed`] (this test binary again, in a child
/// process) on the outputs under `dir`, killed after step `stop` of [`STEPS`].
fn write_and_be_killed(dir: &Path, stop: usize) {
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["output::file_set::tests::child_writes_the_set_and_is_killed", "--exact", "--test-threads=1"])
        .env("ETLCAL_TEST_SET_DIR", dir)
        .env("ETLCAL_TEST_SET_STOP", stop.to_string())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(!status.success(), "{:?}: the child was not killed", STEPS[stop]);
}

/// What a reader of `first` then `second` gets (each through `check_input`, as every
/// reader does).
fn read_in_order(first: &Path, second: &Path) -> (String, String) {
    let read = |p: &Path| {
        super::super::check_input(p).unwrap();
        std::fs::read_to_string(p).unwrap()
    };
    (read(first), read(second))
}

/// Killed after each step of the commit (a real SIGKILL, in a child process), the set is
/// read back whole by the next reader, whichever output it reads first: the earlier set
/// before the commit, the new one from the commit on (the reader finishes the renames).
/// No marker is left after the read, and no temporary after the next write.
#[test]
fn a_kill_at_any_step_of_the_commit_leaves_one_whole_set() {
    for (stop, step) in STEPS.iter().enumerate() {
        for reversed in [false, true] {
            let d = tempfile::tempdir().unwrap();
            let [c, o] = outputs(d.path());
            for (p, text) in [(&c, "old-c"), (&o, "old-o")] {
                std::fs::create_dir_all(p.parent().unwrap()).unwrap();
                std::fs::write(p, text).unwrap();
            }
            write_and_be_killed(d.path(), stop);
            let (cr, or) = if reversed {
                let (or, cr) = read_in_order(&o, &c);
                (cr, or)
            } else {
                read_in_order(&c, &o)
            };
            let want = if stop < 2 { ("old-c", "old-o") } else { ("new-c", "new-o") };
            assert_eq!(
                (cr.as_str(), or.as_str()),
                want,
                "killed after {step:?}, read {}",
                ["c first", "o first"][reversed as usize]
            );
            for p in [&c, &o] {
                assert!(!marker_of(p).exists(), "{step:?}: {} left", marker_of(p).display());
            }
            // The next run writing there leaves only its outputs.
            write_file_set(&[&c, &o], |tmp| {
                std::fs::write(&tmp[0], "next-c").unwrap();
                std::fs::write(&tmp[1], "next-o").unwrap();
                Ok(())
            })
            .unwrap();
            for (p, text) in [(&c, "next-c"), (&o, "next-o")] {
                assert_eq!(std::fs::read_to_string(p).unwrap(), text);
                let names: Vec<_> =
                    std::fs::read_dir(p.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name()).collect();
                assert_eq!(names, [p.file_name().unwrap()], "{step:?}: leftovers {names:?}");
            }
        }
    }
}

/// A writer that finds a set left committed by a killed run completes it before it checks
/// or writes anything (a single-file write of one of its outputs included).
#[test]
fn a_writer_completes_a_committed_set_first() {
    let d = tempfile::tempdir().unwrap();
    let [c, o] = outputs(d.path());
    for (p, text) in [(&c, "old-c"), (&o, "old-o")] {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    // Killed after the first rename: c.json new, o.json old on disk.
    write_and_be_killed(d.path(), 3);
    assert_eq!(std::fs::read_to_string(&o).unwrap(), "old-o");
    // Rewriting c.json alone: o.json is first made the set's new one.
    crate::write_atomic(&c, b"alone").unwrap();
    assert_eq!(std::fs::read_to_string(&o).unwrap(), "new-o");
    assert_eq!(std::fs::read_to_string(&c).unwrap(), "alone");
    assert!(!marker_of(&c).exists() && !marker_of(&o).exists());
}

/// A marker cut anywhere (a kill while it was written) is not a commit.
#[test]
fn only_a_whole_marker_is_read() {
    let targets = [PathBuf::from("/a/c.json"), PathBuf::from("/b/with\nnewline.json")];
    let bytes = marker_bytes(4242, &targets);
    assert_eq!(parse_marker(&bytes), Some((4242, targets.to_vec())));
    for cut in 0..bytes.len() {
        assert_eq!(parse_marker(&bytes[..cut]), None, "cut at {cut}");
    }
}
