//! `etlcal triangulate` and `etlcal rectify` on the synthetic two-camera rig of
//! `fixtures/rig/` (`etl_sim::stereo_rig`, opencv family, moving centres): the point of
//! noise-free pixels comes back, the rectification is the library's, and every bad input
//! is one line with nothing written.

use std::path::{Path, PathBuf};
use std::process::Output;

use etl_calib::rig::{Rig, RigSetting};
use etl_formats::Trust;
use serde_json::Value;

use super::common::etlcal;

fn rig_json() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/rig/rig.json")
}

/// Camera 0's and camera 1's pixels of `x0` (camera 0's frame at its setting) at E_in
/// (150, 160) mA and (30, 31) degC, through the library's rig.
fn pixels_of(x0: [f64; 3]) -> [[f64; 2]; 2] {
    let rig = Rig::load(&rig_json()).unwrap();
    let at = rig.at(&[RigSetting::of(150.0), RigSetting::of(160.0)], &[30.0, 31.0], Trust::Refuse).unwrap();
    [
        at.cameras()[0].project_camera_point(x0).unwrap(),
        at.cameras()[1].project_camera_point(at.poses()[1].apply(x0)).unwrap(),
    ]
}

fn json(out: &Output) -> Value {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn refused(out: Output, what: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("etlcal: error: ") && err.contains(what), "{err}");
}

const SETTINGS: [&str; 8] = ["--setting", "150", "160mA", "--t", "30", "31", "--sigma-px", "0.2"];

#[test]
fn triangulate_gives_the_point_of_noise_free_pixels_back() {
    let rig = rig_json();
    let x = [25.0, -12.0, 820.0];
    let [p0, p1] = pixels_of(x);
    let (a, b) = (format!("0:{},{}", p0[0], p0[1]), format!("right:{},{}", p1[0], p1[1]));
    let mut args = vec!["triangulate", "--rig", rig.to_str().unwrap(), "--pixel", &a, "--pixel", &b, "--json"];
    args.extend_from_slice(&SETTINGS);
    let j = json(&etlcal(&args));
    let p = &j["points"][0];
    for i in 0..3 {
        assert!((p["point_mm"][i].as_f64().unwrap() - x[i]).abs() < 1e-6, "{p}");
        let var = p["covariance_mm2"][i][i].as_f64().unwrap();
        let parts = p["from_pixels_mm2"][i][i].as_f64().unwrap() + p["from_calibration_mm2"][i][i].as_f64().unwrap();
        assert!((var - parts).abs() < 1e-12 * var && (p["std_mm"][i].as_f64().unwrap() - var.sqrt()).abs() < 1e-12);
    }
    assert_eq!((j["sigma_px"].as_f64(), j["pixel_only"].as_bool()), (Some(0.2), Some(false)));
    assert_eq!(p["extrapolated"], false);
    // The fixture's rig has no joint covariance: independent groups, said so.
    assert_eq!(p["calibration_covariance"], "independent");
    // A file of two points, the second seen by camera 1 alone: refused naming it.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("pixels.json");
    std::fs::write(&file, serde_json::to_string(&[[Some(p0), Some(p1)], [Some(p0), Some(p1)]]).unwrap()).unwrap();
    let mut args = vec![
        "triangulate",
        "--rig",
        rig.to_str().unwrap(),
        "--pixels",
        file.to_str().unwrap(),
        "--json",
        "--pixel-only",
    ];
    args.extend_from_slice(&SETTINGS);
    let j = json(&etlcal(&args));
    assert_eq!(j["points"].as_array().unwrap().len(), 2);
    assert!(j["points"][1]["from_calibration_mm2"].is_null());
    assert!(j["points"][1]["calibration_covariance"].is_null());
    std::fs::write(&file, serde_json::to_string(&[[None, Some(p1)]]).unwrap()).unwrap();
    refused(etlcal(&args), "too few cameras seeing the point");
}

