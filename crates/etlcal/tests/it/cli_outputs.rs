//! Outputs and inputs (docs/RELIABILITY.md, "Outputs"): an output that is an
//! input, or exists and is not a regular file, is refused before anything is read, in one
//! line with exit status 1, inputs and earlier outputs intact and no temporary left; sets
//! of files are replaced whole, also when the writer is killed at a random moment.
use std::collections::BTreeMap;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use rand::{Rng, SeedableRng};

use crate::common::tree;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// The time every run here writes into a report (`SOURCE_DATE_EPOCH`): sets are compared
/// byte for byte, and a report's index.html says when it was written, to the minute.
const REPORT_TIME: (&str, &str) = ("SOURCE_DATE_EPOCH", "1796214896");

fn etlcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(args)
        .current_dir(ROOT)
        .env(REPORT_TIME.0, REPORT_TIME.1)
        .output()
        .expect("run etlcal")
}

fn ok(args: &[&str]) -> Output {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The one stderr line of a run that failed with status 1.
fn refused(args: &[&str]) -> String {
    let out = etlcal(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    assert!(err.starts_with("etlcal: error: "), "{args:?}: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn thermal_table(path: &Path) {
    let mut text = String::from("temperature_c,e_in_ma,e_t_ma\n");
    for t in [27.0, 29.0, 31.0, 33.0, 35.0, 37.0] {
        for e in [40.0, 80.0, 120.0, 160.0, 200.0, 240.0] {
            let e_t = etl_core::thermal::ThermalSurface::PAPER.e_t_ma(e, t).unwrap();
            text.push_str(&format!("{t},{e},{e_t}\n"));
        }
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn an_output_that_is_an_input_is_refused_before_reading() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n);
    std::fs::copy(format!("{ROOT}/fixtures/golden/observations.json"), p("o.json")).unwrap();
    std::fs::write(p("d.json"), r#"{"format": "etlcal.dataset/1"}"#).unwrap();
    thermal_table(&p("t.csv"));
    std::fs::create_dir(p("D")).unwrap();
    std::fs::write(p("D/index.html"), "a calibration named index.html").unwrap();
    std::os::unix::fs::symlink(p("o.json"), p("link.json")).unwrap();
    std::fs::hard_link(p("t.csv"), p("hard.csv")).unwrap();
    std::fs::copy(format!("{ROOT}/fixtures/service/calibration.json"), p("c.json")).unwrap();
    std::os::unix::fs::symlink(p("c.json"), p("c-link.yaml")).unwrap();
    let before = tree(d.path());
    let q = |n: &str| -> &'static str { Box::leak(p(n).to_str().unwrap().to_owned().into_boxed_str()) };
    let (o, d_json, t_csv) = (q("o.json"), q("d.json"), q("t.csv"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["calibrate", "--observations", o, "--out", o], "is the input"),
        (vec!["calibrate", "--observations", o, "--out", q("link.json")], "is the input"),
        (vec!["calibrate", "--dataset", d_json, "--observations-out", d_json, "--out", q("c.json")], "is the input"),
        (vec!["thermal", "fit", t_csv, "--out", t_csv], "is the input"),
        (
            vec!["export", "--calibration", q("c.json"), "--e-com", "140", "--format", "opencv", "--out", q("c.json")],
            "is the input",
        ),
        (
            vec![
                "export",
                "--calibration",
                q("c.json"),
                "--e-com",
                "140",
                "--format",
                "ros",
                "--out",
                q("c-link.yaml"),
            ],
            "is the input",
        ),
        (vec!["thermal", "fit", t_csv, "--out", q("hard.csv")], "is the input"),
        (vec!["report", "--calibration", q("D/index.html"), "--out", q("D")], "holds the input"),
        (
            vec!["thermal", "calibrate", "--virtual", "--quick", "--out", q("t.json"), "--table", q("t.json")],
            "two outputs",
        ),
    ];
    for (args, why) in cases {
        let err = refused(&args);
        assert!(err.contains(why), "{args:?}: {err}");
        assert_eq!(tree(d.path()), before, "{args:?} changed the directory");
    }
}

#[test]
fn outputs_that_are_not_regular_files_are_refused_modes_kept_symlinks_written_through() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n);
    thermal_table(&p("t.csv"));
    assert!(Command::new("mkfifo").arg(p("fifo")).status().unwrap().success());
    std::fs::create_dir(p("dir")).unwrap();
    for out in [s(&p("fifo")), "/dev/null", s(&p("dir"))] {
        let err = refused(&["thermal", "fit", s(&p("t.csv")), "--out", out]);
        assert!(err.contains("not a regular file"), "{out}: {err}");
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    assert!(std::fs::metadata(p("fifo")).unwrap().file_type().is_fifo());
    // A FIFO as an input is refused before it is opened (opening it would block).
    let err = refused(&["calibrate", "--observations", s(&p("fifo")), "--out", s(&p("c.json"))]);
    assert!(err.contains("not a regular file: refused as an input"), "{err}");
    // A replaced file keeps its mode; a symlink is written through and kept.
    std::fs::write(p("th.json"), "old").unwrap();
    std::fs::set_permissions(p("th.json"), std::fs::Permissions::from_mode(0o600)).unwrap();
    std::os::unix::fs::symlink(p("th.json"), p("link.json")).unwrap();
    ok(&["thermal", "fit", s(&p("t.csv")), "--out", s(&p("link.json"))]);
    assert!(std::fs::symlink_metadata(p("link.json")).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(p("th.json")).unwrap().contains("etlcal.thermal/1"));
    assert_eq!(std::fs::metadata(p("th.json")).unwrap().permissions().mode() & 0o777, 0o600);
    let names: Vec<_> = std::fs::read_dir(d.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 5, "no temporary left: {names:?}");
}

#[test]
fn an_existing_output_directory_with_a_trailing_slash_works_and_foreign_files_are_kept() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("sim");
    std::fs::create_dir(&out).unwrap();
    let slash = format!("{}/", out.display());
    ok(&["simulate", "--out", &slash, "--observations-only", "--seed", "3"]);
    ok(&["simulate", "--out", &slash, "--observations-only", "--seed", "4"]);
    assert!(out.join("observations.json").is_file());
    std::fs::write(out.join("calibration.json"), "the user's").unwrap();
    let before = tree(&out);
    let err = refused(&["simulate", "--out", &slash, "--observations-only"]);
    assert!(err.contains("holds calibration.json"), "{err}");
    assert_eq!(tree(&out), before);
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1, "no temporary left");
}

/// Runs `args` and kills it (SIGKILL) after `delay_ms`; true if it had finished before.
fn kill_after(args: &[&str], delay_ms: u64) -> bool {
    let mut child = Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(args)
        .current_dir(ROOT)
        .env(REPORT_TIME.0, REPORT_TIME.1)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(delay_ms));
    let finished = child.try_wait().unwrap().is_some();
    let _ = child.kill();
    let _ = child.wait();
    finished
}

