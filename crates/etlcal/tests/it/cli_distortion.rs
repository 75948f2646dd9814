//! Issue 16 through the binary: `etlcal simulate --config` with `"rig": "strong"`,
//! `etlcal calibrate --distortion paper|opencv|auto --focal-degree 1..5|auto --fix-k3
//! --zero-tangent`, and every bad input (one line on stderr naming the flag, the exit code,
//! nothing written or overwritten).

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::common::etlcal_run as etlcal;

/// `etlcal simulate --config CONFIG --out DIR/sim FLAGS...` with `config` written to
/// DIR/strong.json: (exit code, stderr, the output directory).
fn simulate(dir: &Path, config: &str, flags: &[&str]) -> (i32, String, PathBuf) {
    let path = dir.join("strong.json");
    std::fs::write(&path, config).unwrap();
    let sim = dir.join("sim");
    let mut args = vec!["simulate", "--config", path.to_str().unwrap(), "--out", sim.to_str().unwrap()];
    args.extend_from_slice(flags);
    let (code, _, err) = etlcal(&args);
    (code, err, sim)
}

/// The strong rig's observations (seed 4) in `dir`.
fn strong(dir: &Path) -> PathBuf {
    let config = r#"{"format": "etlcal.simconfig/1", "rig": "strong", "seed": 4}"#;
    let (code, err, sim) = simulate(dir, config, &["--observations-only"]);
    assert_eq!(code, 0, "{err}");
    sim.join("observations.json")
}

fn calibrate(obs: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["calibrate", "--observations", obs.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    etlcal(&args)
}

#[test]
fn the_strong_rig_calibrates_in_the_opencv_family_and_auto_chooses_it() {
    let dir = tempfile::tempdir().unwrap();
    let obs = strong(dir.path());
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(obs.with_file_name("truth.json")).unwrap()).unwrap();
    let out = dir.path().join("cal.json");
    let (code, stdout, err) = calibrate(&obs, &out, &["--distortion", "opencv", "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(j["distortion_model"], "opencv");
    assert_eq!((j["distortion_a"].as_array().unwrap().len(), j["kf_x"].as_array().unwrap().len()), (15, 4));
    assert!(j.get("model_selection").is_none());
    let pp = |v: &Value| [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()];
    let (got, want) = (pp(&j["principal_point"]), pp(&truth["model"]["principal_point"]));
    assert!((got[0] - want[0]).hypot(got[1] - want[1]) < 2.0, "{got:?} vs {want:?}");
    assert!(j["rms_reprojection_px"].as_f64().unwrap() < 0.4);
    // auto: the comparison table in the file, opencv chosen, said on stdout.
    let (code, stdout, err) = calibrate(&obs, &out, &["--distortion", "auto", "--thermal", "paper"]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("model: opencv distortion, focal degree 3"), "{stdout}");
    let j: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let sel = &j["model_selection"];
    assert_eq!(
        (sel["method"].as_str(), sel["rule"].as_str()),
        (Some("leave-one-view-out"), Some("one-standard-error"))
    );
    let chosen: Vec<&Value> = sel["candidates"].as_array().unwrap().iter().filter(|c| c["chosen"] == true).collect();
    assert_eq!(chosen.len(), 1);
    assert_eq!((chosen[0]["distortion_model"].as_str(), chosen[0]["focal_degree"].as_u64()), (Some("opencv"), Some(3)));
    // The file reads back (its model_selection validated) and reports.
    let (code, _, err) =
        etlcal(&["focus", "--calibration", out.to_str().unwrap(), "--distance-mm", "200", "--t", "27"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn bad_model_flags_are_refused_naming_the_flag_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let obs = strong(dir.path());
    let out = dir.path().join("cal.json");
    std::fs::write(&out, "earlier").unwrap();
    let cases: [(&[&str], i32, &str); 7] = [
        (&["--distortion", "brown"], 2, "brown"),
        (&["--focal-degree", "6"], 2, "--focal-degree"),
        (&["--focal-degree", "cubic"], 2, "cubic"),
        (&["--fix-k3"], 1, "--fix-k3 is an OpenCV flag: it needs --distortion opencv or auto"),
        (&["--distortion", "paper", "--zero-tangent"], 1, "--zero-tangent is an OpenCV flag"),
        (&["--method", "per-setting", "--distortion", "opencv"], 1, "--method per-setting takes no --distortion"),
        (&["--method", "per-setting", "--focal-degree", "2"], 1, "--method per-setting takes no --focal-degree"),
    ];
    for (flags, want_code, words) in cases {
        let (code, stdout, err) = calibrate(&obs, &out, flags);
        assert_eq!(code, want_code, "{flags:?}: {err}");
        assert!(err.contains(words), "{flags:?}: {err}");
        if want_code == 1 {
            assert_eq!(err.lines().count(), 1, "{flags:?}: {err}");
        }
        assert!(stdout.is_empty());
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "earlier", "{flags:?} touched the output");
    }
}

#[test]
fn the_strong_rig_is_corners_only_and_not_with_setting_views() {
    let dir = tempfile::tempdir().unwrap();
    let strong = r#"{"format": "etlcal.simconfig/1", "rig": "strong"}"#;
    let (code, err, sim) = simulate(dir.path(), strong, &[]);
    assert_eq!(code, 1);
    assert!(err.contains("pass --observations-only") && err.lines().count() == 1, "{err}");
    assert!(!sim.exists());
    let (code, err, _) = simulate(dir.path(), strong, &["--observations-only", "--setting-views"]);
    assert_eq!(code, 1);
    assert!(err.contains("setting_rig") && err.contains("strong"), "{err}");
    let (code, err, _) = simulate(dir.path(), r#"{"format": "etlcal.simconfig/1", "rig": "wide"}"#, &[]);
    assert_eq!(code, 1);
    assert!(err.contains("wide"), "{err}");
}

#[test]
fn study_crlb_on_the_strong_rig_and_rig_refused_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let (code, stdout, err) =
        etlcal(&["study", "crlb", "--rig", "strong", "--trials", "4", "--out", out.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((j["rig"].as_str(), j["trials"][0].as_u64()), (Some("strong"), Some(4)));
    for f in ["crlb-strong.json", "crlb-strong.md", "crlb-strong.svg", "crlb-strong.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let (code, _, err) = etlcal(&["study", "fig5", "--rig", "strong", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("--rig strong is for `study crlb` only") && err.lines().count() == 1, "{err}");
}
