//! `etlcal thermal calibrate --virtual --quick`: the section 4.1 procedure on the virtual
//! rig recovers the virtual lens's true surface (the paper's), and writes the thermal file
//! and its table.

use std::process::Command;

#[test]
fn the_virtual_procedure_recovers_the_true_surface_and_writes_both_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("new/thermal.json");
    let out_s = out.to_str().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(["thermal", "calibrate", "--virtual", "--quick", "--out", out_s, "--json"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let v: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["samples"], 25, "{v}");
    // Against the truth, referenced to the first temperature as the procedure is.
    let err = v["surface_error_ma"].as_f64().unwrap();
    assert!(err < 0.3, "surface error {err} mA");
    assert_eq!(v["format"], "etlcal.thermal/1");
    let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written["coefficients"], v["coefficients"]);
    let table = std::fs::read_to_string(out.with_extension("csv")).unwrap();
    assert_eq!(table.lines().next(), Some("temperature_c,e_in_ma,e_t_ma"));
    assert_eq!(table.lines().count(), 26);
}

/// A search window too narrow for the lens's drift: the refocus ends at its edge, and the
/// one-line error names the flag to widen (not the library's field), nothing written.
#[test]
fn a_refocus_at_the_edge_of_its_window_names_the_flag_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("thermal.json");
    let args = ["thermal", "calibrate", "--virtual", "--quick", "--search-ma", "0.5", "--out", out.to_str().unwrap()];
    let (code, stdout, err) = super::common::etlcal_run(&args);
    assert_eq!((code, stdout.as_str()), (1, ""), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("ended at the edge of its window") && err.contains("widen the search (--search-ma)"), "{err}");
    assert!(!err.contains("search_half_width_ma"), "{err}");
    assert!(!out.exists() && !out.with_extension("csv").exists());
}

/// `--dynamics` and `--settle-ms`: a bad dynamics file or wait is refused in one line
/// naming it before the lens is touched, and nothing is written.
#[test]
fn bad_dynamics_or_settling_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("thermal.json");
    let bad = dir.path().join("dynamics.json");
    let fixture =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/lens-dynamics/el-10-30-published.json");
    let text = std::fs::read_to_string(fixture).unwrap().replace("\"creep_fraction\": 0.01", "\"creep_fraction\": 2");
    std::fs::write(&bad, text).unwrap();
    let base = ["thermal", "calibrate", "--virtual", "--quick", "--out", out.to_str().unwrap()];
    for (extra, want) in [
        (vec!["--dynamics", bad.to_str().unwrap()], "creep_fraction = 2 is outside [0, 0.5]"),
        (vec!["--settle-ms", "-1"], "--settle-ms -1 must lie in 0..=10000 ms"),
        (vec!["--settle-ms", "NaN"], "--settle-ms NaN must lie in 0..=10000 ms"),
    ] {
        let args: Vec<&str> = base.iter().copied().chain(extra.iter().copied()).collect();
        let (code, stdout, err) = super::common::etlcal_run(&args);
        assert_eq!((code, stdout.as_str()), (1, ""), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(want), "{err}");
        assert!(!out.exists() && !out.with_extension("csv").exists());
    }
}
