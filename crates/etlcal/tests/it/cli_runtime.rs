//! The run-time side through the binary: no thermal surface assumed by
//! `calibrate`, the calibrated ranges enforced by every verb, `export` for OpenCV, ROS and
//! mrcal. Bad input: one-line error, exit 1, nothing written.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::common::{etlcal_run as etlcal, render_move_pair};

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

/// The service calibration without its thermal part, as `calibrate` writes one made from
/// views with E_com and no thermal calibration (`"temperature_compensation": "none"`).
fn uncompensated_calibration(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("fixtures/service/calibration.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    let o = v.as_object_mut().unwrap();
    o.remove("thermal").unwrap();
    o.insert("temperature_compensation".into(), "none".into());
    let p = dir.join("uncompensated.json");
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

/// Fails as a usage error (exit 2) in one line naming each of `needles`, nothing written.
fn usage_error_without_writing(args: &[&str], out: &Path, needles: &[&str]) {
    let (code, stdout, err) = etlcal(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(stdout.is_empty(), "{stdout}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: {needle:?} not in {err}");
    }
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
}

/// `calibrate` on views with E_com and no `--thermal`: said once on stderr, recorded in
/// the file; the file is then used with `--e-com` and refuses `--e-in/--t` naming it.
#[test]
fn calibrate_without_thermal_says_so_and_the_file_takes_e_com() {
    let dir = tempfile::tempdir().unwrap();
    let golden = root().join("fixtures/golden/observations.json");
    let bare = dir.path().join("bare.json");
    let args = ["calibrate", "--observations", golden.to_str().unwrap(), "--estimator", "paper", "--out"];
    let (code, _, err) = etlcal(&[&args[..], &[bare.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{err}");
    let said: Vec<&str> = err.lines().filter(|l| l.contains("no temperature compensation")).collect();
    assert_eq!(said.len(), 1, "said once: {err}");
    assert!(said[0].starts_with("etlcal: warning: ") && said[0].ends_with("use it with --e-com MA"), "{err}");
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&bare).unwrap()).unwrap();
    assert_eq!(file["temperature_compensation"], "none");
    assert!(file.get("thermal").is_none());
    // With a thermal calibration the field is absent and nothing is said.
    let with = dir.path().join("with.json");
    let (code, _, err) = etlcal(&[&args[..], &[with.to_str().unwrap(), "--thermal", "paper"]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("temperature compensation"), "{err}");
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&with).unwrap()).unwrap();
    assert!(file.get("temperature_compensation").is_none(), "{file}");

    // The run-time verbs: --e-com at the calibration's own E_com range; --e-in/--t refused
    // naming --e-com.
    let b = bare.to_str().unwrap();
    let kf_x: Vec<f64> = serde_json::from_value(file["kf_x"].clone()).unwrap();
    let (lo, hi) = (file["e_com_range_ma"][0].as_f64().unwrap(), file["e_com_range_ma"][1].as_f64().unwrap());
    let e = 0.5 * (lo + hi);
    let x = dir.path().join("x.yaml");
    let (xs, es) = (x.to_str().unwrap(), format!("{e}"));
    let j = json_ok(&["export", "--calibration", b, "--e-com", &es, "--format", "opencv", "--out", xs, "--json"]);
    assert_eq!(j["e_com_ma"].as_f64().unwrap(), e);
    assert_eq!((j["e_in_ma"].clone(), j["temperature_c"].clone()), (Value::Null, Value::Null), "{j}");
    let fx = kf_x.iter().rev().fold(0.0, |acc, k| acc * e + k);
    assert!((j["camera_matrix"][0][0].as_f64().unwrap() / fx - 1.0).abs() < 1e-12, "fx(E_com) of the file: {j}");
    assert!(std::fs::read_to_string(&x).unwrap().contains(&format!("E_com {e:?} mA")));
    std::fs::remove_file(&x).unwrap();
    fails_without_writing(
        &["export", "--calibration", b, "--e-in", "150", "--t", "30", "--format", "opencv", "--out", xs],
        &x,
        "has no temperature compensation (thermal): give the setting as --e-com MA, not --e-in/--t",
    );
    // The focus verb names the E_com in focus instead of an E_in it cannot give.
    let (code, _, err) = etlcal(&["focus", "--calibration", b, "--distance-mm", "80", "--t", "30"]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("no driver current can be given; the E_com in focus at 80 mm is "), "{err}");
    assert!(err.contains("(give it to export, measure, undistort as --e-com)"), "{err}");
}

/// `--e-com` and `--e-in/--t` are one setting in two forms: exactly one of them, refused
/// as a usage error (exit 2, one line, nothing written) otherwise, on every verb.
#[test]
fn the_two_setting_forms_exclude_each_other_on_every_verb() {
    let dir = tempfile::tempdir().unwrap();
    let cal = root().join("fixtures/service/calibration.json");
    let c = cal.to_str().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let img = dir.path().join("img.png");
    let i = img.to_str().unwrap();
    let verbs: [Vec<&str>; 3] = [
        vec!["export", "--calibration", c, "--format", "opencv", "--out", o],
        vec!["undistort", i, "--calibration", c, "--out", o],
        vec!["measure", "--calibration", c, i, i, "--pattern", "9x7", "--square", "1.5"],
    ];
    for verb in &verbs {
        let with = |extra: &[&'static str]| [&verb[..], extra].concat();
        usage_error_without_writing(
            &with(&["--e-in", "150", "--t", "30", "--e-com", "140"]),
            &out,
            &["--e-com", "cannot be used with", "--help"],
        );
        usage_error_without_writing(&with(&["--e-com", "140", "--e-in", "150"]), &out, &["--e-in", "--e-com"]);
        usage_error_without_writing(&with(&["--e-in", "150"]), &out, &["--t"]);
        usage_error_without_writing(&with(&["--t", "30"]), &out, &["--e-in"]);
        usage_error_without_writing(&with(&[]), &out, &["--e-in", "--e-com"]);
    }
}

/// Every run-time verb at `--e-com E` is the verb at `--e-in/--t` whose E_com is E, to the
/// bit, on a calibration with a thermal part and on the same calibration without one; out
/// of the calibrated E_com range it is refused unless extrapolation is asked for.
#[test]
fn every_runtime_verb_at_e_com_is_the_verb_at_the_setting_of_that_e_com() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let service = root().join("fixtures/service/calibration.json");
    let (with, bare) = (service.to_str().unwrap().to_owned(), uncompensated_calibration(dir.path()));
    let bare = bare.to_str().unwrap().to_owned();
    let thermal = json_ok(&["thermal", "eval", "--t", "30", "--e-in", "153", "--thermal", "paper", "--json"]);
    let e = format!("{}", thermal["e_com_ma"].as_f64().unwrap());
    let setting: [&str; 4] = ["--e-in", "153", "--t", "30"];
    let at_e_com: [&str; 2] = ["--e-com", &e];
    // export: the same camera and fit (and the same file but for the header's setting).
    let export = |cal: &str, s: &[&str], out: &str| {
        let args = [&["export", "--calibration", cal, "--format", "mrcal", "--out", out, "--json"][..], s].concat();
        json_ok(&args)
    };
    let a = export(&with, &setting, &p("a.cameramodel"));
    for cal in [&with, &bare] {
        let b = export(cal, &at_e_com, &p("b.cameramodel"));
        for key in ["e_com_ma", "camera_matrix", "dist_coeffs", "fit_rms_px", "fit_max_px", "extrapolated"] {
            assert_eq!(a[key], b[key], "{key}: {a} != {b}");
        }
        let body = |f: &str| std::fs::read_to_string(p(f)).unwrap().lines().skip(2).collect::<Vec<_>>().join("\n");
        assert_eq!(body("a.cameramodel"), body("b.cameramodel"));
    }
    // measure and undistort on rendered images of the rig at that E_com.
    render_move_pair(&p("a.png"), &p("b.png"), &e);
    let measure = |cal: &str, s: &[&str]| {
        let (a, b) = (p("a.png"), p("b.png"));
        json_ok(
            &[&["measure", "--calibration", cal, &a, &b, "--pattern", "9x7", "--square", "1.5", "--json"][..], s]
                .concat(),
        )
    };
    let m = measure(&with, &setting);
    assert!((m["distance_mm"].as_f64().unwrap() - 2.0).abs() < 0.02, "{m}");
    assert_eq!(m, measure(&with, &at_e_com));
    assert_eq!(m, measure(&bare, &at_e_com));
    let undistort = |cal: &str, s: &[&str], out: &str| {
        json_ok(&[&["undistort", &p("a.png"), "--calibration", cal, "--out", &p(out), "--json"][..], s].concat())
    };
    let u = undistort(&with, &setting, "u1");
    assert_eq!(u["e_com_ma"], undistort(&bare, &at_e_com, "u2")["e_com_ma"]);
    let png = |d: &str| std::fs::read(dir.path().join(d).join("a.png")).unwrap();
    assert_eq!(png("u1"), png("u2"), "the same undistorted image");
    // Out of the calibrated E_com range (80..225 mA, margin 5): refused, or extrapolated.
    let x = dir.path().join("x.yaml");
    let xs = x.to_str().unwrap();
    let args = ["export", "--calibration", bare.as_str(), "--e-com", "240", "--format", "ros", "--out", xs];
    fails_without_writing(&args, &x, "e_com_ma = 240 is outside [75, 230]");
    let j = json_ok(&[&args[..], &["--allow-extrapolation", "--json"]].concat());
    assert_eq!(j["extrapolated"], true);
    assert!(std::fs::read_to_string(&x).unwrap().contains("EXTRAPOLATED"));
    let u = dir.path().join("u3");
    let args = ["undistort", &p("a.png"), "--calibration", &bare, "--e-com", "60", "--out", u.to_str().unwrap()];
    fails_without_writing(&args, &u, "e_com_ma = 60 is outside [75, 230]");
    let args = ["measure", "--calibration", &bare, &p("a.png"), &p("b.png"), "--pattern", "9x7", "--square", "1.5"];
    let (code, _, err) = etlcal(&[&args[..], &["--e-com", "NaN"]].concat());
    assert_eq!((code, err.trim_end().lines().count()), (1, 1), "{err}");
    assert!(err.contains("e_com_ma is NaN"), "{err}");
}
