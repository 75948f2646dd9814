//! The run-time side through the binary: no thermal surface assumed by
//! `calibrate`, the calibrated ranges enforced by every verb, `export` for OpenCV, ROS and
//! mrcal. Bad input: one-line error, exit 1, nothing written.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::common::etlcal_run as etlcal;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Fails with one line naming `needle`, and `out` is not written.
fn fails_without_writing(args: &[&str], out: &Path, needle: &str) {
    let (code, _, err) = etlcal(args);
    assert_eq!(code, 1, "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{args:?}: {err}");
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
}

fn json_ok(args: &[&str]) -> Value {
    let (code, out, err) = etlcal(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&out).unwrap()
}

/// The golden observations (every view with a recorded E_com) with the E_com removed.
fn observations_without_e_com(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("fixtures/golden/observations.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    for view in v["views"].as_array_mut().unwrap() {
        view.as_object_mut().unwrap().remove("e_com_ma");
    }
    let p = dir.join("no-e-com.json");
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

#[test]
fn calibrate_assumes_no_thermal_surface_and_keeps_the_chosen_one_whole() {
    let dir = tempfile::tempdir().unwrap();
    let obs = observations_without_e_com(dir.path());
    let out = dir.path().join("cal.json");
    let (o, c) = (obs.to_str().unwrap(), out.to_str().unwrap());
    fails_without_writing(
        &["calibrate", "--observations", o, "--estimator", "paper", "--out", c],
        &out,
        "view 0 has no e_com_ma and no thermal calibration was chosen",
    );
    fails_without_writing(
        &["calibrate", "--observations", o, "--thermal", "no-such.json", "--out", c],
        &out,
        "no-such.json",
    );
    let cal = json_ok(&[
        "calibrate",
        "--observations",
        o,
        "--estimator",
        "paper",
        "--thermal",
        "paper",
        "--out",
        c,
        "--json",
    ]);
    let t = &cal["thermal"];
    assert_eq!(t["source"], "paper");
    assert_eq!(t["t_range_c"], serde_json::json!([27.0, 37.0]));
    assert_eq!(t["e_in_range_ma"], serde_json::json!([40.0, 240.0]));
    // With every E_com recorded and no --thermal, the calibration has no thermal part, and
    // the run-time verbs say so instead of assuming one.
    let golden = root().join("fixtures/golden/observations.json");
    let bare = dir.path().join("bare.json");
    let cal = json_ok(&[
        "calibrate",
        "--observations",
        golden.to_str().unwrap(),
        "--estimator",
        "paper",
        "--out",
        bare.to_str().unwrap(),
        "--json",
    ]);
    assert!(cal.get("thermal").is_none(), "{}", cal["thermal"]);
    let x = dir.path().join("x.yaml");
    fails_without_writing(
        &[
            "export",
            "--calibration",
            bare.to_str().unwrap(),
            "--e-in",
            "150",
            "--t",
            "30",
            "--format",
            "opencv",
            "--out",
            x.to_str().unwrap(),
        ],
        &x,
        "no temperature compensation",
    );
}

#[test]
fn export_writes_each_format_and_refuses_bad_settings() {
    let dir = tempfile::tempdir().unwrap();
    let cal = root().join("fixtures/service/calibration.json");
    let c = cal.to_str().unwrap();
    for (format, first_key) in [("opencv", "%YAML:1.0"), ("ros", "image_width: 1936"), ("mrcal", "'lensmodel'")] {
        let out = dir.path().join(format!("cam.{format}"));
        let j = json_ok(&[
            "export",
            "--calibration",
            c,
            "--e-in",
            "150",
            "--t",
            "30",
            "--format",
            format,
            "--out",
            out.to_str().unwrap(),
            "--json",
        ]);
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains(first_key), "{format}: {text}");
        assert!(text.contains(&format!("rms {} px", j["fit_rms_px"])), "{format}: the fit error is stated");
        assert_eq!(j["extrapolated"], false);
        let k = j["camera_matrix"].as_array().unwrap();
        assert_eq!(k.len(), 3);
        assert!(j["fit_max_px"].as_f64().unwrap() < 0.1, "{j}");
    }
    let out = dir.path().join("bad.yaml");
    let o = out.to_str().unwrap();
    let args = |e: &'static str, t: &'static str, f: &'static str| {
        vec!["export", "--calibration", c, "--e-in", e, "--t", t, "--format", f, "--out", o]
    };
    fails_without_writing(&args("150", "30", "json"), &out, "\"json\" is not one of opencv, ros, mrcal");
    fails_without_writing(&args("150", "80", "opencv"), &out, "temperature_c = 80 is outside [26, 38]");
    fails_without_writing(&args("260", "30", "opencv"), &out, "e_in_ma = 260 is outside [35, 245]");
    fails_without_writing(&args("60", "30", "opencv"), &out, "e_com_ma = 57.99");
    fails_without_writing(&args("NaN", "30", "opencv"), &out, "e_in_ma is NaN");
    let missing = dir.path().join("missing.json");
    fails_without_writing(
        &[
            "export",
            "--calibration",
            missing.to_str().unwrap(),
            "--e-in",
            "150",
            "--t",
            "30",
            "--format",
            "ros",
            "--out",
            o,
        ],
        &out,
        "missing.json",
    );
    // Asked for, an extrapolated export is written and says so.
    let j = json_ok(&[&args("150", "39", "opencv")[..], &["--allow-extrapolation", "--json"]].concat());
    assert_eq!(j["extrapolated"], true);
    assert!(std::fs::read_to_string(&out).unwrap().contains("EXTRAPOLATED"));
}
