//! Conventions every verb shares, run as the built binary: output directories
//! are created, global flags go before or after the verb, and every failure (clap's
//! included) is one line on stderr with the documented exit status.

use etl_core::thermal::ThermalSurface;
use serde_json::Value;

use super::common::etlcal;

/// The one stderr line of a failed run with exit status `code`.
fn one_line_failure(args: &[&str], code: i32) -> String {
    let out = etlcal(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    assert!(err.starts_with("etlcal: error: "), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    err
}

fn json_of(args: &[&str]) -> Value {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn simulate_creates_a_missing_output_directory_as_demo_report_and_study_do() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a/b/sim");
    let v = json_of(&["simulate", "--out", out.to_str().unwrap(), "--observations-only", "--json"]);
    assert_eq!(v["views"], 15);
    assert_eq!(v["images"], 0);
    for f in ["observations.json", "a0.json", "truth.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // An output "directory" that is a file: refused in one line, nothing written beside it.
    let file = dir.path().join("plain");
    std::fs::write(&file, b"x").unwrap();
    one_line_failure(&["simulate", "--out", file.to_str().unwrap(), "--observations-only"], 1);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2, "only a/ and plain");
    // The help of every --out says so.
    for verb in ["simulate", "demo", "report", "study", "calibrate", "render"] {
        let help = String::from_utf8(etlcal(&[verb, "--help"]).stdout).unwrap();
        assert!(help.contains("created"), "{verb} --help: {help}");
    }
}

#[test]
fn thermal_fit_creates_the_parent_directory_of_its_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("t.csv");
    // Samples of the paper's surface: the fit returns it (rms 0).
    let mut text = String::from("temperature_c,e_in_ma,e_t_ma\n");
    for t in [27.0, 29.0, 31.0, 33.0, 35.0, 37.0] {
        for e in [40.0, 80.0, 120.0, 160.0, 200.0, 240.0] {
            text.push_str(&format!("{t},{e},{}\n", ThermalSurface::PAPER.e_t_ma(e, t).unwrap()));
        }
    }
    std::fs::write(&table, text).unwrap();
    let out = dir.path().join("new/dir/thermal.json");
    let v = json_of(&["thermal", "fit", table.to_str().unwrap(), "--out", out.to_str().unwrap(), "--json"]);
    assert!(v["rms_ma"].as_f64().unwrap() < 1e-9, "{v}");
    assert_eq!(v["samples"], 36);
    assert!(out.is_file());
}

#[test]
fn json_is_accepted_before_or_after_the_verb() {
    let after = json_of(&["thermal", "eval", "--t", "35", "--e-in", "150", "--thermal", "paper", "--json"]);
    let before = json_of(&["--json", "thermal", "eval", "--t", "35", "--e-in", "150", "--thermal", "paper"]);
    let between = json_of(&["thermal", "--json", "eval", "--t", "35", "--e-in", "150", "--thermal", "paper"]);
    assert_eq!(after, before);
    assert_eq!(after, between);
    assert!(after["e_com_ma"].as_f64().unwrap() < 150.0, "{after}");
}

#[test]
fn lens_target_flags_go_before_or_after_the_subcommand() {
    for args in [
        &["lens", "info", "--virtual", "--json"][..],
        &["lens", "--virtual", "info", "--json"],
        &["--json", "lens", "--virtual", "info"],
    ] {
        let v = json_of(args);
        assert!(v["max_current_ma"].as_f64().unwrap() > 0.0, "{args:?}: {v}");
    }
    let v = json_of(&["lens", "get-current", "--json", "--virtual"]);
    assert_eq!(v["current_ma"], 0.0, "a fresh virtual lens is at 0 mA");
    let e = one_line_failure(&["lens", "info"], 1);
    assert!(e.contains("--port PATH") && e.contains("--virtual"), "{e}");
    let e = one_line_failure(&["lens", "info", "--virtual", "--port", "/dev/null"], 1);
    assert!(e.contains("not both"), "{e}");
}

#[test]
fn clap_errors_are_one_line_with_exit_status_2() {
    let e = one_line_failure(&["detect", "x.png"], 2);
    assert!(e.contains("--pattern") && e.ends_with("; see etlcal detect --help\n"), "{e}");
    let e = one_line_failure(&["frobnicate"], 2);
    assert!(e.contains("frobnicate") && e.contains("see etlcal --help"), "{e}");
    let e = one_line_failure(&["lens", "info", "--virtual", "--bogus"], 2);
    assert!(e.contains("--bogus") && e.contains("see etlcal lens info --help"), "{e}");
    let e = one_line_failure(&["model", "--step", "abc"], 2);
    assert!(e.contains("abc") && e.contains("see etlcal model --help"), "{e}");
    let e = one_line_failure(&[], 2);
    assert!(e.contains("see etlcal --help"), "{e}");
}

#[test]
fn help_and_version_print_on_stdout_with_exit_status_0() {
    for args in [&["--help"][..], &["detect", "--help"], &["lens", "info", "--help"], &["help", "render"]] {
        let out = etlcal(args);
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: etlcal"), "{args:?}");
        assert!(out.stderr.is_empty(), "{args:?}");
    }
    let out = etlcal(&["--version"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(String::from_utf8(out.stdout).unwrap(), format!("etlcal {}\n", env!("CARGO_PKG_VERSION")));
}