#[test]
fn rectify_writes_the_librarys_rectification_exports_and_maps() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rect");
    let rig = rig_json();
    let mut args = vec!["rectify", "--rig", rig.to_str().unwrap(), "--pair", "0,1", "--out", out.to_str().unwrap()];
    args.extend_from_slice(&SETTINGS[..6]);
    args.extend_from_slice(&["--format", "ros", "mrcal", "--maps", "--json"]);
    let j = json(&etlcal(&args));
    let lib = Rig::load(&rig)
        .unwrap()
        .at(&[RigSetting::of(150.0), RigSetting::of(160.0)], &[30.0, 31.0], Trust::Refuse)
        .unwrap()
        .stereo_rectify(0, 1, -1.0)
        .unwrap();
    assert_eq!(j["P2"], serde_json::json!(lib.rectification.p2));
    assert!((j["baseline_mm"].as_f64().unwrap() - lib.baseline_mm()).abs() < 1e-12);
    let mut names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "left.cameramodel",
            "left.yaml",
            "left_map_x.npy",
            "left_map_y.npy",
            "right.cameramodel",
            "right.yaml",
            "right_map_x.npy",
            "right_map_y.npy",
            "stereo.yaml"
        ]
    );
    let stereo = std::fs::read_to_string(out.join("stereo.yaml")).unwrap();
    assert!(stereo.starts_with("%YAML:1.0\n---\n") && stereo.contains("P2: !!opencv-matrix"));
    let ros = std::fs::read_to_string(out.join("right.yaml")).unwrap();
    let p2 = lib.rectification.p2;
    assert!(ros.contains(&etl_formats::export::num(p2[0][3])) && p2[0][3] < 0.0, "{ros}");
}

/// Each bad input: one line naming it, nothing written.
#[test]
fn rig_verbs_refuse_bad_inputs_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rect");
    let o = out.to_str().unwrap();
    let rig = rig_json();
    let r = rig.to_str().unwrap();
    let rect = |extra: &[&str]| {
        let mut args = vec!["rectify", "--rig", r, "--out", o];
        args.extend_from_slice(extra);
        etlcal(&args)
    };
    refused(rect(&["--pair", "0,1", "--setting", "150", "--t", "30", "31"]), "--setting: the rig has 2 cameras, got 1");
    refused(rect(&["--pair", "0,1", "--setting", "150", "160", "--t", "30"]), "--t: the rig has 2 cameras, got 1");
    refused(
        rect(&["--pair", "0,1", "--setting", "150", "12dpt", "--t", "30", "31"]),
        "camera 1 (right): invalid input: a focal_power setting (dpt) for a calibration whose setting is current (mA)",
    );
    refused(
        rect(&["--pair", "0,2", "--setting", "150", "160", "--t", "30", "31"]),
        "--pair: camera 2 is not one of the rig's cameras 0..1",
    );
    refused(
        rect(&["--pair", "0,1", "--alpha", "0", "--setting", "150", "160", "--t", "30", "31"]),
        "--alpha 0: only -1",
    );
    assert!(!out.exists());
    // A rig file whose calibrations are missing.
    let lonely = dir.path().join("rig.json");
    std::fs::copy(&rig, &lonely).unwrap();
    refused(
        etlcal(&[
            "rectify",
            "--rig",
            lonely.to_str().unwrap(),
            "--pair",
            "0,1",
            "--setting",
            "150",
            "160",
            "--t",
            "30",
            "31",
            "--out",
            o,
        ]),
        "cameras[0].calibration_path: ",
    );
    assert!(!out.exists());
    // A calibration without its covariance: triangulate refuses unless --pixel-only.
    let mut file: Value = serde_json::from_str(&std::fs::read_to_string(&rig).unwrap()).unwrap();
    let fixtures = rig.parent().unwrap();
    for (k, name) in ["left.json", "right.json"].iter().enumerate() {
        let mut cal: Value = serde_json::from_str(&std::fs::read_to_string(fixtures.join(name)).unwrap()).unwrap();
        if k == 1 {
            cal.as_object_mut().unwrap().remove("covariance");
        }
        std::fs::write(dir.path().join(name), cal.to_string()).unwrap();
    }
    file["cameras"][0]["calibration_path"] = "left.json".into();
    std::fs::write(&lonely, file.to_string()).unwrap();
    let tri = |extra: &[&str]| {
        let mut args =
            vec!["triangulate", "--rig", lonely.to_str().unwrap(), "--pixel", "0:1000,700", "--pixel", "1:880,705"];
        args.extend_from_slice(&SETTINGS);
        args.extend_from_slice(extra);
        etlcal(&args)
    };
    refused(tri(&[]), "camera 1 (right): pass pixel-only to leave the calibration's part out");
    assert!(tri(&["--pixel-only"]).status.success());
}
