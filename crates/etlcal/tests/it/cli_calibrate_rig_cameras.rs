//! `etlcal calibrate-rig` with per-camera requests: each lens its own temperature surface
//! (`--thermal CAM=FILE|paper`) and its own model flags (`--camera-flags CAM="FLAGS"`), the
//! rig file carrying each camera's family and triangulating; and the one-line refusals of
//! bad per-camera flags (exit 1, nothing written).

use std::path::Path;

use etl_core::model::CameraModel;
use serde_json::Value;

use super::common::etlcal_run;

/// Simulates a 2-camera rig into `dir` (seeded) and writes `noecom.json`, its dataset with
/// E_in only (every view's e_com_ma removed: the lens's surface is needed); returns it.
fn simulate_e_in_only(dir: &Path) -> Value {
    let out = dir.to_str().unwrap();
    let (code, _, stderr) = etlcal_run(&["simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out", out]);
    assert_eq!(code, 0, "{stderr}");
    let mut d: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("rig_dataset.json")).unwrap()).unwrap();
    for v in d["views"].as_array_mut().unwrap() {
        for s in v["cameras"].as_array_mut().unwrap() {
            s.as_object_mut().unwrap().remove("e_com_ma");
        }
    }
    std::fs::write(dir.join("noecom.json"), serde_json::to_string(&d).unwrap()).unwrap();
    d
}

