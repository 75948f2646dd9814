//! The `etlcal model` and `etlcal thermal` verbs, run as the built binary: JSON numbers
//! against the core and the paper, and bad input (one-line error, non-zero exit, no output
//! file written).

use std::path::Path;

use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde_json::Value;

use super::common::etlcal;

/// Runs a command expected to succeed with `--json`; returns the parsed object.
fn json_ok(args: &[&str]) -> Value {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.trim_end().lines().count(), 1, "one JSON object on one line: {text}");
    serde_json::from_str(&text).unwrap()
}

/// Runs a command expected to fail; returns its one-line stderr.
fn fails(args: &[&str]) -> String {
    let out = etlcal(args);
    assert!(!out.status.success(), "{args:?} should fail");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one-line error: {err}");
    assert!(err.starts_with("etlcal: error: "), "{err}");
    err
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn model_table_matches_the_core_and_the_paper() {
    let v = json_ok(&["model", "--from", "0", "--to", "250", "--step", "50", "--json"]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    let cam = CameraModel::paper_rig();
    let lens = LensPhysics::paper();
    for r in rows {
        let e = num(&r["e_ma"]);
        let k = cam.intrinsics(e).unwrap();
        let d = cam.distortion(e).unwrap();
        // serde_json's default float parsing may be off by one ulp: compare to 1e-14.
        let pairs = [
            (&r["fx_px"], k.fx),
            (&r["fy_px"], k.fy),
            (&r["k1"], d.padded()[0]),
            (&r["p1"], d.padded()[1]),
            (&r["p2"], d.padded()[2]),
            (&r["f_liq_mm"], lens.f_liq_mm(e).unwrap()),
            (&r["f_com_mm"], lens.f_com_mm(e).unwrap()),
        ];
        for (got, want) in pairs {
            assert!((num(got) - want).abs() <= 1e-14 * want.abs(), "E = {e}: {got} vs {want}");
        }
    }
    // The paper rig at 100 mA: fx = 5380 - 700 + 200 - 30; f_liq spans 120.5 .. 50.5 mm.
    assert_eq!(num(&rows[2]["fx_px"]), 4850.0);
    assert!((num(&rows[0]["f_liq_mm"]) - 120.5).abs() < 0.1);
    assert!((num(&rows[5]["f_liq_mm"]) - 50.5).abs() < 0.1);
    // Text mode prints the table.
    let out = etlcal(&["model", "--step", "125"]);
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 2 + 3);
}

/// Fig. 5: the cubic's RMSE is the paper's 1.09e-3 mm (within 10 % of 1.10e-3), and the
/// RMSE falls with the degree.
#[test]
fn model_fit_degrees_reproduces_fig5() {
    let v = json_ok(&["model", "--fit-degrees", "--from", "0", "--to", "260", "--json"]);
    let r: Vec<f64> = v["fit_rmse_mm"].as_array().unwrap().iter().map(num).collect();
    assert_eq!(r.len(), 6);
    assert!((r[2] - 1.10e-3).abs() < 0.1 * 1.10e-3, "cubic RMSE {}", r[2]);
    assert!(r.windows(2).all(|w| w[1] < w[0]), "{r:?}");
    assert_eq!(v["samples"], 2601);
}

#[test]
fn model_bad_input_is_a_one_line_error() {
    assert!(fails(&["model", "--from", "NaN"]).contains("--from"));
    assert!(fails(&["model", "--step", "0"]).contains("--step"));
    assert!(fails(&["model", "--from", "10", "--to", "0"]).contains("--from"));
    // Below about -151 mA the membrane pressure p_0 + p_a is negative: outside the model.
    assert!(fails(&["model", "--from", "-200", "--to", "0", "--json"]).contains("membrane pressure"));
}

#[test]
fn thermal_eval_uses_the_paper_surface_when_chosen() {
    let v = json_ok(&["thermal", "eval", "--t", "33.5", "--e-in", "150", "--thermal", "paper", "--json"]);
    let e_t = ThermalSurface::PAPER.e_t_ma(150.0, 33.5).unwrap();
    assert!((num(&v["e_t_ma"]) - e_t).abs() < 1e-12);
    assert!((num(&v["e_com_ma"]) - (150.0 - e_t)).abs() < 1e-12);
    assert_eq!(v["extrapolated"], false);
    // Near 0 at 27 degC.
    let v = json_ok(&["thermal", "eval", "--t", "27", "--e-in", "100", "--thermal", "paper", "--json"]);
    assert!(num(&v["e_t_ma"]).abs() < 0.5);
    // Outside the paper's 27..37 degC x 40..240 mA (margins 1 degC, 5 mA): refused, the
    // quantity named; evaluated and marked only when asked for.
    let e = fails(&["thermal", "eval", "--t", "30", "--e-in", "-5", "--thermal", "paper"]);
    assert!(e.contains("e_in_ma = -5 is outside [35, 245]"), "{e}");
    let e = fails(&["thermal", "eval", "--t", "80", "--e-in", "150", "--thermal", "paper"]);
    assert!(e.contains("temperature_c = 80 is outside [26, 38]"), "{e}");
    let v = json_ok(&[
        "thermal",
        "eval",
        "--t",
        "30",
        "--e-in",
        "-5",
        "--thermal",
        "paper",
        "--allow-extrapolation",
        "--json",
    ]);
    assert_eq!(v["extrapolated"], true);
    // No surface is assumed: without --thermal, a usage error (exit 2).
    let out = etlcal(&["thermal", "eval", "--t", "30", "--e-in", "100"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--thermal"));
}

#[test]
fn thermal_eval_bad_input_is_a_one_line_error() {
    fn with<'a>(a: &[&'a str]) -> Vec<&'a str> {
        [a, &["--thermal", "paper"]].concat()
    }
    assert!(fails(&with(&["thermal", "eval", "--t", "30", "--e-in", "NaN", "--json"])).contains("e_in_ma"));
    assert!(fails(&with(&["thermal", "eval", "--t", "inf", "--e-in", "100"])).contains("temperature_c"));
    // 303 K passed as degC: outside the operating domain, even when extrapolating.
    assert!(fails(&with(&["thermal", "eval", "--t", "303.15", "--e-in", "100", "--allow-extrapolation"]))
        .contains("t_c = 303.15 is outside [-40, 125]"));
    let dir = tempfile::tempdir().unwrap();
    let wrong = dir.path().join("wrong.json");
    std::fs::write(&wrong, r#"{"format": "etlcal.calibration/1"}"#).unwrap();
    let e = fails(&["thermal", "eval", "--t", "30", "--e-in", "100", "--thermal", wrong.to_str().unwrap()]);
    assert!(e.contains("etlcal.calibration/1") && e.contains("etlcal.thermal/1"), "{e}");
    let missing = dir.path().join("missing.json");
    fails(&["thermal", "eval", "--t", "30", "--e-in", "100", "--thermal", missing.to_str().unwrap()]);
}

/// The paper's procedure grid (27..37 degC by 1, 40..240 mA by 20) as a CSV table.
fn write_table(path: &Path, noise_ma: f64, seed: u64) {
    let truth = ThermalSurface::PAPER;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_ma.max(1e-300)).unwrap();
    let mut text = String::from("temperature_c,e_in_ma,e_t_ma\n");
    for it in 0..=10 {
        for ie in 0..=10 {
            let (t, e) = (27.0 + it as f64, 40.0 + 20.0 * ie as f64);
            let y = truth.e_t_ma(e, t).unwrap() + if noise_ma > 0.0 { noise.sample(&mut rng) } else { 0.0 };
            text.push_str(&format!("{t},{e},{y}\n"));
        }
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn thermal_fit_recovers_the_surface_and_eval_reads_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("table.csv");
    let out = dir.path().join("thermal.json");
    write_table(&table, 0.0, 0);
    let v = json_ok(&["thermal", "fit", table.to_str().unwrap(), "--out", out.to_str().unwrap(), "--json"]);
    assert_eq!(v["samples"], 121);
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(file["format"], "etlcal.thermal/1");
    let keys: Vec<&str> = file.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(keys.len(), 5, "{keys:?}");
    for (k, c) in file["coefficients"].as_array().unwrap().iter().enumerate() {
        let want = ThermalSurface::PAPER.coefficients[k];
        assert!((num(c) - want).abs() <= 1e-9 * want.abs(), "c{k}: {c} vs {want}");
    }
    assert!(num(&file["rms_ma"]) < 1e-9);
    assert_eq!(file["t_range_c"], serde_json::json!([27.0, 37.0]));
    assert_eq!(file["e_in_range_ma"], serde_json::json!([40.0, 240.0]));
    let paper = json_ok(&["thermal", "eval", "--t", "35", "--e-in", "120", "--thermal", "paper", "--json"]);
    let fitted =
        json_ok(&["thermal", "eval", "--t", "35", "--e-in", "120", "--thermal", out.to_str().unwrap(), "--json"]);
    assert!((num(&paper["e_com_ma"]) - num(&fitted["e_com_ma"])).abs() < 1e-9);
}

/// With 0.2 mA noise on E_T the reported RMS is 0.2 +- 0.03 mA (the paper: 0.2106 mA).
#[test]
fn thermal_fit_reports_the_noise_rms() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("noisy.csv");
    let out = dir.path().join("thermal.json");
    write_table(&table, 0.2, 42);
    let v = json_ok(&["thermal", "fit", table.to_str().unwrap(), "--out", out.to_str().unwrap(), "--json"]);
    assert!((num(&v["rms_ma"]) - 0.2).abs() < 0.03, "{v}");
}

