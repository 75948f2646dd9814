//! `etlcal lens --virtual ...` through the real binary: the `--json` keys of issue 6, the
//! clamping policy (beyond the limits: clamped with a warning, exit 0), NaN refused.
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
fn info_temperature_and_set_current_on_the_virtual_lens() {
    let (code, out, err) = etlcal(&["lens", "--virtual", "--json", "info"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    for key in [
        "firmware_type",
        "firmware_version",
        "lens_serial",
        "max_current_ma",
        "upper_limit_ma",
        "lower_limit_ma",
        "temperature_c",
    ] {
        assert!(j.get(key).is_some(), "info lacks {key}: {j}");
    }
    let (code, out, _) = etlcal(&["lens", "--virtual", "--json", "temperature"]);
    assert_eq!(code, 0);
    let t: Value = serde_json::from_str(&out).unwrap();
    assert!(t["temperature_c"].as_f64().unwrap().is_finite());
    let (code, out, err) = etlcal(&["lens", "--virtual", "--json", "set-current", "400"]);
    assert_eq!(code, 0, "{err}");
    let s: Value = serde_json::from_str(&out).unwrap();
    assert!(s["commanded_ma"].as_f64().unwrap() <= j["upper_limit_ma"].as_f64().unwrap());
    assert!(err.contains("clamped"), "{err}");
    let (code, _, err) = etlcal(&["lens", "--virtual", "set-current", "NaN"]);
    assert_ne!(code, 0);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

#[test]
fn hold_keeps_e_com_while_the_virtual_lens_warms() {
    let (code, out, err) = etlcal(&[
        "lens",
        "--virtual",
        "--json",
        "hold",
        "--e-com",
        "150",
        "--thermal",
        "paper",
        "--duration",
        "2",
        "--warm",
        "10",
        "--time-scale",
        "100",
    ]);
    assert_eq!(code, 0, "{err}");
    let h: Value = serde_json::from_str(&out).unwrap();
    assert!(h["worst_e_com_error_ma"].as_f64().unwrap() < 0.5, "{h}");
    let range = h["temperature_range_c"].as_array().unwrap();
    assert!(range[1].as_f64().unwrap() - range[0].as_f64().unwrap() > 5.0, "{h}");
}
