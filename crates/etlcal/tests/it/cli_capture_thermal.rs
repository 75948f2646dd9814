//! `etlcal capture thermal` on the simulated rig (the sim camera on a 240 x 180 window of
//! its sensor): the fixture plan's grid captured and fitted, compared with the virtual
//! lens's true surface; a capture killed with SIGKILL and resumed; bad plans refused in one
//! line with nothing written.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use rand::{Rng, SeedableRng};

use crate::common::{etlcal_run, tree};
use etl_calib::thermal_calibration::ProcedureResult;
use etl_formats::thermal::{read_thermal_table, ThermalFile};

/// A window of the sim sensor that shows the board at every stage position of the plan.
const ROI: [&str; 4] = ["1018", "449", "240", "180"];

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures").join(name).to_string_lossy().into_owned()
}

fn thermal_args<'a>(plan: &'a str, out: &'a str) -> Vec<&'a str> {
    let mut args = vec![
        "capture",
        "thermal",
        "--camera",
        "sim",
        "--lens",
        "virtual",
        "--stage",
        "sim",
        "--plan",
        plan,
        "--out",
        out,
        "--quiet",
        "--sim-roi",
    ];
    args.extend_from_slice(&ROI);
    args
}

/// The fitted surface's RMS distance from the virtual lens's true one over the grid's
/// ranges, referenced to the first temperature as the procedure is, mA.
fn surface_error_ma(dir: &Path) -> f64 {
    let file = ThermalFile::load(&dir.join("thermal.json")).unwrap();
    let samples = read_thermal_table(&dir.join("thermal.csv")).unwrap();
    let calibration = file.calibration();
    let result = ProcedureResult { samples, calibration, rms_ma: file.rms_ma, frames: 0 };
    let truth = etl_rig::rig::paper_virtual_lens().surface;
    let c = &result.calibration;
    etl_sim::virtual_rig::surface_error_ma(&result, &truth, c.e_in_range_ma, c.t_range_c, 27.0).unwrap().0
}

