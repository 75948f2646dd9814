//! A focal-power calibration end to end as the built binary: `simulate --focal-power`
//! (the paper rig in the driver's focal-power mode at 25, 30 and 35 degC), `calibrate`
//! (no thermal part), `focus` giving the focal power, `export` and `measure` at `--dpt`;
//! and the refusals, each one line, exit status 1, nothing written: a thermal calibration
//! or a current prior with focal-power views, a current given to a focal-power calibration
//! and a focal power to a current one, a power outside the calibrated range.
use std::path::Path;

use serde_json::Value;

use super::common::etlcal;

fn json_of(args: &[&str]) -> Value {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn refused(args: &[&str], needle: &str, unwritten: &Path) {
    let out = etlcal(args);
    assert_eq!(out.status.code(), Some(1), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{needle}: {err}");
    assert!(!unwritten.exists(), "{} was written", unwritten.display());
}

#[test]
fn a_focal_power_calibration_from_simulation_to_focus_and_export() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    json_of(&["simulate", "--focal-power", "--observations-only", "--out", &p("sim"), "--seed", "2", "--json"]);
    let obs: Value = serde_json::from_str(&std::fs::read_to_string(p("sim/observations.json")).unwrap()).unwrap();
    assert!(obs["views"][0]["focal_power_dpt"].is_f64() && obs["views"][0].get("e_in_ma").is_none());
    let obs_path = p("sim/observations.json");
    let cal = json_of(&["calibrate", "--observations", &obs_path, "--out", &p("cal.json"), "--json"]);
    assert_eq!(cal["setting"], "focal_power", "{cal}");
    assert!(cal["rms_reprojection_px"].as_f64().unwrap() < 0.35, "{cal}");
    // The focus law in dioptres: the rig focuses 80 mm at 127.1 mA, where the liquid lens
    // has 1000 / f_liq(127.1 mA) dpt.
    let f = json_of(&["focus", "--calibration", &p("cal.json"), "--distance-mm", "80", "--t", "30", "--json"]);
    let want = etl_sim::simulate::focal_power::power_dpt(127.1);
    assert!((f["focal_power_dpt"].as_f64().unwrap() - want).abs() < 0.05, "{f} against {want}");
    let dpt = format!("{want}");
    let e = json_of(&[
        "export",
        "--calibration",
        &p("cal.json"),
        "--dpt",
        &dpt,
        "--t",
        "30",
        "--format",
        "opencv",
        "--out",
        &p("cv.yaml"),
        "--json",
    ]);
    assert_eq!((e["setting"].as_str(), e["focal_power_dpt"].as_f64()), (Some("focal_power"), Some(want)));
    let yaml = std::fs::read_to_string(p("cv.yaml")).unwrap();
    assert!(yaml.contains("focal power") && yaml.contains("setting: focal_power"), "{yaml:.200}");
    // The report says its setting: the range, the axes and the views in dpt, no NaN.
    json_of(&["report", "--calibration", &p("cal.json"), "--observations", &obs_path, "--out", &p("report"), "--json"]);
    let html = std::fs::read_to_string(p("report/index.html")).unwrap();
    assert!(html.contains("focal power 12.4 .. 18.8 dpt") && html.contains("focal power (dpt)"), "{html:.600}");
    assert!(!html.contains("NaN"), "a NaN in the report");
    // Refusals, nothing written.
    let out = p("refused.json");
    refused(
        &["calibrate", "--observations", &obs_path, "--thermal", "paper", "--out", &out],
        "--thermal does not apply",
        Path::new(&out),
    );
    refused(
        &["calibrate", "--observations", &obs_path, "--sigma-e-ma", "0.4", "--out", &out],
        "--sigma-e-ma does not apply",
        Path::new(&out),
    );
    let export = |setting: &[&str], cal: &str| {
        let mut a = vec!["export", "--calibration", cal, "--format", "opencv", "--out", &out];
        a.extend_from_slice(setting);
        a.into_iter().map(str::to_owned).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>, needle: &str| {
        refused(&a.iter().map(String::as_str).collect::<Vec<_>>(), needle, Path::new(&out))
    };
    run(export(&["--e-in", "150", "--t", "30"], &p("cal.json")), "its setting is the focal power");
    run(export(&["--dpt", "25", "--t", "30"], &p("cal.json")), "focal_power_dpt");
    json_of(&["simulate", "--observations-only", "--out", &p("cur"), "--json"]);
    json_of(&[
        "calibrate",
        "--observations",
        &p("cur/observations.json"),
        "--thermal",
        "paper",
        "--out",
        &p("cur.json"),
        "--json",
    ]);
    run(export(&["--dpt", "15", "--t", "30"], &p("cur.json")), "its setting is the lens current");
    // --model auto chooses among all 20 candidates on focal-power views too, and says so
    // in dpt; it is refused beside a choice it makes itself.
    let auto =
        json_of(&["calibrate", "--observations", &obs_path, "--model", "auto", "--out", &p("auto.json"), "--json"]);
    assert_eq!(auto["setting"], "focal_power");
    let candidates = auto["model_selection"]["candidates"].as_array().unwrap();
    assert_eq!(candidates.len(), 20, "{}", auto["model_selection"]);
    assert_eq!(candidates.iter().filter(|c| c["chosen"] == true).count(), 1);
    let text = auto.to_string();
    assert!(!text.contains(" mA is "), "a focal-power range said in mA: {text:.300}");
    let alone = ["calibrate", "--observations", &obs_path, "--model", "auto", "--centre", "fixed", "--out", &out];
    refused(
        &alone,
        "--model auto chooses the distortion family, the focal degree and the centre itself: drop --centre",
        Path::new(&out),
    );
    // The prior on the focal power: recorded as given; refused with currents, or not positive.
    let own =
        json_of(&["calibrate", "--observations", &obs_path, "--sigma-p-dpt", "0.1", "--out", &p("own.json"), "--json"]);
    assert_eq!(own["covariance_noise"]["sigma_p_dpt"], 0.1, "{}", own["covariance_noise"]);
    let cur_obs = p("cur/observations.json");
    let with_current =
        ["calibrate", "--observations", &cur_obs, "--thermal", "paper", "--sigma-p-dpt", "0.1", "--out", &out];
    refused(&with_current, "--sigma-p-dpt is the prior on a focal-power view's setting", Path::new(&out));
    refused(
        &["calibrate", "--observations", &obs_path, "--sigma-p-dpt", "0", "--out", &out],
        "--sigma-p-dpt must be positive",
        Path::new(&out),
    );
}

/// Views of both kinds in one file are refused naming the view, and a focal-power view
/// with a current as well.
#[test]
fn mixed_settings_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    json_of(&["simulate", "--focal-power", "--observations-only", "--out", &p("sim"), "--json"]);
    let text = std::fs::read_to_string(p("sim/observations.json")).unwrap();
    let mut obs: Value = serde_json::from_str(&text).unwrap();
    obs["views"][3] = serde_json::json!({"e_in_ma": 150.0, "temperature_c": 30.0, "points": obs["views"][3]["points"]});
    std::fs::write(p("mixed.json"), obs.to_string()).unwrap();
    let out = p("cal.json");
    refused(
        &["calibrate", "--observations", &p("mixed.json"), "--out", &out],
        "views[3] is set by a current",
        Path::new(&out),
    );
    let mut both: Value = serde_json::from_str(&text).unwrap();
    both["views"][1]["e_in_ma"] = serde_json::json!(150.0);
    std::fs::write(p("both.json"), both.to_string()).unwrap();
    refused(
        &["calibrate", "--observations", &p("both.json"), "--out", &out],
        "view 1 gives both e_in_ma and focal_power_dpt",
        Path::new(&out),
    );
}