/// `kills` runs of `args_of(k)` (k alternates between 0 and 1 once a run completed) over a
/// directory holding a whole set, kill i at a random moment of the i-th of `kills` equal
/// slices of a run's duration (every phase of the run is hit, whatever the draws); after
/// every kill the directory holds exactly one of the two complete sets. Returns how many
/// runs were killed before they finished.
fn kill_test(name: &str, kills: usize, args_of: impl Fn(usize, &Path) -> Vec<String>) -> usize {
    kill_test_seen(name, kills, args_of, tree)
}

/// The files under `dir` as the next reader sees them: each read once through
/// `etl_formats::output::check_input` (which finishes a committed set's renames, as every
/// reader does), then listed without hidden entries (a killed writer's temporaries and
/// markers, which the next writer removes).
fn tree_as_read(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let names: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    for p in names.iter().filter(|p| !hidden(p)) {
        etl_formats::output::check_input(p).unwrap();
    }
    tree(dir).into_iter().filter(|(p, _)| !hidden(p)).collect()
}

fn hidden(p: &Path) -> bool {
    p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'))
}

/// [`kill_test`] with the directory compared as `seen` shows it.
fn kill_test_seen(
    name: &str,
    kills: usize,
    args_of: impl Fn(usize, &Path) -> Vec<String>,
    seen: fn(&Path) -> BTreeMap<PathBuf, Vec<u8>>,
) -> usize {
    let d = tempfile::tempdir().unwrap();
    let mut sets = vec![];
    let mut millis = 0u64;
    for k in 0..2 {
        let out = d.path().join(format!("ref{k}"));
        let args = args_of(k, &out);
        let start = std::time::Instant::now();
        ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
        millis = millis.max(start.elapsed().as_millis() as u64);
        sets.push(tree(&out));
    }
    assert_ne!(sets[0], sets[1]);
    let out = d.path().join("out");
    ok(&args_of(0, &out).iter().map(String::as_str).collect::<Vec<_>>());
    let (mut current, mut killed) = (0, 0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
    for i in 0..kills {
        let next = 1 - current;
        let args = args_of(next, &out);
        let slice = (millis * i as u64 / kills as u64)..=(millis * (i as u64 + 1) / kills as u64);
        let finished = kill_after(&args.iter().map(String::as_str).collect::<Vec<_>>(), rng.random_range(slice));
        let now = seen(&out);
        // Temporaries of the killed run may remain beside `out` (or, for file sets, as
        // hidden entries beside each file); never as a visible file inside it.
        let whole = sets.iter().position(|s| *s == now);
        assert!(whole.is_some(), "{name}: kill {i} left a mixed set: {:?}", now.keys().collect::<Vec<_>>());
        killed += usize::from(!finished && whole == Some(current));
        current = whole.unwrap();
    }
    // The next run writing there removes the killed runs' temporaries.
    ok(&args_of(0, &out).iter().map(String::as_str).collect::<Vec<_>>());
    let left: Vec<_> = std::fs::read_dir(d.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 3, "{name}: temporaries left: {left:?}");
    // (A set directory's list of its entries, `.etlcal-set`, is part of the set.)
    let inside: Vec<_> =
        tree(&out).into_keys().filter(|p| hidden(p) && p.file_name() != Some(".etlcal-set".as_ref())).collect();
    assert!(inside.is_empty(), "{name}: temporaries left in the output: {inside:?}");
    killed
}

#[test]
fn killed_study_and_undistort_leave_one_whole_set() {
    let study = |k: usize, out: &Path| -> Vec<String> {
        let seed = (k + 1).to_string();
        ["study", "fig6", "--trials", "1", "--seed", &seed, "--out", s(out)].map(String::from).to_vec()
    };
    let killed = kill_test_seen("study", 40, study, tree_as_read);
    assert!(killed > 0, "no study run was killed before finishing");
    // Three distinct images of the calibration's size (no two rows alike).
    let d = tempfile::tempdir().unwrap();
    let [w, h] = etl_core::model::CameraModel::PAPER_IMAGE_SIZE;
    let images: Vec<String> = (0..3u32)
        .map(|i| {
            let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([((x * 7 + y * 3 + i * 50) % 251) as u8]));
            let p = d.path().join(format!("view{i}.png"));
            img.save(&p).unwrap();
            p.to_str().unwrap().to_owned()
        })
        .collect();
    let undistort = |k: usize, out: &Path| -> Vec<String> {
        let e_com = if k == 0 { "150" } else { "170" };
        let mut a: Vec<String> = ["undistort", "--calibration", "fixtures/service/calibration.json", "--e-com", e_com]
            .map(String::from)
            .to_vec();
        a.extend(images.iter().cloned());
        a.extend(["--out".to_owned(), s(out).to_owned()]);
        a
    };
    let killed = kill_test_seen("undistort", 40, undistort, tree_as_read);
    assert!(killed > 0, "no undistort run was killed before finishing");
}

