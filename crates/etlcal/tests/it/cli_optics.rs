//! `etlcal simulate --optics`: the paper's procedure traced through the ray-traced rigs of
//! fixtures/optics (etl_sim::optics), against what the optics are (the paraxial truth the
//! same run writes, and the closed forms of etl-sim's own tests), and its bad input.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::common::etlcal_run;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn fixture(name: &str) -> String {
    format!("{ROOT}/fixtures/optics/{name}")
}

fn read(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn simulate(optics: &str, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["simulate", "--optics", optics, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    etlcal_run(&args)
}

#[test]
fn a_traced_rig_gives_the_papers_views_and_its_truth() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("cooke");
    let (code, stdout, err) = simulate(&fixture("cooke-16mm-centred.json"), &out, &["--seed", "3", "--json"]);
    assert_eq!(code, 0, "{err}");
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    let obs = read(&out.join("observations.json"));
    let truth = read(&out.join("truth.json"));
    let views = obs["views"].as_array().unwrap();
    assert_eq!(views.len(), 15, "the paper's 15 currents");
    assert_eq!(summary["views"], 15);
    assert_eq!(obs["offstate_views"].as_array().unwrap().len(), 10);
    assert_eq!(obs["setting_views"].as_array().unwrap().len(), 15 * 8);
    // The farthest ETL view sees the whole 14 x 12 board; nearer ones, magnified, part of
    // it (the corners whose spots fall inside the image), never fewer than 60.
    let counts: Vec<usize> = views.iter().map(|v| v["points"].as_array().unwrap().len()).collect();
    assert!(counts[0] == 168 && counts.iter().all(|&n| (60..=168).contains(&n)), "{counts:?}");
    assert_eq!(views[0]["e_com_ma"], 80.0);
    assert_eq!(truth["format"], "etlcal.optics-truth/1");
    let settings = truth["settings"].as_array().unwrap();
    assert_eq!(settings.len(), 15);
    let f: Vec<f64> = settings.iter().map(|s| s["focal_length_mm"].as_f64().unwrap()).collect();
    let pupil: Vec<f64> = settings.iter().map(|s| s["entrance_pupil_z_mm"].as_f64().unwrap()).collect();
    let focus: Vec<f64> = settings.iter().map(|s| s["focus_distance_mm"].as_f64().unwrap()).collect();
    // More ETL power at more current: a shorter focal length and a nearer focus, and the
    // entrance pupil (the model's projection centre) moves along the axis.
    assert!(f.windows(2).all(|w| w[1] < w[0]) && focus.windows(2).all(|w| w[1] < w[0]), "{f:?} {focus:?}");
    let shift = (pupil[14] - pupil[0]).abs();
    assert!((0.3..2.0).contains(&shift), "pupil shift {shift} mm over 80..225 mA");
    // The board's scale in the image follows the focal length over the distance: near the
    // centre a 1.5 mm square spans about f / pitch * 1.5 / (d - f) px, d from the entrance
    // pupil (the thin-lens magnification, whose principal plane is not the pupil: a few
    // percent at the far view, more near), growing as the focus comes nearer.
    let pitch = read(Path::new(&fixture("cooke-16mm-centred.json")))["sensor"]["pixel_pitch_mm"].as_f64().unwrap();
    let mut spacings = vec![];
    for (k, v) in views.iter().enumerate() {
        let p = v["points"].as_array().unwrap();
        // The corner at board (x, y) mm, found by its world coordinates.
        let px = |x: f64, y: f64| {
            let q = p.iter().find(|q| q["world_mm"][0] == x && q["world_mm"][1] == y).expect("a central corner");
            [q["pixel"][0].as_f64().unwrap(), q["pixel"][1].as_f64().unwrap()]
        };
        let (a, b) = (px(9.0, 9.0), px(10.5, 9.0));
        let spacing = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        let expected = f[k] / pitch * 1.5 / (focus[k] - pupil[k] - f[k]);
        let tolerance = if k == 0 { 0.03 } else { 0.08 };
        assert!((spacing / expected - 1.0).abs() < tolerance, "view {k}: {spacing} px, expected {expected}");
        spacings.push(spacing);
    }
    assert!(spacings.windows(2).all(|w| w[1] > w[0]), "{spacings:?}");
}

#[test]
fn the_seed_draws_the_pixel_noise_and_nothing_else() {
    let d = tempfile::tempdir().unwrap();
    // The fixture's procedure at three of its currents and fewer views: what the seed
    // draws does not depend on how many views there are, and the test runs three traces.
    let mut optics = read(Path::new(&fixture("cooke-16mm-centred.json")));
    optics["procedure"]["e_com_ma"] = serde_json::json!([80.0, 150.0, 225.0]);
    optics["procedure"]["setting_views_per_current"] = 3.into();
    let small = d.path().join("small.json");
    std::fs::write(&small, serde_json::to_string(&optics).unwrap()).unwrap();
    let run = |seed: &str, noise: &str| -> PathBuf {
        let out = d.path().join(format!("s{seed}-{noise}"));
        let (code, _, err) = simulate(small.to_str().unwrap(), &out, &["--seed", seed, "--pixel-noise-px", noise]);
        assert_eq!(code, 0, "{err}");
        out.join("observations.json")
    };
    let bytes = |p: PathBuf| std::fs::read(p).unwrap();
    assert_eq!(bytes(run("1", "0")), bytes(run("2", "0")), "noise-free traces do not depend on the seed");
    let (noisy, clean) = (read(&run("2", "0.05")), read(&d.path().join("s2-0/observations.json")));
    let pixels = |v: &Value| -> Vec<f64> {
        let points = v["views"].as_array().unwrap().iter().flat_map(|w| w["points"].as_array().unwrap().clone());
        points.flat_map(|p| [p["pixel"][0].as_f64().unwrap(), p["pixel"][1].as_f64().unwrap()]).collect()
    };
    let diff: Vec<f64> = pixels(&noisy).iter().zip(pixels(&clean)).map(|(a, b)| a - b).collect();
    let rms = (diff.iter().map(|d| d * d).sum::<f64>() / diff.len() as f64).sqrt();
    assert!((0.045..0.055).contains(&rms), "pixel noise RMS {rms} px, 0.05 asked");
}

#[test]
fn bad_optics_are_refused_naming_the_field_and_nothing_is_written() {
    let d = tempfile::tempdir().unwrap();
    let original = read(Path::new(&fixture("cooke-16mm-centred.json")));
    type Change = fn(&mut Value);
    let cases: [(&str, Change, &str); 4] = [
        ("format.json", |v| v["format"] = "etlcal.optics/9".into(), "format"),
        ("radius.json", |v| v["prime"]["surfaces"][0]["radius_mm"] = 0.05.into(), "prime.surfaces[0].radius_mm"),
        ("stop.json", |v| v["prime"]["stop"] = 40.into(), "prime.stop"),
        ("tiny.json", |v| v["prime"]["surfaces"][0]["semi_diameter_mm"] = 0.02.into(), "prime.surfaces[0]"),
    ];
    for (name, change, field) in cases {
        let mut v = original.clone();
        change(&mut v);
        let path = d.path().join(name);
        std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
        let out = d.path().join("out");
        let (code, stdout, err) = simulate(path.to_str().unwrap(), &out, &[]);
        assert_eq!(code, 1, "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(field), "{name}: {field}: {err}");
        assert!(stdout.is_empty() && !out.exists(), "{name}: nothing written");
    }
    // The model simulation's flags are refused beside --optics, before anything is read.
    let out = d.path().join("out");
    for flag in [["--setting-views", ""], ["--stage-noise-um", "5"], ["--config", "sim.json"]] {
        let args: Vec<&str> = flag.into_iter().filter(|a| !a.is_empty()).collect();
        let (code, _, err) = simulate(&fixture("cooke-16mm-centred.json"), &out, &args);
        assert_eq!(code, 2, "{flag:?}: {err}");
        assert!(err.contains("cannot be used with"), "{flag:?}: {err}");
        assert!(!out.exists());
    }
    let (code, _, err) = simulate(&fixture("cooke-16mm-centred.json"), &out, &["--pixel-noise-px", "-1"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--pixel-noise-px -1 px is outside [0, 100] px"), "{err}");
    assert!(!out.exists());
}

/// `simulate --rig 2 --optics FILE`: two traced Cooke cameras on one stage, the record as
/// an `etlcal.rig-dataset/1` of points, the truth as each camera's pose and optics.
#[test]
fn a_traced_rig_of_two_cameras_gives_a_rig_dataset_and_its_truth() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("rig");
    let cooke = fixture("cooke-16mm-centred.json");
    let (code, stdout, err) =
        simulate(&cooke, &out, &["--rig", "2", "--views", "3", "--baseline-mm", "25", "--seed", "4", "--json"]);
    assert_eq!(code, 0, "{err}");
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((summary["cameras"].as_u64(), summary["views"].as_u64()), (Some(2), Some(3)));
    let dataset = etl_formats::rig_dataset::RigDataset::load(&out.join("rig_dataset.json")).unwrap();
    assert_eq!((dataset.cameras.len(), dataset.views.len(), dataset.offstate_views.len()), (2, 3, 10));
    assert!(dataset.views.iter().all(|v| v.cameras.len() == 2 && v.cameras.iter().all(|s| s.e_com_ma.is_some())));
    let truth = read(&out.join("truth.json"));
    assert_eq!(truth["format"], "etlcal.optics-rig-truth/1");
    assert_eq!((truth["baseline_mm"].as_f64(), truth["pixel_noise_px"].as_f64()), (Some(25.0), Some(0.05)));
    let cams = truth["cameras"].as_array().unwrap();
    // Camera 0 where its file puts it; camera 1 25 mm from its origin.
    assert_eq!(cams[0]["rotation_rodrigues"], serde_json::json!([0.004, -0.003, 0.002]));
    let centre = |c: &Value| {
        let om: Vec<f64> = c["rotation_rodrigues"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let t: Vec<f64> = c["translation_mm"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let r = etl_core::model::rotation::rodrigues_to_matrix([om[0], om[1], om[2]]);
        etl_core::model::rotation::mat_t_vec(&r, [-t[0], -t[1], -t[2]])
    };
    let (c0, c1) = (centre(&cams[0]), centre(&cams[1]));
    let b = (0..3).map(|i| (c1[i] - c0[i]).powi(2)).sum::<f64>().sqrt();
    assert!((b - 25.0).abs() < 1e-9, "{b}");
    assert_eq!(cams[1]["settings"].as_array().unwrap().len(), 15);
    // The recorded currents lie inside the procedure's 80..225 mA.
    let e: Vec<f64> = dataset.views.iter().flat_map(|v| &v.cameras).filter_map(|s| s.e_com_ma).collect();
    assert!(e.iter().all(|e| (80.0..=225.0).contains(e)), "{e:?}");
}

#[test]
fn a_bad_traced_rig_is_refused_naming_the_flag_and_nothing_is_written() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let cooke = fixture("cooke-16mm-centred.json");
    let cases: [(&[&str], &str); 5] = [
        (&["--rig", "3", "--optics", &cooke], "--optics: 2 files for 3 cameras"),
        (&["--rig", "2", "--moving-centre"], "--moving-centre"),
        (&["--rig", "2", "--views", "2"], "--views"),
        (&["--rig", "2", "--baseline-mm", "2"], "--baseline-mm"),
        // 150 mm off, camera 1 stands farther than its lens can focus.
        (&["--rig", "2", "--baseline-mm", "150"], "--baseline-mm: at 150 mm the cameras share"),
    ];
    for (args, want) in cases {
        let (code, stdout, err) = simulate(&cooke, &out, args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {want}: {err}");
        assert!(stdout.is_empty() && !out.exists(), "{args:?}: nothing written");
    }
    // Two files without --rig.
    let (code, _, err) = simulate(&cooke, &out, &["--optics", &cooke]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--optics: 2 files given"), "{err}");
    assert!(!out.exists());
}
