//! From images to a calibration through the real binary: `etlcal simulate` renders the
//! paper rig, `etlcal calibrate --dataset` detects and calibrates; views whose board is
//! not found are reported and skipped; a missing image fails the run before any work and
//! writes nothing.

use serde_json::Value;

use super::common::etlcal_run as etlcal;

#[test]
fn images_to_calibration_with_skipped_views_and_a_missing_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, out, err) = etlcal(&["simulate", "--out", d, "--seed", "3", "--json"]);
    assert_eq!(code, 0, "{err}");
    let sim: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(sim["images"], 25);
    let dataset = dir.path().join("dataset.json");
    let cal = dir.path().join("cal.json");
    let run = |out: &std::path::Path| {
        etlcal(&["calibrate", "--dataset", dataset.to_str().unwrap(), "--out", out.to_str().unwrap(), "--json"])
    };
    let (code, out, err) = run(&cal);
    assert_eq!(code, 0, "{err}");
    let c: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(c["format"], "etlcal.calibration/1");
    let truth = etl_core::model::CameraModel::paper_rig();
    let fx = |kf: &Value, e: f64| (0..4).map(|i| kf[i].as_f64().unwrap() * e.powi(i as i32)).sum::<f64>();
    for e in [80.0, 150.0, 225.0] {
        let rel = fx(&c["kf_x"], e) / truth.focal_lengths(e).0 - 1.0;
        assert!(rel.abs() < 0.01, "fx({e}) off by {rel}");
    }
    // The rig's ChArUco boards need no per-view hints; Zhang takes the lens-off views from
    // their board file, partial views and all (as a checkerboard pattern it could not).
    let ds: Value = serde_json::from_str(&std::fs::read_to_string(&dataset).unwrap()).unwrap();
    assert_eq!(ds["board"]["type"], "charuco");
    assert!(ds["views"]
        .as_array()
        .unwrap()
        .iter()
        .all(|v| v.get("first_corner").is_none() && v.get("board").is_none()));
    let off_board = dir.path().join("offstate-board.json");
    std::fs::write(&off_board, ds["offstate_board"].to_string()).unwrap();
    let mut args = vec!["zhang".to_owned(), "--board".into(), off_board.to_str().unwrap().into(), "--json".into()];
    args.extend((0..10).map(|k| dir.path().join(format!("offstate/off{k:02}.png")).to_str().unwrap().to_owned()));
    let (code, out, err) = etlcal(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    let z: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(z["views_used"], 10);
    let (f0, pp) = (truth.focal_lengths(0.0).0, truth.principal_point);
    assert!((z["fx"].as_f64().unwrap() / f0 - 1.0).abs() < 0.005, "{z}");
    assert!((z["u0"].as_f64().unwrap() - pp[0]).abs() < 5.0 && (z["v0"].as_f64().unwrap() - pp[1]).abs() < 5.0, "{z}");
    // A view whose image shows no board is skipped and named; the run goes on.
    let blank = image::GrayImage::from_pixel(1936, 1458, image::Luma([128]));
    blank.save(dir.path().join("views/view03.png")).unwrap();
    let cal2 = dir.path().join("cal2.json");
    let (code, _, err) = run(&cal2);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("view03.png"), "the skipped view is reported: {err}");
    assert!(cal2.exists());
    // A missing image fails before any work, and the earlier output stays whole.
    let before = std::fs::read(&cal).unwrap();
    std::fs::remove_file(dir.path().join("views/view05.png")).unwrap();
    let (code, _, err) = run(&cal);
    assert_ne!(code, 0);
    assert!(err.contains("view05.png") && err.lines().count() == 1, "{err}");
    assert_eq!(std::fs::read(&cal).unwrap(), before);
}
