//! `etlcal zhang --model opencv` on the wide-lens set fixtures/wide/stereo752_left
//! (SOURCE.md there): OpenCV's keys in the JSON beside today's, and OpenCV's flags refused
//! with the paper's model (one line naming the flag, exit 1).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn images() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/wide/stereo752_left");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    v.sort();
    v.truncate(8);
    v
}

fn zhang(extra: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_etlcal"));
    cmd.arg("zhang").args(images()).args(["--pattern", "11x8", "--square", "1"]).args(extra);
    cmd.output().unwrap()
}

#[test]
fn opencv_model_adds_camera_matrix_dist_coeffs_per_view_rms_and_stds() {
    let out = zhang(&["--model", "opencv", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in
        ["fx", "fy", "u0", "v0", "rms_px", "views_used", "camera_matrix", "dist_coeffs", "per_view_rms_px", "std"]
    {
        assert!(v.get(key).is_some(), "{key} missing: {v}");
    }
    assert_eq!(v["model"], "opencv");
    assert_eq!(v["views_used"], 8);
    let k = &v["camera_matrix"];
    assert_eq!((k[0][0].as_f64(), k[0][2].as_f64()), (v["fx"].as_f64(), v["u0"].as_f64()));
    assert_eq!((k[1][1].as_f64(), k[2][2].as_f64(), k[0][1].as_f64()), (v["fy"].as_f64(), Some(1.0), Some(0.0)));
    let d: Vec<f64> = v["dist_coeffs"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(d.len(), 5);
    assert!(d[0] < -0.3 && d[1] > 0.1, "a wide lens: {d:?}");
    assert_eq!(v["per_view_rms_px"].as_array().unwrap().len(), 8);
    assert_eq!(v["images_used"].as_array().unwrap().len(), 8);
    for name in ["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"] {
        assert!(v["std"][name].as_f64().unwrap() > 0.0, "std of {name}");
    }
    // --fix-k3 holds k3 at zero, with no standard deviation.
    let out = zhang(&["--model", "opencv", "--fix-k3", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((v["dist_coeffs"][4].as_f64(), v["std"]["k3"].as_f64()), (Some(0.0), Some(0.0)));
    assert_eq!(v["fix_k3"], true);
}

#[test]
fn opencv_flags_with_the_paper_model_are_refused_naming_the_flag() {
    for flag in ["--fix-k3", "--zero-tangent"] {
        for model in [&["--model", "paper"][..], &[][..]] {
            let out = zhang(&[model, &[flag, "--json"]].concat());
            assert_eq!(out.status.code(), Some(1), "{flag} {model:?}");
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(
                err.starts_with("etlcal: error: ") && err.contains(flag) && err.contains("--model opencv"),
                "{err}"
            );
            assert!(out.stdout.is_empty());
        }
    }
    let out = zhang(&["--model", "brown"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("brown"));
}

/// `--json`'s `"projection_std_px"`: the documented 5 x 5 grid spanning the image (centre
/// and corners included), at infinity and at the views' distance, the image's edges less
/// certain than the centre, and the text output's summary line. This wide lens's 5-term
/// model folds over beyond the corners it saw (k1 < -0.3): the pixels at the left and right
/// edges do not unproject and are null, as documented.
#[test]
fn the_json_holds_the_projection_uncertainty_on_a_grid() {
    let out = zhang(&["--model", "opencv", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let p = &v["projection_std_px"];
    assert_eq!(p["grid"], serde_json::json!([5, 5]));
    let pixels = p["pixels"].as_array().unwrap();
    assert_eq!(pixels.len(), 25);
    assert_eq!(pixels[0], serde_json::json!([0.0, 0.0]));
    let size = [752.0, 480.0];
    assert_eq!(pixels[12], serde_json::json!([(size[0] - 1.0) / 2.0, (size[1] - 1.0) / 2.0]), "the centre");
    assert_eq!(pixels[24], serde_json::json!([size[0] - 1.0, size[1] - 1.0]));
    let norm = |s: &serde_json::Value| s[0].as_f64().unwrap().hypot(s[1].as_f64().unwrap());
    for key in ["at_infinity", "at_views_distance"] {
        let s = p[key].as_array().unwrap();
        assert_eq!(s.len(), 25);
        let centre = norm(&s[12]);
        assert!(centre > 0.0 && centre < 0.5, "{key}: {centre} px at the centre");
        let (nulls, worst) =
            s.iter().fold((0, 0.0f64), |(n, w), x| if x.is_null() { (n + 1, w) } else { (n, w.max(norm(x))) });
        assert_eq!(nulls, 10, "{key}: the left and right edges: {s:?}");
        assert!(s.iter().enumerate().all(|(k, x)| x.is_null() == (k % 5 == 0 || k % 5 == 4)), "{key}: {s:?}");
        assert!(worst > 2.5 * centre, "{key}: worst {worst} px, centre {centre} px");
    }
    assert!(p["views_distance_mm"].as_f64().unwrap() > 1.0);
    let text = zhang(&["--model", "opencv"]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("projection uncertainty at infinity (mrcal's sense): "), "{text}");
}

/// `--report DIR`: index.html with the numbers and the two uncertainty maps (PNG, 32 x 24
/// cells of 20 px), the paths in `--json`'s `"report"`; a DIR that is a file is refused
/// before any image is read, and the file is left as it was.
#[test]
fn the_report_holds_the_numbers_and_two_uncertainty_maps() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("zhang-report");
    let out = zhang(&["--model", "opencv", "--json", "--report", report.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["report"].as_array().unwrap().len(), 3, "{v}");
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    for text in ["Projection uncertainty", "At infinity", "views' distance", "k3", "uncertainty_infinity.png"] {
        assert!(html.contains(text), "index.html lacks {text}");
    }
    for png in ["uncertainty_infinity.png", "uncertainty_views_distance.png"] {
        let img = image::open(report.join(png)).unwrap();
        assert_eq!((img.width(), img.height()), (32 * 20, 24 * 20), "{png}");
    }
    let file = dir.path().join("a-file");
    std::fs::write(&file, "keep me").unwrap();
    let out = zhang(&["--report", file.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
}