#[test]
fn killed_simulate_and_report_leave_one_whole_set() {
    let simulate = |k: usize, out: &Path| -> Vec<String> {
        let seed = (k + 1).to_string();
        ["simulate", "--out", s(out), "--seed", &seed].map(String::from).to_vec()
    };
    let killed = kill_test("simulate", 8, simulate);
    assert!(killed > 0, "no simulate run was killed before finishing");
    let report = |k: usize, out: &Path| -> Vec<String> {
        let mut a = ["report", "--calibration", "fixtures/service/calibration.json", "--out", s(out)]
            .map(String::from)
            .to_vec();
        if k == 1 {
            a.extend(["--observations".into(), "fixtures/golden/observations.json".into()]);
        }
        a
    };
    let killed = kill_test("report", 8, report);
    assert!(killed > 0, "no report run was killed before finishing");
}

/// An edit of an observations file's JSON.
type Change = fn(&mut serde_json::Value);

/// The golden observations with `change` applied, written to `dir/name`.
fn observations_with(dir: &Path, name: &str, change: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let text = std::fs::read_to_string(format!("{ROOT}/fixtures/golden/observations.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    change(&mut v);
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string(&v).unwrap()).unwrap();
    p
}

/// A simulation within the caps (1000 currents x 1000 views) would need about 49 GB: it is
/// costed before anything is allocated, against the memory budget (half of physical memory,
/// or `ETLCAL_MEMORY_BUDGET`), and refused naming the option and the estimate; a budget
/// that does not parse is refused too, never ignored. Nothing is written either way.
#[test]
fn a_simulation_beyond_the_memory_budget_is_refused_before_it_allocates() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let config = d.path().join("sim.json");
    let currents: Vec<String> = (0..1000).map(|i| format!("{}", 80.0 + 0.1 * f64::from(i))).collect();
    std::fs::write(
        &config,
        format!(
            r#"{{"format": "etlcal.simconfig/1", "setting_rig": {{"e_com_ma": [{}], "views_per_setting": 1000,
                "blur_px": 2.0, "aperture_mm": 2.5, "max_tilt_deg": 25.0}}}}"#,
            currents.join(",")
        ),
    )
    .unwrap();
    let run = |budget: Option<&str>, views: &str| {
        let text = std::fs::read_to_string(&config).unwrap().replace("\"views_per_setting\": 1000,", views);
        std::fs::write(&config, text).unwrap();
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_etlcal"));
        c.args(["simulate", "--observations-only", "--quiet", "--config", s(&config), "--out", s(&out)]);
        match budget {
            Some(b) => c.env("ETLCAL_MEMORY_BUDGET", b),
            None => c.env_remove("ETLCAL_MEMORY_BUDGET"),
        };
        let o = c.output().unwrap();
        (o.status.code(), String::from_utf8(o.stderr).unwrap())
    };
    let (code, err) = run(Some("24G"), "\"views_per_setting\": 1000,");
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(
            "setting_rig.views_per_setting needs about 49 GB, above the memory budget of 26 GB \
                      (ETLCAL_MEMORY_BUDGET): refused before allocating"
        ),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    let (code, err) = run(None, "\"views_per_setting\": 1000,");
    assert!(code == Some(1) && err.contains("(half of physical memory; ETLCAL_MEMORY_BUDGET sets it)"), "{err}");
    let (code, err) = run(Some("lots"), "\"views_per_setting\": 1000,");
    assert!(code == Some(1) && err.contains("ETLCAL_MEMORY_BUDGET=\"lots\" is not a number of bytes"), "{err}");
    assert!(!out.exists(), "nothing written");
    // One view per current is within a 1 GB budget: written.
    let (code, err) = run(Some("1G"), "\"views_per_setting\": 1,");
    assert_eq!(code, Some(0), "{err}");
    assert!(out.join("observations.json").is_file());
}