#[test]
fn the_thermal_plan_on_the_sim_rig_fits_the_virtual_lenss_surface() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T");
    let (plan, out_s) = (fixture("plan-thermal.json"), out.to_string_lossy().into_owned());
    let (code, stdout, stderr) = etlcal_run(&[&thermal_args(&plan, &out_s)[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["samples_taken"].as_u64(), report["stopped"].as_bool()), (Some(16), Some(false)), "{report}");
    let samples = read_thermal_table(&out.join("thermal.csv")).unwrap();
    // Series by series (4 currents x 4 temperatures): the lens at each step's temperature,
    // E_T = 0 at the first, rising with the temperature as the paper's surface does.
    for (n, s) in samples.iter().enumerate() {
        assert!((s.temperature_c - [27.0, 30.0, 33.0, 36.0][n % 4]).abs() <= 0.25, "{n}: {s:?}");
        if n % 4 == 0 {
            assert_eq!(s.e_t_ma, 0.0);
        }
    }
    let error_ma = surface_error_ma(&out);
    eprintln!("thermal capture: fit RMS {} mA; {error_ma:.3} mA RMS from the true surface", report["rms_ma"]);
    // Measured 0.11 mA (the refocus of a 2.5 mm aperture's sharpness peak, up to 22 frames).
    assert!(error_ma < 0.5, "{error_ma} mA");
    // `etlcal thermal fit` reads the table and fits the same surface.
    let refit = dir.path().join("refit.json");
    let table = out.join("thermal.csv");
    let (code, _, stderr) =
        etlcal_run(&["thermal", "fit", &table.to_string_lossy(), "--out", &refit.to_string_lossy(), "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    let (a, b) = (ThermalFile::load(&refit).unwrap(), ThermalFile::load(&out.join("thermal.json")).unwrap());
    assert_eq!(a.coefficients, b.coefficients);
}

fn spawn_thermal(plan: &str, out: &str) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(thermal_args(plan, out))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

#[test]
fn a_thermal_capture_killed_at_random_moments_resumes_and_fits() {
    let dir = tempfile::tempdir().unwrap();
    let plan = fixture("plan-thermal.json");
    let out = dir.path().join("K");
    let out_s = out.to_string_lossy().into_owned();
    let rows = || read_thermal_table(&out.join("thermal.csv")).map_or(0, |r| r.len());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut kills, mut runs) = (0, 0);
    // Kill moments over 0.3..1.5 s: the start, a refocus, the table's writing.
    while kills < 5 {
        runs += 1;
        assert!(runs < 40, "no end after {runs} runs");
        let before = rows();
        let mut child = spawn_thermal(&plan, &out_s);
        std::thread::sleep(Duration::from_secs_f64(rng.random_range(0.3..1.5)));
        if let Some(status) = child.try_wait().unwrap() {
            let output = child.wait_with_output().unwrap();
            assert!(status.success(), "{}", String::from_utf8_lossy(&output.stderr));
            break;
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        kills += 1;
        assert!(rows() >= before, "a kill lost rows");
    }
    let (code, stdout, stderr) = etlcal_run(&[&thermal_args(&plan, &out_s)[..], &["--json"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let kept = report["samples_kept"].as_u64().unwrap();
    eprintln!("killed {kills} times in {runs} runs; {kept} samples kept by the last run");
    assert!(kills >= 3 && kept > 0, "{kills} kills, {report}");
    assert_eq!(kept + report["samples_taken"].as_u64().unwrap(), 16, "{report}");
    let samples = read_thermal_table(&out.join("thermal.csv")).unwrap();
    for (n, s) in samples.iter().enumerate() {
        assert!((s.temperature_c - [27.0, 30.0, 33.0, 36.0][n % 4]).abs() <= 0.25, "{n}: {s:?}");
    }
    let error_ma = surface_error_ma(&out);
    assert!(error_ma < 0.5, "{error_ma} mA");
    let temporaries: Vec<PathBuf> = tree(&out)
        .into_keys()
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')))
        .collect();
    assert_eq!(temporaries, Vec::<PathBuf>::new());
}

#[test]
fn bad_thermal_plans_fail_in_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T");
    let out_s = out.to_string_lossy().into_owned();
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("plan-thermal.json")).unwrap()).unwrap();
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        v.to_string()
    };
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "no thermal keys",
            edit(&|v| drop(v.as_object_mut().unwrap().remove("thermal"))),
            "the plan has no \"thermal\" keys",
        ),
        (
            "three temperatures",
            edit(&|v| v["thermal"]["temperatures_c"] = serde_json::json!([27, 30, 33])),
            "thermal.temperatures_c: 3 distinct temperatures",
        ),
        (
            "no tolerance",
            edit(&|v| v["thermal"]["temperature_tolerance_c"] = serde_json::json!(0)),
            "thermal.temperature_tolerance_c 0 must lie in (0, 10] degC",
        ),
        ("unknown key", edit(&|v| v["thermal"]["heater_w"] = serde_json::json!(3)), "heater_w"),
        (
            "too few refocus frames",
            edit(&|v| v["thermal"]["refocus_frames"] = serde_json::json!(5)),
            "thermal.refocus_frames: 5 frames",
        ),
        (
            "autofocus",
            edit(&|v| {
                v["focus"] = serde_json::json!("autofocus");
                v.as_object_mut().unwrap().remove("currents_ma");
            }),
            "focus: the temperature procedure starts each series at one of the plan's currents",
        ),
        (
            "three currents",
            edit(&|v| {
                v["currents_ma"] = serde_json::json!([89.7, 129.7, 129.7, 209.7]);
            }),
            "currents_ma: 3 distinct currents",
        ),
        (
            "beyond the stage",
            edit(&|v| v["stage_mm"][3] = serde_json::json!(-4.0)),
            "stage_mm[3] -4 mm is outside the travel of stage sim",
        ),
    ];
    for (what, text, expected) in cases {
        let plan = dir.path().join("plan.json");
        std::fs::write(&plan, text).unwrap();
        let (code, _, stderr) = etlcal_run(&thermal_args(&plan.to_string_lossy(), &out_s));
        assert_eq!((code, stderr.lines().count()), (1, 1), "{what}: {stderr}");
        assert!(stderr.contains(expected), "{what}: {stderr}");
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
    let plan = fixture("plan-thermal.json");
    let mut args = thermal_args(&plan, &out_s);
    let n = args.len();
    args[n - 4] = "1900";
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("camera sim: region of interest x 1900"), "{stderr}");
    assert!(!out.exists());
    // A flag of the views' capture that this one has no use for is refused, not ignored.
    let mut args = thermal_args(&plan, &out_s);
    args.extend_from_slice(&["--settle-tolerance-px", "0.2"]);
    let (code, _, stderr) = etlcal_run(&args);
    assert_eq!((code, stderr.lines().count()), (1, 1), "{stderr}");
    assert!(stderr.contains("--settle-tolerance-px: capture thermal settles each frame on its sharpness"), "{stderr}");
    assert!(!out.exists());
}
