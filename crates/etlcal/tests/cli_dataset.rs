//! From images to a calibration through the real binary: `etlcal simulate` renders the
//! paper rig, `etlcal calibrate --dataset` detects and calibrates; views whose board is
//! not found are reported and skipped; a missing image fails the run before any work and
//! writes nothing.
use std::process::Command;

use serde_json::Value;

fn etlcal(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_etlcal")).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

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