#[test]
fn numbers_out_of_their_documented_ranges_are_refused_naming_the_quantity() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let sim = |extra: &[&str]| {
        let mut a = vec!["simulate", "--observations-only", "--out", s(&out)];
        a.extend_from_slice(extra);
        refused(&a)
    };
    let err = sim(&["--pixel-noise-px", "1e308"]);
    assert!(err.contains("--pixel-noise-px 1e308 px is outside [0, 100] px") && err.len() < 200, "{err}");
    std::fs::write(
        d.path().join("sim.json"),
        r#"{"format": "etlcal.simconfig/1", "setting_rig": {"e_com_ma": [80, 150], "views_per_setting": 1000000000000,
            "blur_px": 2.0, "aperture_mm": 2.5, "max_tilt_deg": 25.0}}"#,
    )
    .unwrap();
    let err = sim(&["--setting-views", "--config", s(&d.path().join("sim.json"))]);
    assert!(err.contains("views_per_setting") && err.contains("at most 1000"), "{err}");
    let err = sim(&["--stage-noise-um", "-1"]);
    assert!(err.contains("--stage-noise-um -1 um is outside"), "{err}");
    assert!(!out.exists(), "nothing written");
    // Observations: each bad number named with its view and point.
    let cases: [(&str, Change, &str); 4] = [
        (
            "e_com.json",
            |v| v["views"][2]["e_com_ma"] = (-1e6).into(),
            "view 2: e_com_ma -1e6 mA is outside the lens driver's",
        ),
        (
            "size.json",
            |v| v["image_size"] = serde_json::json!([0, 0]),
            "image_size [0, 0] px: each side must be in [1, 65536]",
        ),
        (
            "z.json",
            |v| v["offstate_views"][1]["points"][3]["world_mm"][2] = 2.0.into(),
            "lens-off view 1 point 3: world_mm Z = 2 mm",
        ),
        (
            "px.json",
            |v| v["views"][0]["points"][5]["pixel"][0] = 1e300.into(),
            "view 0 point 5: pixel coordinate 1e300 px",
        ),
    ];
    for (name, change, needle) in cases {
        let obs = observations_with(d.path(), name, change);
        let err = refused(&["calibrate", "--observations", s(&obs), "--out", s(&d.path().join("c.json"))]);
        assert!(err.contains(needle), "{name}: {err}");
    }
    assert!(!d.path().join("c.json").exists());
    // Negative numbers are values (not flags) for every verb; NaN is in no range.
    let img = d.path().join("r.png");
    let err = refused(&["render", "--e-com", "-292", "--aperture-mm", "NaN", "--out", s(&img)]);
    assert!(err.contains("--aperture-mm NaN mm is outside [0, 50] mm"), "{err}");
    let err = refused(&["render", "--e-com", "-1e6", "--out", s(&img)]);
    assert!(err.contains("--e-com -1e6 mA is outside [-292.84, 292.84] mA"), "{err}");
    assert!(!img.exists());
}

