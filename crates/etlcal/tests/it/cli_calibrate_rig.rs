//! `etlcal simulate --rig N` and `etlcal calibrate-rig`: a simulated 2-camera rig
//! calibrated jointly from the command line (its extrinsics within 3 standard deviations
//! of the truth, the same by either solver), and the one-line refusals of bad rig
//! datasets (exit 1, nothing written).

use std::path::Path;

use serde_json::Value;

use super::common::etlcal_run;

/// Simulates a 2-camera rig into `dir` (seeded); returns the rig dataset's JSON.
fn simulate(dir: &Path) -> Value {
    let out = dir.to_str().unwrap();
    let (code, _, stderr) = etlcal_run(&["simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out", out]);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(dir.join("rig_dataset.json")).unwrap()).unwrap()
}

#[test]
fn calibrate_rig_recovers_the_simulated_extrinsics() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("truth_rig.json")).unwrap()).unwrap();
    let dataset = dir.path().join("rig_dataset.json");
    let mut results = vec![];
    for solver in ["dense", "sparse"] {
        let out = dir.path().join(format!("out/{solver}/rig.json"));
        let args = [
            "calibrate-rig",
            "--dataset",
            dataset.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--solver",
            solver,
            "--json",
        ];
        let (code, stdout, stderr) = etlcal_run(&args);
        assert_eq!(code, 0, "{stderr}");
        let v: Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(v["summary"]["solver"], solver);
        assert_eq!(v["format"], "etlcal.rig/1");
        let written: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(written["extrinsics"], v["extrinsics"]);
        // The joint covariance over both cameras' numbers, square, for `triangulate`.
        let joint = &written["joint_covariance"];
        assert_eq!(joint["cameras"], serde_json::json!([0, 1]));
        let m = joint["matrix"].as_array().unwrap();
        assert!(m.len() > 12 && m.iter().all(|r| r.as_array().unwrap().len() == m.len()), "{}", m.len());
        let e = &v["extrinsics"][0];
        let t = &truth["extrinsics"][0];
        for (i, key) in ["rotation_rodrigues", "translation_mm"].iter().enumerate() {
            for c in 0..3 {
                let (est, tru) = (e[key][c].as_f64().unwrap(), t[key][c].as_f64().unwrap());
                let std = e["covariance"][3 * i + c][3 * i + c].as_f64().unwrap().sqrt();
                assert!((est - tru).abs() <= 3.0 * std, "{key}[{c}]: {est} vs {tru} (std {std})");
            }
        }
        let rms = v["summary"]["cameras"][1]["rms_px"].as_f64().unwrap();
        assert!(rms > 0.1 && rms < 0.5, "{rms}");
        results.push(e["translation_mm"][0].as_f64().unwrap());
    }
    assert!((results[0] - results[1]).abs() < 1e-6, "{results:?}");
}

