//! `etlcal measure` as the built binary: a 2 mm stage move between two rendered images of
//! the paper rig, measured with the demo's calibration, and a refused image.

use serde_json::Value;

use super::common::{etlcal, render_move_pair};

fn json_of(args: &[&str]) -> Value {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn measures_a_2_mm_stage_move_in_rendered_images() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    json_of(&["demo", "--no-images", "--out", &p("demo"), "--json"]);
    let cal = p("demo/calibration.json");
    // The board must stay in the image: at this current and 2 mm nearer it does.
    // The compensated current of (E_in, T) = (153 mA, 30 degC) through the paper's surface,
    // which the demo's calibration records.
    let e_com = json_of(&["thermal", "eval", "--t", "30", "--e-in", "153", "--thermal", "paper", "--json"])["e_com_ma"]
        .as_f64()
        .unwrap();
    let e = format!("{e_com}");
    let z_a_mm = render_move_pair(&p("a.png"), &p("b.png"), &e);
    let z_b = format!("{}", z_a_mm - 2.0);
    let measure_at = |t: &str, a: &str, b: &str, extra: &[&str]| {
        let mut args = vec!["measure", "--calibration", &cal, "--e-in", "153", "--t", t, a, b];
        args.extend(["--pattern", "9x7", "--square", "1.5"]);
        args.extend(extra);
        etlcal(&args)
    };
    let measure = |a: &str, b: &str, json: bool| measure_at("30", a, b, if json { &["--json"] } else { &[] });
    // 80 degC is outside the calibration's thermal range (27..37 degC): the temperature is
    // named (not the current), unless extrapolation is asked for, and then it is marked.
    let out = measure_at("80", &p("a.png"), &p("b.png"), &[]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("temperature_c = 80 is outside [26, 38]") && err.lines().count() == 1, "{err}");
    let out = measure_at("37.5", &p("a.png"), &p("b.png"), &["--allow-extrapolation", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let m: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(m["extrapolated"], Value::Bool(false), "37.5 degC is within the 1 degC margin: {m}");
    let out = measure(&p("a.png"), &p("b.png"), true);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let m: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((m["e_com_ma"].as_f64().unwrap() - e_com).abs() < 1e-9, "{m}");
    let dist = m["distance_mm"].as_f64().unwrap();
    assert!((dist - 2.0).abs() < 0.02, "distance {dist} mm for a 2 mm move");
    // The standard deviation (pixel noise and the calibration's covariance): the true move,
    // R (0, 0, -2) of the rendered rig, lies within 4 of them on each axis, and they are
    // microns, not nothing.
    assert_eq!(m["std_includes_calibration"], Value::Bool(true), "{m}");
    let r =
        etl_core::model::rotation::rodrigues_to_matrix(etl_core::model::CameraModel::paper_rig().rotation_rodrigues);
    for i in 0..3 {
        let d = m["displacement_mm"][i].as_f64().unwrap();
        let s = m["displacement_std_mm"][i].as_f64().unwrap();
        assert!(s > 1e-5 && s < 0.02, "std {s} mm: {m}");
        assert!((d - (-2.0 * r[i][2])).abs() < 4.0 * s, "axis {i}: {d} against {} +- {s}: {m}", -2.0 * r[i][2]);
    }
    assert!(m["pose_a"]["sigma_px"].as_f64().unwrap() > 0.0, "{m}");
    // The same move of the rig's ChArUco board, which overflows the frame at this stage
    // position: `--board FILE`, each pose from the corners its image shows.
    let board = p("charuco.json");
    std::fs::write(
        &board,
        r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}"#,
    )
    .unwrap();
    let z_a = z_a_mm.to_string();
    let render_charuco = |out: &str, z: &str, seed: &str| {
        json_of(&["render", "--out", out, "--e-com", &e, "--z-mm", z, "--board", &board, "--seed", seed, "--json"])
    };
    let ca = render_charuco(&p("ca.png"), &z_a, "3");
    render_charuco(&p("cb.png"), &z_b, "4");
    assert!(ca["ids"].as_array().unwrap().len() < 168, "the board overflows the frame");
    let (ca_png, cb_png) = (p("ca.png"), p("cb.png"));
    let mc = json_of(&[
        "measure",
        "--calibration",
        &cal,
        "--e-in",
        "153",
        "--t",
        "30",
        &ca_png,
        &cb_png,
        "--board",
        &board,
        "--json",
    ]);
    let dist = mc["distance_mm"].as_f64().unwrap();
    assert!((dist - 2.0).abs() < 0.02, "ChArUco: distance {dist} mm for a 2 mm move");
    // A calibration file without a covariance (older files): the pixel noise's part alone,
    // said on stderr and in the JSON.
    let mut old: Value = serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    old.as_object_mut().unwrap().remove("covariance").unwrap();
    let old_cal = p("old.json");
    std::fs::write(&old_cal, old.to_string()).unwrap();
    let (a_png, b_png) = (p("a.png"), p("b.png"));
    let out = etlcal(&[
        "measure",
        "--calibration",
        &old_cal,
        "--e-in",
        "153",
        "--t",
        "30",
        &a_png,
        &b_png,
        "--pattern",
        "9x7",
        "--square",
        "1.5",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let o: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(o["std_includes_calibration"], Value::Bool(false), "{o}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("has no covariance"));
    let (s_old, s_new) = (o["displacement_std_mm"][2].as_f64().unwrap(), m["displacement_std_mm"][2].as_f64().unwrap());
    assert!(s_old > 0.0 && s_old < s_new, "pixel alone {s_old} against with calibration {s_new}");
    // An image of the wrong size: one line naming it, exit 1.
    let small = dir.path().join("small.png");
    image::GrayImage::new(64, 48).save(&small).unwrap();
    let out = measure(&p("a.png"), small.to_str().unwrap(), false);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("small.png"), "{err}");
}