/// A dataset's image that is not a regular file (a FIFO: opening it would block forever) is
/// refused by the detection of `calibrate --dataset`, as every other input is.
#[test]
fn a_fifo_as_a_dataset_image_is_refused_not_opened() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n);
    assert!(Command::new("mkfifo").arg(p("view.png")).status().unwrap().success());
    let views: Vec<String> = [(80.0, 75.0), (150.0, 22.0), (225.0, 2.0)]
        .iter()
        .map(|(e, z)| format!(r#"{{"image": "view.png", "e_in_ma": {e}, "temperature_c": 30.0, "z_w_mm": {z}}}"#))
        .collect();
    let dataset = format!(
        r#"{{"format": "etlcal.dataset/1", "image_size": [1936, 1458], "board": {{"inner_corners": [14, 12], "square_mm": 1.5}}, "views": [{}]}}"#,
        views.join(", ")
    );
    std::fs::write(p("dataset.json"), dataset).unwrap();
    let err =
        refused(&["calibrate", "--dataset", s(&p("dataset.json")), "--thermal", "paper", "--out", s(&p("c.json"))]);
    assert!(err.contains("not a regular file"), "{err}");
    assert!(!p("c.json").exists());
}

/// A read-only output is refused, not replaced (as root, too: a rename would replace it),
/// and stays as it was.
#[test]
fn a_read_only_output_is_refused_and_kept() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n);
    thermal_table(&p("t.csv"));
    std::fs::write(p("ro.json"), "the user's, read-only").unwrap();
    std::fs::set_permissions(p("ro.json"), std::fs::Permissions::from_mode(0o444)).unwrap();
    let before = tree(d.path());
    let err = refused(&["thermal", "fit", s(&p("t.csv")), "--out", s(&p("ro.json"))]);
    assert!(err.contains("is read-only: refused as an output"), "{err}");
    assert_eq!(tree(d.path()), before);
}