/// Each bad rig dataset is refused in one line naming what is wrong, and nothing is
/// written.
#[test]
fn calibrate_rig_refuses_bad_rig_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let good = simulate(dir.path());
    type Edit = fn(&mut Value);
    let cases: [(Edit, &str); 5] = [
        (
            |d| d["views"][0]["cameras"][0]["camera"] = 7.into(),
            "views[0].cameras[0].camera: 7 is not a camera of the rig",
        ),
        (
            |d| {
                for v in d["views"].as_array_mut().unwrap() {
                    v["cameras"].as_array_mut().unwrap().retain(|s| s["camera"] == 0);
                }
                d["views"].as_array_mut().unwrap().retain(|v| !v["cameras"].as_array().unwrap().is_empty());
            },
            "cameras[1]: camera \"cam1\" sees the board in none of the",
        ),
        (
            |d| d["cameras"][1]["board"] = serde_json::json!({"inner_corners": [9, 6], "square_mm": 2.0}),
            "cameras[1].board: camera \"cam1\" names another board than the rig's",
        ),
        (
            |d| d["views"][2]["cameras"][1]["focal_power_dpt"] = 10.0.into(),
            "views[2].cameras[1] gives both e_in_ma and focal_power_dpt",
        ),
        (
            |d| {
                let s = &mut d["views"][1]["cameras"][0];
                s.as_object_mut().unwrap().remove("points");
                s["image"] = "views/c0.png".into();
            },
            "views[1].cameras[0] gives an image but views[0].cameras[0] gives points",
        ),
    ];
    for (i, (edit, expected)) in cases.iter().enumerate() {
        let mut d = good.clone();
        edit(&mut d);
        let path = dir.path().join(format!("bad{i}.json"));
        std::fs::write(&path, serde_json::to_string(&d).unwrap()).unwrap();
        let out = dir.path().join(format!("out{i}/rig.json"));
        let (code, stdout, stderr) =
            etlcal_run(&["calibrate-rig", "--dataset", path.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_eq!(code, 1, "{expected}: {stderr}");
        assert!(stderr.contains(expected), "expected {expected:?} in {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stdout.is_empty());
        assert!(!out.exists(), "{expected}: written");
    }
}

/// The calibrate flags the joint solve cannot honour are refused, nothing written.
#[test]
fn calibrate_rig_refuses_the_per_setting_method_and_a_robust_loss() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let dataset = dir.path().join("rig_dataset.json");
    let out = dir.path().join("rig.json");
    for (flags, expected) in [
        (vec!["--method", "per-setting"], "a rig is calibrated by the proposed method only"),
        (vec!["--robust", "huber"], "robust: the joint solve is least squares"),
    ] {
        let mut args = vec!["calibrate-rig", "--dataset", dataset.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(flags);
        let (code, _, stderr) = etlcal_run(&args);
        assert_eq!(code, 1, "{stderr}");
        assert!(stderr.contains(expected) && stderr.trim_end().lines().count() == 1, "{stderr}");
        assert!(!out.exists());
    }
}

/// `simulate --rig` refuses a rig outside its ranges in one line naming the flag, and
/// writes nothing.
#[test]
fn simulate_rig_refuses_designs_outside_their_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rig");
    for (flags, expected) in [
        (vec!["--rig", "1"], "--rig: 1 is outside 2..=64"),
        (vec!["--rig", "2", "--baseline-mm", "10"], "--baseline-mm 10 mm is outside [60, 150] mm"),
        (vec!["--rig", "2", "--views", "2"], "--views: 2 is outside 3..=10000"),
    ] {
        let mut args = vec!["simulate", "--observations-only", "--out", out.to_str().unwrap()];
        args.extend(flags);
        let (code, _, stderr) = etlcal_run(&args);
        assert_eq!(code, 1, "{stderr}");
        assert!(stderr.contains(expected) && stderr.trim_end().lines().count() == 1, "{stderr}");
        assert!(!out.exists());
    }
}

/// A rig dataset of images: the simulated points rig with each entry's points replaced by
/// an image under `images/` (which the caller writes, or not).
fn images_dataset(points: &Value) -> Value {
    let mut d = points.clone();
    for (i, v) in d["views"].as_array_mut().unwrap().iter_mut().enumerate() {
        for s in v["cameras"].as_array_mut().unwrap() {
            let k = s["camera"].as_u64().unwrap();
            s.as_object_mut().unwrap().remove("points");
            s["image"] = format!("images/cam{k}/view{i:02}.png").into();
        }
    }
    d.as_object_mut().unwrap().remove("offstate_views");
    d
}

/// From images: an image that does not exist, and a camera whose board is found in none
/// of its images, are each refused in one line naming it, nothing written.
#[test]
fn calibrate_rig_from_images_refuses_a_missing_image_and_a_blind_camera() {
    let dir = tempfile::tempdir().unwrap();
    let d = images_dataset(&simulate(dir.path()));
    let path = dir.path().join("rig_images.json");
    std::fs::write(&path, serde_json::to_string(&d).unwrap()).unwrap();
    let out = dir.path().join("out/rig.json");
    let run = || etlcal_run(&["calibrate-rig", "--dataset", path.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let (code, stdout, stderr) = run();
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("images/cam0/view00.png") && stderr.trim_end().lines().count() == 1, "{stderr}");
    assert!(stdout.is_empty() && !out.exists());
    // Every image there, all grey: camera 0's board is found nowhere.
    let size = [1936u32, 1458];
    let grey = etl_sim::render::Image {
        width: size[0],
        height: size[1],
        bit_depth: etl_sim::render::BitDepth::Eight,
        data: vec![128; (size[0] * size[1]) as usize],
    };
    for v in d["views"].as_array().unwrap() {
        for s in v["cameras"].as_array().unwrap() {
            let p = dir.path().join(s["image"].as_str().unwrap());
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            grey.save_png(&p).unwrap();
        }
    }
    let (code, stdout, stderr) = run();
    assert_eq!(code, 1, "{stderr}");
    let named = stderr.contains("camera 0 (cam0): ") && stderr.contains("the board was found in 0 of 15 views");
    assert!(named && stderr.trim_end().lines().count() == 1, "{stderr}");
    assert!(stdout.is_empty() && !out.exists());
}
