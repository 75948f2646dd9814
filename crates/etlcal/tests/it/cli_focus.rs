//! `etlcal focus` as the built binary: the current that focuses the calibrated paper rig at
//! a distance (consistent with `thermal eval`), and the refusals: a distance outside the
//! law's range, a temperature outside the thermal surface's domain, a calibration without a
//! focus law. Each is one line on stderr and exit status 1.
use std::path::Path;

use serde_json::Value;

use super::common::etlcal;

fn json_of(args: &[&str]) -> Value {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Calibrates the simulated paper rig (seed 3) into `dir/cal.json`.
fn calibration(dir: &Path) -> String {
    let p = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    json_of(&["simulate", "--out", &p("sim"), "--observations-only", "--seed", "3", "--json"]);
    let cal = json_of(&[
        "calibrate",
        "--observations",
        &p("sim/observations.json"),
        "--thermal",
        "paper",
        "--out",
        &p("cal.json"),
        "--json",
    ]);
    let law = &cal["focus_law"];
    assert_eq!(law["views"], 15, "{law}");
    p("cal.json")
}

fn refused(args: &[&str], needle: &str) {
    let out = etlcal(args);
    assert_eq!(out.status.code(), Some(1), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{needle}: {err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn focuses_at_a_distance_and_refuses_what_is_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let cal = calibration(dir.path());
    let f = json_of(&["focus", "--calibration", &cal, "--distance-mm", "80", "--t", "30", "--json"]);
    let keys: Vec<&str> = f.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(keys, ["distance_mm", "e_com_ma", "e_in_ma", "extrapolated"]);
    assert_eq!(f["extrapolated"], false);
    assert_eq!(f["distance_mm"], 80.0);
    let (e_in, e_com) = (f["e_in_ma"].as_f64().unwrap(), f["e_com_ma"].as_f64().unwrap());
    // The rig's lens focuses 80 mm at 127.1 mA; the calibration's law is close to it.
    assert!((e_com - 127.1).abs() < 0.5, "{f}");
    let eval = json_of(&["thermal", "eval", "--t", "30", "--e-in", &format!("{e_in}"), "--thermal", "paper", "--json"]);
    assert!((eval["e_com_ma"].as_f64().unwrap() - e_com).abs() < 1e-6, "{eval} {f}");
    // Plain output: one line.
    let out = etlcal(&["focus", "--calibration", &cal, "--distance-mm", "80", "--t", "30"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(text.contains("E_in") && text.contains("80 mm"), "{text}");

    refused(&["focus", "--calibration", &cal, "--distance-mm", "500", "--t", "30"], "distance_mm");
    refused(&["focus", "--calibration", &cal, "--distance-mm", "20", "--t", "30"], "distance_mm");
    refused(&["focus", "--calibration", &cal, "--distance-mm", "80", "--t", "300"], "temperature_c");
    refused(
        &["focus", "--calibration", &cal, "--distance-mm", "80", "--t", "80"],
        "temperature_c = 80 is outside [26, 38]",
    );
    let x = json_of(&[
        "focus",
        "--calibration",
        &cal,
        "--distance-mm",
        "80",
        "--t",
        "39",
        "--allow-extrapolation",
        "--json",
    ]);
    assert_eq!(x["extrapolated"], true, "{x}");
    // Without a focus law.
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("focus_law");
    let bare = dir.path().join("bare.json");
    std::fs::write(&bare, v.to_string()).unwrap();
    refused(
        &["focus", "--calibration", bare.to_str().unwrap(), "--distance-mm", "80", "--t", "30"],
        "this calibration has no focus law",
    );
}