/// `render` writes its image and the image's corners as one set: when the corners cannot
/// be written (a directory stands where the file goes), the earlier image is kept whole.
#[test]
fn render_keeps_the_earlier_image_when_its_corners_cannot_be_written() {
    let d = tempfile::tempdir().unwrap();
    let img = d.path().join("view.png");
    std::fs::write(&img, "the earlier image").unwrap();
    std::fs::create_dir(d.path().join("view.png.corners.json")).unwrap();
    let before = tree(d.path());
    let err = refused(&["render", "--out", s(&img)]);
    assert!(err.contains("view.png.corners.json") && err.contains("not a regular file"), "{err}");
    assert_eq!(tree(d.path()), before, "the image was replaced");
}

/// `thermal calibrate` writes its surface and its table as one set: an output that cannot
/// be written (its directory is a file) leaves the earlier table whole.
#[test]
fn thermal_calibrate_writes_its_surface_and_table_both_or_neither() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n);
    std::fs::create_dir(p("tables")).unwrap();
    thermal_table(&p("tables/t.csv"));
    std::fs::write(p("blocked"), "a file where a directory is expected").unwrap();
    let before = tree(d.path());
    let out = etlcal(&[
        "thermal",
        "calibrate",
        "--virtual",
        "--quick",
        "--table",
        s(&p("tables/t.csv")),
        "--out",
        s(&p("blocked/t.json")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("blocked/t.json"), "{err}");
    assert_eq!(tree(d.path()), before, "the table was replaced alone");
}

/// Runs `args`, killing it after `limit_s` seconds: `None` if it had to be killed (a hang).
fn within(args: &[&str], limit_s: u64) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(args)
        .current_dir(ROOT)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed().as_secs() >= limit_s {
            child.kill().unwrap();
            child.wait().unwrap();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    Some(child.wait_with_output().unwrap())
}

/// `report` spun forever inside the plotting library on a range of 1e308 (a calibration's
/// E_com range, an observation's pixel): both are refused by the readers, in one line,
/// before a plot is drawn or the output directory made.
#[test]
fn report_refuses_ranges_of_1e308_instead_of_hanging() {
    let d = tempfile::tempdir().unwrap();
    let fixture = format!("{ROOT}/fixtures/service/calibration.json");
    let mut cal: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&fixture).unwrap()).unwrap();
    cal["e_com_range_ma"] = serde_json::json!([80.0, 1e308]);
    let wide = d.path().join("wide.json");
    std::fs::write(&wide, serde_json::to_string(&cal).unwrap()).unwrap();
    let obs = observations_with(d.path(), "far.json", |v| v["views"][3]["points"][7]["pixel"][1] = 1e308.into());
    let out = d.path().join("report");
    let cases = [
        (vec!["report", "--calibration", s(&wide), "--out", s(&out)], "e_com_range_ma [80, 1e308] must be"),
        (
            vec!["report", "--calibration", &fixture, "--observations", s(&obs), "--out", s(&out)],
            "view 3 point 7: pixel coordinate 1e308 px",
        ),
    ];
    for (args, needle) in cases {
        let run = within(&args, 120).unwrap_or_else(|| panic!("{args:?} hung (killed after 120 s)"));
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}: wrote {}", out.display());
    }
}
