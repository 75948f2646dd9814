//! `etlcal render` run as the built binary: the image and its corners file, the corners
//! against the model and against `etlcal detect` on the written image, and bad input (one
//! line, non-zero exit, nothing written).
use std::process::{Command, Output};

use etl_core::model::CameraModel;
use serde_json::Value;

fn etlcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_etlcal")).args(args).output().expect("run etlcal")
}

#[test]
fn renders_an_image_whose_detected_corners_are_the_true_ones() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("b.png");
    let out = etlcal(&["render", "--out", img.to_str().unwrap(), "--e-com", "150", "--seed", "3", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let file: Value = serde_json::from_slice(&std::fs::read(dir.path().join("b.png.corners.json")).unwrap()).unwrap();
    assert_eq!(j, file);
    let corners = j["corners_px"].as_array().unwrap();
    assert_eq!(corners.len(), 168);
    // Corner (i, j) is the model's projection of (1.5 i, 1.5 j, z).
    let z = j["z_w_mm"].as_f64().unwrap();
    let p = CameraModel::paper_rig().project([1.5 * 3.0, 1.5 * 2.0, z], 150.0).unwrap();
    let c = &corners[2 * 14 + 3];
    assert!((c[0].as_f64().unwrap() - p[0]).abs() < 1e-9 && (c[1].as_f64().unwrap() - p[1]).abs() < 1e-9);
    // The detector finds them again to a few hundredths of a pixel.
    let det = etlcal(&["detect", img.to_str().unwrap(), "--pattern", "14x12", "--json"]);
    assert!(det.status.success());
    let d: Value = serde_json::from_slice(&det.stdout).unwrap();
    let found = d["images"][0]["corners_px"].as_array().unwrap();
    let in_image = j["in_image"].as_array().unwrap();
    if in_image.iter().all(|b| b.as_bool() == Some(true)) {
        let mut s = 0.0;
        for (a, b) in found.iter().zip(corners) {
            let (du, dv) =
                (a[0].as_f64().unwrap() - b[0].as_f64().unwrap(), a[1].as_f64().unwrap() - b[1].as_f64().unwrap());
            s += du * du + dv * dv;
        }
        let rms = (s / found.len() as f64).sqrt();
        assert!(rms < 0.03, "rms {rms}");
    }
}

#[test]
fn bad_input_fails_in_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("x.png");
    let p = img.to_str().unwrap();
    let missing = dir.path().join("no/such/dir/x.png");
    for (args, needle) in [
        (vec!["render", "--out", p, "--bit-depth", "12"], "bit-depth"),
        (vec!["render", "--out", p, "--square=-1"], "square"),
        (vec!["render", "--out", p, "--pattern", "2x12"], "3"),
        (vec!["render", "--out", missing.to_str().unwrap()], "does not exist"),
        (vec!["render", "--out", p, "--e-com", "NaN"], ""),
    ] {
        let out = etlcal(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!img.exists(), "{args:?} wrote an image");
    }
}
