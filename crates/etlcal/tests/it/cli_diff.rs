//! `etlcal diff`: two calibrations' projections compared at one setting, against what the
//! difference between them must give, and its bad input (one line, nothing written).

use std::path::Path;

use serde_json::Value;

use super::common::etlcal_run as etlcal;

const CAL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/service/calibration.json");

fn diff_json(a: &str, b: &str, extra: &[&str]) -> Value {
    let mut args = vec!["diff", a, b, "--e-com", "150", "--json"];
    args.extend_from_slice(extra);
    let (code, out, err) = etlcal(&args);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// A calibration with its principal point moved by (`du`, 0) px, written to `path`.
fn shifted(path: &Path, du: f64) -> String {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(CAL).unwrap()).unwrap();
    v["principal_point"][0] = (v["principal_point"][0].as_f64().unwrap() + du).into();
    std::fs::write(path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn a_calibration_differs_from_itself_by_nothing_and_from_a_moved_principal_point_by_the_move() {
    let d = tempfile::tempdir().unwrap();
    let same = diff_json(CAL, CAL, &[]);
    assert_eq!(same["grid"], serde_json::json!([64, 48]));
    assert!(same["max_px"].as_f64().unwrap() < 1e-9 && same["rotated_max_px"].as_f64().unwrap() < 1e-9, "{same}");
    assert_eq!(same["unmapped"], 0);
    let b = shifted(&d.path().join("b.json"), 2.0);
    let heat = d.path().join("maps/heat.png");
    let j = diff_json(CAL, &b, &["--grid", "32x24", "--heatmap", heat.to_str().unwrap()]);
    let (rms, max) = (j["rms_px"].as_f64().unwrap(), j["max_px"].as_f64().unwrap());
    assert!((rms - 2.0).abs() < 1e-6 && (max - 2.0).abs() < 1e-6, "{j}");
    // A rotation of the camera explains nearly all of a principal point's move.
    assert!(j["rotated_rms_px"].as_f64().unwrap() < 0.2, "{j}");
    assert_eq!(j["e_com_ma"], 150.0);
    let png = image::open(&heat).unwrap();
    assert_eq!((png.width() % 32, png.height() % 24, png.width() / 32), (0, 0, png.height() / 24));
    // The human line says the same.
    let (code, out, err) = etlcal(&["diff", CAL, &b, "--e-com", "150", "--grid", "32x24"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("intrinsics only rms 2.0000 px, max 2.0000 px"), "{out}");
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let d = tempfile::tempdir().unwrap();
    let heat = d.path().join("heat.png");
    let h = heat.to_str().unwrap();
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(CAL).unwrap()).unwrap();
    v["image_size"] = serde_json::json!([640, 480]);
    let small = d.path().join("small.json");
    std::fs::write(&small, serde_json::to_string(&v).unwrap()).unwrap();
    let s = small.to_str().unwrap();
    let cases: [(&[&str], i32, &str); 5] = [
        (&["diff", CAL, s, "--e-com", "150", "--heatmap", h], 1, "the same image is compared"),
        (&["diff", CAL, CAL, "--e-com", "150", "--grid", "0x24", "--heatmap", h], 1, "grid 0x24"),
        (&["diff", CAL, CAL, "--e-com", "150", "--grid", "many"], 2, "is not a grid CxR"),
        (&["diff", CAL, CAL, "--e-com", "1000", "--heatmap", h], 1, "e_com_ma = 1000 is outside"),
        (&["diff", CAL, CAL, "--e-com", "150", "--heatmap", CAL], 1, "is the input"),
    ];
    for (args, want, what) in cases {
        let (code, _, err) = etlcal(args);
        assert_eq!(code, want, "{args:?}: {err}");
        assert!(err.contains(what) && err.trim_end().lines().count() == 1, "{args:?}: {err}");
        assert!(!heat.exists(), "{args:?} wrote the heat map");
    }
    assert_eq!(
        serde_json::from_str::<Value>(&std::fs::read_to_string(CAL).unwrap()).unwrap()["format"],
        "etlcal.calibration/1"
    );
}
