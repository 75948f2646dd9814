//! `etlcal capture`, `camera` and `stage` on the simulated rig: the acceptance run
//! (capture the fixture plan, calibrate, compare with the truth), a capture killed with
//! SIGKILL at random moments and resumed, a camera that runs out of frames, bad plans.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use rand::{Rng, SeedableRng};

use crate::common::{etlcal_run, tree};
use etl_core::model::CameraModel;
use etl_formats::dataset::Dataset;

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures").join(name).to_string_lossy().into_owned()
}

fn capture_args<'a>(plan: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "capture", "views", "--camera", "sim", "--lens", "virtual", "--stage", "sim", "--plan", plan, "--out", out,
        "--quiet",
    ]
}

/// Every file of `dir` that is a temporary (`.NAME.tmpPID`).
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    tree(dir).into_keys().filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'))).collect()
}

#[test]
fn the_fixture_plan_captured_on_the_sim_rig_calibrates_to_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("D");
    let (plan, out_s) = (fixture("plan.json"), out.to_string_lossy().into_owned());
    let (code, stdout, stderr) = etlcal_run(&[&capture_args(&plan, &out_s)[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["offstate_taken"].as_u64(), report["views_taken"].as_u64()), (Some(10), Some(15)), "{report}");
    let dataset = out.join("dataset.json");
    let cal = out.join("calibration.json");
    // The virtual lens's true thermal surface is the paper's: the user of this rig knows it.
    let (code, _, stderr) = etlcal_run(&[
        "calibrate",
        "--dataset",
        &dataset.to_string_lossy(),
        "--thermal",
        "paper",
        "--out",
        &cal.to_string_lossy(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let c = etl_formats::Calibration::load(&cal).unwrap();
    let m = c.model().unwrap();
    let truth = CameraModel::paper_rig();
    let (ex, ey) = etl_studies::common::curve_errors(&m, &truth, c.e_com_range_ma);
    let pp = (m.principal_point[0] - truth.principal_point[0]).hypot(m.principal_point[1] - truth.principal_point[1]);
    eprintln!(
        "captured dataset: max rel. error fx(E) {:.4} %, fy(E) {:.4} %, principal point {pp:.3} px, RMS {:.4} px, range {:?}",
        100.0 * ex,
        100.0 * ey,
        c.rms_reprojection_px,
        c.e_com_range_ma
    );
    // `etlcal demo` (seed 1, errors-in-variables): 0.06 % and 0.4 px, with the paper's
    // stage and current noise this rig does not have.
    assert!(ex < 0.0015 && ey < 0.0015, "fx {ex}, fy {ey}");
    assert!(pp < 1.5, "principal point off by {pp} px");
    assert!(c.e_com_range_ma[0] < 81.0 && c.e_com_range_ma[1] > 224.0, "{:?}", c.e_com_range_ma);
}

/// A small plan of the paper rig: `n` stage positions with the currents in focus there,
/// 2 lens-off views, 1 frame per view.
fn small_plan(dir: &Path, n: usize) -> String {
    let z = &etl_sim::rig::PAPER_Z_W_MM[..n];
    let e: Vec<f64> = etl_sim::rig::PAPER_E_COM_MA[..n].iter().map(|e| e - 0.3).collect();
    let plan = serde_json::json!({
        "format": "etlcal.plan/1",
        "board": {"type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"},
        "stage_mm": z, "frames": 1, "focus": "current", "currents_ma": e, "offstate_views": 2,
        "offstate_board": {"type": "charuco", "squares": [12, 9], "square_mm": 4.0, "marker_mm": 3.0, "dictionary": "DICT_5X5_100"},
    });
    let path = dir.join("plan.json");
    std::fs::write(&path, plan.to_string()).unwrap();
    path.to_string_lossy().into_owned()
}

fn spawn_capture(plan: &str, out: &str) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(capture_args(plan, out))
        .arg("--json")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// The views of a dataset as a comparable list: (image, z, current) and the lens-off images.
fn views_of(d: &Dataset) -> (Vec<(PathBuf, f64, f64)>, Vec<PathBuf>) {
    (
        d.views.iter().map(|v| (v.image.clone(), v.z_w_mm, v.e_in_ma)).collect(),
        d.offstate_views.iter().map(|v| v.image.clone()).collect(),
    )
}

#[test]
fn a_capture_killed_at_random_moments_resumes_to_the_uninterrupted_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let plan = small_plan(dir.path(), 14);
    let reference = dir.path().join("R");
    let started = std::time::Instant::now();
    let (code, _, stderr) = etlcal_run(&capture_args(&plan, &reference.to_string_lossy()));
    assert_eq!(code, 0, "{stderr}");
    // Kill moments spread over 0..1.1 views' time after a margin for the start (which grows
    // with the images a resume verifies): most runs die within a view, at any step
    // (settling, grabbing, writing the image or the dataset), some finish one first. A run
    // that took no view widens the margin by a quarter view; one that took some halves it.
    let mut view_s = started.elapsed().as_secs_f64() / 16.0;
    let want = Dataset::load(&reference.join("dataset.json")).unwrap();
    let out = dir.path().join("K");
    let out_s = out.to_string_lossy().into_owned();
    let done = || {
        etl_formats::read_json::<Dataset>(&out.join("dataset.json"), etl_formats::dataset::FORMAT)
            .map_or(0, |d| d.views.len() + d.offstate_views.len())
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(28);
    let (mut kills, mut runs, mut margin_s) = (0, 0, 0.0);
    loop {
        runs += 1;
        assert!(runs < 400, "no end after {runs} runs");
        let before = done();
        let mut child = spawn_capture(&plan, &out_s);
        std::thread::sleep(Duration::from_secs_f64(margin_s + rng.random_range(0.02..1.1) * view_s));
        if let Some(status) = child.try_wait().unwrap() {
            let output = child.wait_with_output().unwrap();
            assert!(status.success(), "{}", String::from_utf8_lossy(&output.stderr));
            break;
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        kills += 1;
        // A run that took several views: the reference run was slower than these (a
        // loaded machine); shorten the view's time so that the kills stay within views.
        let taken = done().saturating_sub(before);
        if taken > 1 {
            view_s *= 0.6;
        }
        margin_s = if taken > 0 { 0.5 * margin_s } else { margin_s + 0.25 * view_s };
    }
    assert!(kills >= 20, "only {kills} kills before the capture ended");
    let (code, _, stderr) = etlcal_run(&capture_args(&plan, &out_s));
    assert_eq!(code, 0, "{stderr}");
    let got = Dataset::load(&out.join("dataset.json")).unwrap();
    eprintln!(
        "killed {kills} times in {runs} runs; {} views and {} lens-off views at the end",
        got.views.len(),
        got.offstate_views.len()
    );
    assert_eq!(views_of(&got), views_of(&want));
    assert_eq!((got.board, got.offstate_board, got.image_size), (want.board, want.offstate_board, want.image_size));
    // The temperatures are the lens's, measured: each restart starts a new virtual lens at
    // its 27 degC ambient, which then warms under its current as the uninterrupted one did.
    for v in got.views.iter().chain(&want.views) {
        assert!((26.9..29.0).contains(&v.temperature_c), "{v:?}");
    }
    for image in got.views.iter().map(|v| &v.image).chain(got.offstate_views.iter().map(|v| &v.image)) {
        let img = etl_image::read_image(&out.join(image)).unwrap();
        assert_eq!([img.width(), img.height()], got.image_size);
    }
    assert_eq!(temporaries(&out), Vec::<PathBuf>::new());
}

#[test]
fn ctrl_c_ends_the_capture_after_the_current_view() {
    let dir = tempfile::tempdir().unwrap();
    let plan = small_plan(dir.path(), 6);
    let out = dir.path().join("D");
    let child = spawn_capture(&plan, &out.to_string_lossy());
    std::thread::sleep(Duration::from_millis(2500));
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).unwrap();
    let output = child.wait_with_output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["stopped"], true, "{report}");
    let taken = report["offstate_taken"].as_u64().unwrap() + report["views_taken"].as_u64().unwrap();
    assert!(taken < 8, "{report}");
    let d: Dataset = etl_formats::read_json(&out.join("dataset.json"), etl_formats::dataset::FORMAT).unwrap();
    assert_eq!(d.offstate_views.len() + d.views.len(), taken as usize);
    assert_eq!(temporaries(&out), Vec::<PathBuf>::new());
}

#[test]
fn bad_plans_and_specs_fail_in_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("D");
    let out_s = out.to_string_lossy().into_owned();
    let good = std::fs::read_to_string(fixture("plan.json")).unwrap();
    let cases: [(&str, String, &str); 5] = [
        ("no positions", good.replacen("\"stage_mm\": [75.0", "\"stage_mm\": [], \"x_\": [75.0", 1), "x_"),
        ("0 frames", good.replace("\"frames\": 2", "\"frames\": 0"), "frames: 0 frames"),
        ("unknown key", good.replace("\"frames\": 2", "\"frames\": 2, \"speed_mm_s\": 3"), "speed_mm_s"),
        (
            "beyond the stage",
            good.replace("\"stage_mm\": [75.0", "\"stage_mm\": [175.0"),
            "stage_mm[0] 175 mm is outside the travel of stage sim",
        ),
        (
            "empty positions",
            serde_json::to_string(&{
                let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
                v["stage_mm"] = serde_json::json!([]);
                v["currents_ma"] = serde_json::json!([]);
                v
            })
            .unwrap(),
            "stage_mm: the plan has no stage positions",
        ),
    ];
    for (what, text, expected) in cases {
        let plan = dir.path().join("plan.json");
        std::fs::write(&plan, text).unwrap();
        let (code, _, stderr) = etlcal_run(&capture_args(&plan.to_string_lossy(), &out_s));
        assert_eq!(code, 1, "{what}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{what}: {stderr}");
        assert!(stderr.contains(expected), "{what}: {stderr}");
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
    let plan = fixture("plan.json");
    let mut args = capture_args(&plan, &out_s);
    args[3] = "webcam:0";
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("camera webcam:0: unknown camera spec"), "{stderr}");
    assert!(!out.exists());
    // A shaper from dynamics whose membrane does not ring: refused, nothing written.
    let published = fixture("lens-dynamics/el-10-30-published.json");
    let over = dir.path().join("over.json");
    std::fs::write(&over, std::fs::read_to_string(published).unwrap().replace("\"damping\": 0.28", "\"damping\": 1.5"))
        .unwrap();
    let over_s = over.to_string_lossy().into_owned();
    let mut args = capture_args(&plan, &out_s);
    args.extend_from_slice(&["--shaped", &over_s]);
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("--shaped") && stderr.contains("no shaper"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn a_files_camera_that_runs_out_ends_the_capture_and_the_capture_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let plan = small_plan(dir.path(), 2);
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("offstate_views");
    std::fs::write(&plan, v.to_string()).unwrap();
    // The frames a files camera replays: the sim rig's two views, copied so that each view
    // settles (2 frames alike) and keeps a third; the folder runs out in view 1.
    let sim = dir.path().join("S");
    let (code, _, stderr) = etlcal_run(&capture_args(&plan, &sim.to_string_lossy()));
    assert_eq!(code, 0, "{stderr}");
    let folder = |name: &str, images: &[&str]| {
        let d = dir.path().join(name);
        std::fs::create_dir(&d).unwrap();
        for (k, image) in images.iter().enumerate() {
            std::fs::copy(sim.join("views").join(image), d.join(format!("f{k:02}.png"))).unwrap();
        }
        format!("files:{}", d.display())
    };
    let first = folder("first", &["view00.png", "view00.png", "view00.png", "view01.png"]);
    let out = dir.path().join("D");
    let out_s = out.to_string_lossy().into_owned();
    let mut args = capture_args(&plan, &out_s);
    args[3] = &first;
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains(&format!("camera {first}: no more images")), "{stderr}");
    let d = Dataset::load(&out.join("dataset.json")).unwrap();
    assert_eq!(d.views.len(), 1);
    assert_eq!(temporaries(&out), Vec::<PathBuf>::new());
    // The same command with the camera back (here: a folder holding view 1) resumes.
    let second = folder("second", &["view01.png", "view01.png", "view01.png"]);
    args[3] = &second;
    let (code, stdout, stderr) = etlcal_run(&[&args[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["views_kept"].as_u64(), report["views_taken"].as_u64()), (Some(1), Some(1)), "{report}");
    let d = Dataset::load(&out.join("dataset.json")).unwrap();
    assert_eq!(d.views.iter().map(|v| v.z_w_mm).collect::<Vec<_>>(), vec![75.0, 60.0]);
}

#[test]
fn camera_list_grab_and_stage_move_work_on_the_sim_rig() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = etlcal_run(&["camera", "list", "--json"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("\"sim\""), "{stdout}");
    let out = dir.path().join("g.png");
    let (code, stdout, stderr) =
        etlcal_run(&["camera", "grab", "--camera", "sim", "--out", &out.to_string_lossy(), "--frames", "2", "--json"]);
    assert_eq!(code, 0, "{stderr}");
    let g: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(g["image_size"], serde_json::json!([1936, 1458]));
    assert_eq!(g["timestamps_ns"].as_array().unwrap().len(), 2);
    let img = etl_image::read_image(&out).unwrap();
    assert_eq!((img.width(), img.height()), (1936, 1458));
    let (code, stdout, stderr) = etlcal_run(&["stage", "--stage", "sim", "move", "22.5", "--json"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(serde_json::from_str::<serde_json::Value>(&stdout).unwrap()["position_mm"], 22.5);
    let (code, _, stderr) = etlcal_run(&["stage", "--stage", "sim", "move", "500"]);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("stage sim: position 500 mm is outside the travel"), "{stderr}");
}

#[test]
fn stage_verbs_drive_a_zaber_stage_over_its_serial_port() {
    use etl_rig::stage::zaber_standin::{StandInConfig, ZaberStandIn};
    let standin = ZaberStandIn::spawn(StandInConfig::default()).unwrap();
    let spec = format!("zaber:{},microstep_um=0.1", standin.path().display());
    let (code, stdout, stderr) = etlcal_run(&["stage", "--stage", &spec, "move", "12.5", "--json"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(serde_json::from_str::<serde_json::Value>(&stdout).unwrap()["position_mm"], 12.5);
    let (code, stdout, _) = etlcal_run(&["stage", "--stage", &spec, "limits", "--json"]);
    assert_eq!(
        (code, serde_json::from_str::<serde_json::Value>(&stdout).unwrap()["limits_mm"].clone()),
        (0, serde_json::json!([0.0, 100.0]))
    );
    let (code, _, stderr) = etlcal_run(&["stage", "--stage", &spec, "move", "150"]);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(
        stderr.contains(&format!("stage zaber:{}: refused 'move abs 1500000': BADDATA", standin.path().display())),
        "{stderr}"
    );
    assert!(standin.transcript().contains(&"> /1 1 move abs 125000".to_owned()));
}

#[test]
fn capture_offstate_takes_the_lens_off_views_alone_and_capture_views_goes_on_from_them() {
    let dir = tempfile::tempdir().unwrap();
    let plan = small_plan(dir.path(), 1);
    let out = dir.path().join("D");
    let out_s = out.to_string_lossy().into_owned();
    let mut args = capture_args(&plan, &out_s);
    args[1] = "offstate";
    let (code, stdout, stderr) = etlcal_run(&[&args[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["offstate_taken"].as_u64(), report["views_taken"].as_u64()), (Some(2), Some(0)), "{report}");
    let d: Dataset = etl_formats::read_json(&out.join("dataset.json"), etl_formats::dataset::FORMAT).unwrap();
    assert_eq!((d.offstate_views.len(), d.views.len()), (2, 0));
    // `capture views` of the same plan keeps them and takes the ETL view.
    let (code, stdout, stderr) = etlcal_run(&[&capture_args(&plan, &out_s)[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["offstate_kept"].as_u64(), report["views_taken"].as_u64()), (Some(2), Some(1)), "{report}");
    // A plan without lens-off views has nothing for `capture offstate`.
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("offstate_views");
    std::fs::write(&plan, v.to_string()).unwrap();
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("offstate_views: the plan asks for no lens-off views"), "{stderr}");
}
