//! `etlcal study`: fig5's JSON and files, and its bad input.

use serde_json::Value;

use super::common::etlcal;

#[test]
fn cli_fig5_json_and_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().to_str().unwrap();
    let out = etlcal(&["study", "fig5", "--json", "--out", out_dir]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["fit_rmse_mm"].as_array().unwrap().len(), 6);
    for f in ["fig5.json", "fig5.md", "fig5.png", "fig5.svg"] {
        let m = std::fs::metadata(dir.path().join(f)).unwrap();
        assert!(m.len() > 100 && m.len() < 200_000, "{f}: {} bytes", m.len());
    }
    let bad = etlcal(&["study", "fig6", "--trials", "0", "--out", out_dir]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--trials 0 must lie in 1..=100000"), "{err}");
    assert!(!dir.path().join("fig6.json").exists());
    let unknown = etlcal(&["study", "fig7"]);
    assert!(!unknown.status.success());
}

#[test]
fn cli_study_refuses_trials_beyond_the_documented_limit_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    for n in ["18446744073709551615", "100000000", "100001"] {
        let bad = etlcal(&["study", "baseline", "--trials", n, "--out", out_dir.to_str().unwrap()]);
        assert_eq!(bad.status.code(), Some(1));
        let err = String::from_utf8_lossy(&bad.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(&format!("--trials {n} must lie in 1..=100000")), "{err}");
        assert!(!out_dir.exists(), "nothing is written");
    }
}