/// Camera 0 with the paper's family and the paper's surface by name, camera 1 in OpenCV's
/// family with its surface from a file: the summary says each camera's request, the rig
/// file carries each family and surface, and `triangulate` puts a corner both cameras saw
/// within 0.1 mm of where the truth has it (camera 0's frame).
#[test]
fn each_camera_its_own_surface_and_distortion_family() {
    let dir = tempfile::tempdir().unwrap();
    let d = simulate_e_in_only(dir.path());
    let surface = dir.path().join("cam1-thermal.json");
    etl_formats::thermal::ThermalFile::paper().save(&surface).unwrap();
    let out = dir.path().join("rig.json");
    let thermal1 = format!("1={}", surface.display());
    let dataset = dir.path().join("noecom.json");
    let args = [
        "calibrate-rig",
        "--dataset",
        dataset.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--thermal",
        "cam0=paper",
        "--thermal",
        &thermal1,
        "--distortion",
        "paper",
        "--camera-flags",
        // Quoted as a shell quotes (a value with spaces would need it).
        "cam1=--distortion 'opencv' --fix-k3",
        "--json",
    ];
    let (code, stdout, stderr) = etlcal_run(&args);
    assert_eq!(code, 0, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    let cameras = &v["summary"]["cameras"];
    assert_eq!(cameras[0]["request"]["thermal"], "paper");
    assert_eq!(cameras[1]["request"]["thermal"], surface.display().to_string());
    assert_eq!(
        (cameras[0]["request"]["distortion"].as_str(), cameras[1]["request"]["distortion"].as_str()),
        (Some("paper"), Some("opencv"))
    );
    assert_eq!(
        (cameras[0]["request"]["fix_k3"].as_bool(), cameras[1]["request"]["fix_k3"].as_bool()),
        (Some(false), Some(true))
    );
    for k in 0..2 {
        let rms = cameras[k]["rms_px"].as_f64().unwrap();
        assert!(rms > 0.1 && rms < 0.5, "camera {k}: {rms}");
    }
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let cal = |k: usize| &written["cameras"][k]["calibration"];
    // A paper-family calibration leaves its family out (the format's default).
    let family = |k: usize| cal(k)["distortion_model"].as_str().unwrap_or("paper").to_owned();
    assert_eq!((family(0).as_str(), family(1).as_str()), ("paper", "opencv"));
    assert_eq!(
        cal(0)["distortion_a"].as_array().unwrap().len() * 5,
        cal(1)["distortion_a"].as_array().unwrap().len() * 3
    );
    assert_eq!(cal(1)["thermal"]["source"], surface.display().to_string());
    // A corner both cameras saw in the middle view: its pixels, E_in and temperatures.
    let view = &d["views"][7];
    let shot = |k: u64| view["cameras"].as_array().unwrap().iter().find(|s| s["camera"] == k).unwrap();
    let (s0, s1) = (shot(0), shot(1));
    let p1 = s1["points"].as_array().unwrap();
    let p0 = s0["points"].as_array().unwrap();
    let (a, b) = p0
        .iter()
        .find_map(|a| p1.iter().find(|b| b[2] == a[2] && b[3] == a[3]).map(|b| (a, b)))
        .expect("a corner both cameras saw");
    let pixel = |k: usize, p: &Value| format!("{k}:{},{}", p[0], p[1]);
    let num = |x: &Value| x.as_f64().unwrap().to_string();
    let (pix0, pix1) = (pixel(0, a), pixel(1, b));
    let tri = [
        "triangulate",
        "--rig",
        out.to_str().unwrap(),
        "--setting",
        &num(&s0["e_in_ma"]),
        &num(&s1["e_in_ma"]),
        "--t",
        &num(&s0["temperature_c"]),
        &num(&s1["temperature_c"]),
        "--pixel",
        &pix0,
        "--pixel",
        &pix1,
        "--json",
    ];
    let (code, stdout, stderr) = etlcal_run(&tri);
    assert_eq!(code, 0, "{stderr}");
    let t: Value = serde_json::from_str(&stdout).unwrap();
    let point = t["points"][0]["point_mm"]
        .as_array()
        .map_or_else(|| t["point_mm"].clone(), |_| t["points"][0]["point_mm"].clone());
    let got: Vec<f64> = point.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let world = [a[2].as_f64().unwrap(), a[3].as_f64().unwrap(), view["z_w_mm"].as_f64().unwrap()];
    let truth = CameraModel::paper_rig().world_to_camera(world);
    let err = (0..3).map(|i| (got[i] - truth[i]).powi(2)).sum::<f64>().sqrt();
    assert!(err < 0.1, "triangulated {got:?}, truth {truth:?} ({err} mm)");
}

/// Each bad per-camera flag is refused in one line naming it (the camera, the flag),
/// exit 1, nothing written.
#[test]
fn bad_per_camera_flags_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    simulate_e_in_only(dir.path());
    let dataset = dir.path().join("noecom.json");
    let out = dir.path().join("out/rig.json");
    let cases: [(&[&str], &str); 13] = [
        (&["--thermal", "paper", "--camera-flags", "cam1=--out x.json"], "--camera-flags \"cam1=--out x.json\": --out is not a per-camera flag"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--solver dense"], "--solver is not a per-camera flag"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--dataset d.json"], "--dataset is not a per-camera flag"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--json"], "--json is not a per-camera flag"),
        (&["--thermal", "paper", "--camera-flags", "cam9=--hold-a0"], "--camera-flags \"cam9=--hold-a0\": \"cam9\" is not a camera of the rig"),
        (&["--thermal", "paper", "--camera-flags", "1=--hold-a0", "--camera-flags", "cam1=--fix-k3"], "camera 1 (cam1) is given its flags twice"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--distortion weird"], "invalid value 'weird' for '--distortion"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--distortion \"opencv"], "--camera-flags \"cam1=--distortion \\\"opencv\": FLAGS has an unclosed quote"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--estimator paper"], "camera 1 (cam1): invalid input: --estimator: one estimator serves every camera"),
        (&["--thermal", "paper", "--camera-flags", "cam1=--method per-setting"], "camera 1 (cam1): invalid input: method: a rig is calibrated by the proposed method only"),
        (&["--thermal", "cam0=paper"], "camera 1 (cam1): views[0].cameras[1] records e_in_ma without e_com_ma, and no temperature surface was given"),
        (&["--thermal", "cam7=paper"], "--thermal \"cam7=paper\": \"cam7\" is not a camera of the rig"),
        (&["--thermal", "cam1=paper", "--thermal", "1=paper"], "--thermal \"1=paper\": camera 1 (cam1) is given a surface twice"),
    ];
    for (flags, expected) in cases {
        let mut args = vec!["calibrate-rig", "--dataset", dataset.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(flags);
        let (code, stdout, stderr) = etlcal_run(&args);
        assert_eq!(code, 1, "{flags:?}: {stderr}");
        assert!(stderr.contains(expected), "expected {expected:?} in {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stdout.is_empty() && !out.exists(), "{flags:?}: written");
    }
}