#[test]
fn thermal_fit_bad_input_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("thermal.json");
    let o = out.to_str().unwrap();
    let cases: &[(&str, &str)] = &[
        ("temp,e,et\n30,100,0\n", "header"),
        ("temperature_c,e_in_ma,e_t_ma\n30,100,NaN\n", "line 2"),
        ("temperature_c,e_in_ma,e_t_ma\n30,100\n", "line 2"),
        ("temperature_c,e_in_ma,e_t_ma\n30,100,0\n31,100,0\n", "too few"),
    ];
    for (k, (text, needle)) in cases.iter().enumerate() {
        let table = dir.path().join(format!("bad{k}.csv"));
        std::fs::write(&table, text).unwrap();
        let e = fails(&["thermal", "fit", table.to_str().unwrap(), "--out", o, "--json"]);
        assert!(e.contains(needle), "case {k}: {e}");
        assert!(!out.exists(), "case {k} wrote {o}");
    }
    // All samples at one temperature: named.
    let table = dir.path().join("one_t.csv");
    let mut text = String::from("temperature_c,e_in_ma,e_t_ma\n");
    for i in 0..20 {
        text.push_str(&format!("30,{},0.1\n", 10 * i));
    }
    std::fs::write(&table, text).unwrap();
    assert!(fails(&["thermal", "fit", table.to_str().unwrap(), "--out", o]).contains("one temperature"));
    assert!(!out.exists());
    // A failed fit leaves an earlier output whole.
    std::fs::write(&out, "earlier").unwrap();
    fails(&["thermal", "fit", table.to_str().unwrap(), "--out", o]);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "earlier");
    // A missing table.
    fails(&["thermal", "fit", dir.path().join("nope.csv").to_str().unwrap(), "--out", o]);
}

/// `etlcal ... | head`: a closed stdout is not a crash. Every verb's human-readable output
/// goes through `outln!`, which ignores the write error as `--json` output does; the read
/// end of the pipe is closed before the process starts, so every write fails.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    for args in [&["model"][..], &["model", "--json"][..]] {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_etlcal"))
            .args(args)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .expect("run etlcal");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
    }
}
