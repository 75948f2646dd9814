//! `etlcal simulate`, `calibrate` and `demo` through the real binary: figures against the
//! truth, and every bad input named in the acceptance criteria (message, exit code, nothing
//! written or overwritten).

use std::path::Path;

use serde_json::Value;

use super::common::etlcal_run as etlcal;

fn simulate(dir: &Path) {
    let d = dir.to_str().unwrap();
    let (code, _, err) = etlcal(&["simulate", "--out", d, "--observations-only", "--seed", "7"]);
    assert_eq!(code, 0, "{err}");
}

/// `calibrate` of the simulation in `dir` (its observations and A0) into `out` with
/// `extra` flags, which must succeed; the calibration file.
fn calibrate_simulated(dir: &Path, out: &str, extra: &[&str]) -> Value {
    let p = |f: &str| dir.join(f).to_str().unwrap().to_owned();
    let (obs, a0) = (p("observations.json"), p("a0.json"));
    let mut args = vec!["calibrate", "--observations", &obs, "--a0", &a0, "--out", out];
    args.extend_from_slice(extra);
    let (code, _, err) = etlcal(&args);
    assert_eq!(code, 0, "{extra:?}: {err}");
    serde_json::from_str::<Value>(&std::fs::read_to_string(out).unwrap()).unwrap()
}

#[test]
fn simulate_then_calibrate_recovers_the_paper_rig() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let obs = dir.path().join("observations.json");
    let a0 = dir.path().join("a0.json");
    let out = dir.path().join("cal.json");
    for est in ["paper", "eiv"] {
        let (code, stdout, err) = etlcal(&[
            "calibrate",
            "--observations",
            obs.to_str().unwrap(),
            "--a0",
            a0.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--estimator",
            est,
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let j: Value = serde_json::from_str(&stdout).unwrap();
        let written: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(j, written, "--json prints the object written");
        assert_eq!(j["format"], "etlcal.calibration/1");
        assert_eq!(j["estimator"], est);
        // 0.2 px per coordinate plus the stage/current errors the paper estimator absorbs.
        let rms = j["rms_reprojection_px"].as_f64().unwrap();
        assert!(rms > 0.25 && rms < 0.6, "{est}: rms {rms}");
        let got = j["kf_x"][0].as_f64().unwrap()
            + 100.0 * j["kf_x"][1].as_f64().unwrap()
            + 1e4 * j["kf_x"][2].as_f64().unwrap()
            + 1e6 * j["kf_x"][3].as_f64().unwrap();
        // The paper estimator carries the stage/current noise into fx (docs/METHOD.md): ~1 %.
        let tol = if est == "paper" { 0.02 } else { 0.005 };
        assert!((got - 4850.0).abs() / 4850.0 < tol, "{est}: fx(100) = {got}");
        assert_eq!(j["std"]["kf_x"].as_array().unwrap().len(), 4);
        assert_eq!(j["views"].as_array().unwrap().len(), 15);
    }
}

#[test]
fn the_default_estimator_is_errors_in_variables() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let calibrate = |out: &str, extra: &[&str]| calibrate_simulated(dir.path(), out, extra);
    let default = calibrate(&p("default.json"), &[]);
    assert_eq!(default["estimator"], "eiv");
    // The same run as --estimator eiv with its default priors (10 um, 0.4 mA), number for number.
    let eiv = calibrate(&p("eiv.json"), &["--estimator", "eiv", "--sigma-z-um", "10", "--sigma-e-ma", "0.4"]);
    assert_eq!(default, eiv);
    // The paper's Eq. 24 stays one flag away, and is a different solution.
    let paper = calibrate(&p("paper.json"), &["--estimator", "paper"]);
    assert_eq!(paper["estimator"], "paper");
    assert_ne!(paper["kf_x"], default["kf_x"]);
    assert!(default["views"].as_array().unwrap().iter().any(|v| v["dz_mm"].as_f64().unwrap() != 0.0));
    assert!(paper["views"].as_array().unwrap().iter().all(|v| v["dz_mm"].as_f64().unwrap() == 0.0));
    let (code, help, _) = etlcal(&["calibrate", "--help"]);
    assert_eq!(code, 0);
    assert!(help.contains("[default: eiv]"), "{help}");
}

#[test]
fn per_setting_baseline_from_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, _, err) = etlcal(&["simulate", "--out", d, "--observations-only", "--setting-views", "--seed", "7"]);
    assert_eq!(code, 0, "{err}");
    let obs = dir.path().join("observations.json");
    let out = dir.path().join("baseline.json");
    let (code, stdout, err) = etlcal(&[
        "calibrate",
        "--observations",
        obs.to_str().unwrap(),
        "--method",
        "per-setting",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let printed: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(printed["estimator"], "per-setting");
    assert_eq!(printed, serde_json::from_str::<Value>(&std::fs::read_to_string(&out).unwrap()).unwrap());
    // The cubic through the per-setting focal lengths, against the truth over 80..225 mA.
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("truth.json")).unwrap()).unwrap();
    let cubic = |k: &Value, e: f64| (0..4).map(|i| k[i].as_f64().unwrap() * e.powi(i as i32)).sum::<f64>();
    for e in [80.0, 150.0, 225.0] {
        let rel = cubic(&printed["kf_x"], e) / cubic(&truth["model"]["kf_x"], e) - 1.0;
        assert!(rel.abs() < 0.03, "fx at {e} mA off by {rel}");
    }
}

#[test]
fn demo_meets_the_acceptance_figures() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("demo");
    let (code, stdout, err) = etlcal(&["demo", "--out", d.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    for k in [
        "fx_curve_max_rel_err",
        "fy_curve_max_rel_err",
        "principal_point_err_px",
        "rms_reprojection_px",
        "views_detected",
        "seconds",
    ] {
        assert!(j[k].is_number(), "{k} missing");
    }
    assert!(j["fx_curve_max_rel_err"].as_f64().unwrap() < 0.01 && j["fy_curve_max_rel_err"].as_f64().unwrap() < 0.01);
    assert!(j["eiv"]["fx_curve_max_rel_err"].as_f64().unwrap() < 0.005);
    let pnp = j["eiv"]["pnp_displacement_err_um"].as_array().unwrap();
    let last = pnp.last().unwrap();
    assert_eq!(last["e_com_ma"].as_f64().unwrap(), 225.0);
    assert!(last["err_um"].as_f64().unwrap() < 20.0, "{last}");
    for f in ["observations.json", "a0.json", "truth.json", "calibration.json", "calibration-paper.json", "summary.md"]
    {
        assert!(d.join(f).is_file(), "{f} not written");
    }
    demo_files_are_named_for_what_they_hold(&d, &j);
    readme_demo_table_is(&j);
    // With a better stage the paper estimator's curve error falls accordingly.
    let (code, stdout, _) = etlcal(&["demo", "--out", d.to_str().unwrap(), "--json", "--stage-noise-um", "1"]);
    assert_eq!(code, 0);
    let j1: Value = serde_json::from_str(&stdout).unwrap();
    assert!(j1["fx_curve_max_rel_err"].as_f64().unwrap() < 0.5 * j["fx_curve_max_rel_err"].as_f64().unwrap());
}

/// calibration.json is the recommended estimator's (errors-in-variables, the `"eiv"`
/// figures of `--json`), calibration-paper.json the paper's; a0.json is Zhang's A0 from
/// the lens-off views: close to the true A0 (truth.json's `kf_x[0]`, `kf_y[0]`,
/// `principal_point`) and not equal to it; report/ is the recommended calibration's.
fn demo_files_are_named_for_what_they_hold(d: &Path, j: &Value) {
    let read = |f: &str| -> Value { serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap() };
    let (cal, paper) = (read("calibration.json"), read("calibration-paper.json"));
    assert_eq!(cal["estimator"], "eiv");
    assert_eq!(paper["estimator"], "paper");
    let rms = |v: &Value| v["rms_reprojection_px"].as_f64().unwrap();
    assert_eq!(rms(&cal), j["eiv"]["rms_reprojection_px"].as_f64().unwrap());
    assert_eq!(rms(&paper), j["rms_reprojection_px"].as_f64().unwrap());
    let (a0, truth) = (read("a0.json"), read("truth.json"));
    let truth = &truth["dataset_model"];
    let f = |v: &Value, k: &str, i: usize| v[k][i].as_f64().unwrap();
    let (kf0x, kf0y) = (f(truth, "kf_x", 0), f(truth, "kf_y", 0));
    let (u0, v0) = (f(truth, "principal_point", 0), f(truth, "principal_point", 1));
    let got = |k: &str| a0[k].as_f64().unwrap();
    assert!((got("kf0x") / kf0x - 1.0).abs() < 0.01 && (got("kf0y") / kf0y - 1.0).abs() < 0.01, "{a0} vs {truth}");
    assert!((got("u0") - u0).hypot(got("v0") - v0) < 10.0, "{a0} vs {truth}");
    assert!(got("u0") != u0 && got("kf0x") != kf0x, "a0.json is the truth's, not Zhang's: {a0}");
    // The page to open first names the recommended calibration first and links every file.
    let page = std::fs::read_to_string(d.join("index.html")).unwrap();
    for file in ["report/index.html", "report-paper/index.html", "calibration.json", "a0.json", "dataset.json"] {
        assert!(page.contains(&format!("<a href=\"{file}\">")), "index.html links no {file}");
    }
    let eiv_fx = format!("{:.3} %", 100.0 * j["eiv"]["fx_curve_max_rel_err"].as_f64().unwrap());
    let paper_fx = format!("{:.3} %", 100.0 * j["fx_curve_max_rel_err"].as_f64().unwrap());
    assert!(page.contains(&format!("<td>max rel. error of fx(E)</td><td>{eiv_fx}</td><td>{paper_fx}</td>")), "{page}");
    let index = std::fs::read_to_string(d.join("report/index.html")).unwrap();
    assert!(index.contains("calibration.json") && !index.contains("calibration-paper.json"));
    assert!(std::fs::read_to_string(d.join("report-paper/index.html")).unwrap().contains("calibration-paper.json"));
}

/// The README's demo table states what `etlcal demo --json` (seed 1, images) prints, rounded
/// as printed there, so it cannot go stale.
fn readme_demo_table_is(j: &Value) {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    let row = |start: &str| -> Vec<String> {
        let line =
            readme.lines().find(|l| l.starts_with(start)).unwrap_or_else(|| panic!("README has no row {start:?}"));
        line.split('|').map(|c| c.trim().to_owned()).filter(|c| !c.is_empty()).skip(1).collect()
    };
    let pnp_225 = |j: &Value| {
        let last = j["pnp_displacement_err_um"].as_array().unwrap().last().unwrap().clone();
        assert_eq!(last["e_com_ma"].as_f64().unwrap(), 225.0);
        last["err_um"].as_f64().unwrap()
    };
    let (paper, eiv) = (j, &j["eiv"]);
    let fx = |j: &Value| format!("{:.2} %", 100.0 * j["fx_curve_max_rel_err"].as_f64().unwrap());
    let pp = |j: &Value| format!("{:.1} px", j["principal_point_err_px"].as_f64().unwrap());
    let um = |j: &Value| format!("{:.1} um", pnp_225(j));
    assert_eq!(row("| max rel. error of fx(E)"), [fx(paper), fx(eiv)], "README demo table, fx(E) row");
    assert_eq!(row("| principal point error"), [pp(paper), pp(eiv)], "README demo table, principal point row");
    assert_eq!(row("| 2 mm stage move"), [um(paper), um(eiv)], "README demo table, PnP row");
}

/// Runs a failing calibrate and checks: exit 1, one line naming `needle`, and the earlier
/// output file left exactly as it was.
fn fails_without_writing(args: &[&str], out: &Path, needle: &str) {
    std::fs::write(out, "earlier output").unwrap();
    let (code, stdout, err) = etlcal(args);
    assert_eq!(code, 1, "stdout {stdout} stderr {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(err.contains(needle), "expected {needle:?} in {err}");
    assert_eq!(std::fs::read_to_string(out).unwrap(), "earlier output");
}

#[test]
fn bad_inputs_fail_with_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let out = p("cal.json");
    let (obs, a0) = (p("observations.json"), p("a0.json"));
    // A JSON file of the wrong format (an A0 file given as observations) and version.
    fails_without_writing(
        &["calibrate", "--observations", &a0, "--a0", &a0, "--out", &out],
        Path::new(&out),
        "etlcal.a0/1",
    );
    let text = std::fs::read_to_string(&obs).unwrap();
    std::fs::write(p("v2.json"), text.replace("etlcal.observations/1", "etlcal.observations/2")).unwrap();
    fails_without_writing(
        &["calibrate", "--observations", &p("v2.json"), "--a0", &a0, "--out", &out],
        Path::new(&out),
        "etlcal.observations/2",
    );
    // Unknown fields are refused.
    std::fs::write(p("unknown.json"), text.replacen("\"views\"", "\"colour\": 1, \"views\"", 1)).unwrap();
    fails_without_writing(
        &["calibrate", "--observations", &p("unknown.json"), "--a0", &a0, "--out", &out],
        Path::new(&out),
        "unknown field",
    );
    // All views at fewer than 3 currents.
    let mut v: Value = serde_json::from_str(&text).unwrap();
    for (i, view) in v["views"].as_array_mut().unwrap().iter_mut().enumerate() {
        view["e_com_ma"] = Value::from(if i % 2 == 0 { 80.0 } else { 90.0 });
    }
    std::fs::write(p("two.json"), v.to_string()).unwrap();
    fails_without_writing(
        &["calibrate", "--observations", &p("two.json"), "--a0", &a0, "--out", &out],
        Path::new(&out),
        "distinct currents",
    );
    // A missing input file, and no A0.
    fails_without_writing(
        &["calibrate", "--observations", &p("nope.json"), "--a0", &a0, "--out", &out],
        Path::new(&out),
        "nope.json",
    );
    // No A0: without --a0 it comes from the lens-off views; with none of those either, the
    // message says to pass --a0.
    let mut no_off: Value = serde_json::from_str(&text).unwrap();
    no_off.as_object_mut().unwrap().remove("offstate_views");
    std::fs::write(p("no_off.json"), no_off.to_string()).unwrap();
    fails_without_writing(&["calibrate", "--observations", &p("no_off.json"), "--out", &out], Path::new(&out), "--a0");
    let (code, _, err) = etlcal(&["calibrate", "--observations", &obs, "--out", &p("zhang_cal.json")]);
    assert_eq!(code, 0, "A0 by Zhang from the lens-off views: {err}");
    // An output path in a missing directory: the directory is created, as every verb does.
    let (code, _, err) = etlcal(&["calibrate", "--observations", &obs, "--a0", &a0, "--out", &p("missing/cal.json")]);
    assert_eq!(code, 0, "{err}");
    assert!(dir.path().join("missing/cal.json").is_file());
    // The per-setting baseline has no bundle adjustment: its flags are refused, even the
    // proposed method's default estimator given explicitly, before anything is read.
    for extra in
        [&["--estimator", "eiv"][..], &["--estimator", "paper"], &["--a0", &a0], &["--hold-a0"], &["--huber-px", "1"]]
    {
        let mut args = vec!["calibrate", "--observations", &obs, "--method", "per-setting", "--out", &out];
        args.extend_from_slice(extra);
        fails_without_writing(&args, Path::new(&out), "--method per-setting takes no --a0, --estimator");
    }
    // Negative noise in simulate.
    let (code, _, err) = etlcal(&["simulate", "--out", &p(""), "--observations-only", "--pixel-noise-px", "-1"]);
    assert_eq!(code, 1);
    assert!(err.contains("--pixel-noise-px -1 px is outside [0, 100] px"), "{err}");
}

#[test]
fn outliers_are_reported_in_the_json_and_warned_on_stderr() {
    // Issue 19: three corners replaced by far-off pixels; the calibration succeeds, lists
    // them in "outliers" (view, point) and says so in "warnings" and on stderr.
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let obs_path = dir.path().join("observations.json");
    let mut obs: Value = serde_json::from_str(&std::fs::read_to_string(&obs_path).unwrap()).unwrap();
    let bad = [(2usize, 5usize), (7, 40), (11, 0)];
    for &(v, p) in &bad {
        let px = &mut obs["views"][v]["points"][p]["pixel"];
        *px = serde_json::json!([px[0].as_f64().unwrap() + 300.0, px[1].as_f64().unwrap() - 200.0]);
    }
    std::fs::write(&obs_path, serde_json::to_string(&obs).unwrap()).unwrap();
    let (a0, out) = (dir.path().join("a0.json"), dir.path().join("cal.json"));
    let (code, stdout, err) = etlcal(&[
        "calibrate",
        "--observations",
        obs_path.to_str().unwrap(),
        "--a0",
        a0.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    let found: Vec<(u64, u64)> = j["outliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| (o["view"].as_u64().unwrap(), o["point"].as_u64().unwrap()))
        .collect();
    assert_eq!(found, bad.map(|(v, p)| (v as u64, p as u64)));
    assert!(j["outliers"][0]["residual_px"].as_f64().unwrap() > 300.0, "{}", j["outliers"]);
    assert!(j["warnings"][0].as_str().unwrap().starts_with("3 of 2311 corners"), "{}", j["warnings"]);
    assert!(err.contains("etlcal: warning: 3 of 2311 corners"), "{err}");
    assert!((j["principal_point"][0].as_f64().unwrap() - 900.0).abs() < 2.0, "{}", j["principal_point"]);
}

/// Runs a failing calibrate and checks: exit `code`, one line containing every one of
/// `needles`, and the earlier output file left exactly as it was.
fn fails_with(args: &[&str], out: &Path, code: i32, needles: &[&str]) {
    std::fs::write(out, "earlier output").unwrap();
    let (got, stdout, err) = etlcal(args);
    assert_eq!(got, code, "{args:?}: stdout {stdout} stderr {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: expected {needle:?} in {err}");
    }
    assert_eq!(std::fs::read_to_string(out).unwrap(), "earlier output");
}

#[test]
fn robust_and_sigma_flags_match_python_and_the_alias_is_the_same_request() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let calibrate = |out: &str, extra: &[&str]| calibrate_simulated(dir.path(), out, extra);
    // --huber-px K is --robust huber --robust-k-px K, number for number.
    let alias = calibrate(&p("alias.json"), &["--huber-px", "0.8"]);
    assert_eq!(alias, calibrate(&p("robust.json"), &["--robust", "huber", "--robust-k-px", "0.8"]));
    let plain = calibrate(&p("plain.json"), &[]);
    assert_ne!(alias["kf_x"], plain["kf_x"], "the loss reached the solver");
    // Cauchy, with the documented default k of 1 px.
    let cauchy = calibrate(&p("cauchy.json"), &["--robust", "cauchy"]);
    assert_eq!(cauchy, calibrate(&p("cauchy1.json"), &["--robust", "cauchy", "--robust-k-px", "1"]));
    assert_ne!(cauchy["kf_x"], plain["kf_x"]);
    // The stage prior in either unit; the pixel noise given instead of estimated.
    let um = calibrate(&p("um.json"), &["--sigma-z-um", "20"]);
    assert_eq!(um, calibrate(&p("mm.json"), &["--sigma-z-mm", "0.02"]));
    assert_ne!(um["kf_x"], plain["kf_x"]);
    let px = calibrate(&p("px.json"), &["--sigma-px", "0.25"]);
    assert_ne!(px["kf_x"], plain["kf_x"]);
    let (code, help, _) = etlcal(&["calibrate", "--help"]);
    assert_eq!(code, 0);
    for words in ["an alias of `--robust huber --robust-k-px PX`", "--sigma-z-mm", "--sigma-px", "[default: 10"] {
        assert!(help.contains(words), "{words:?} not in {help}");
    }
}

#[test]
fn bad_robust_and_sigma_flags_fail_naming_the_flag_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let (obs, a0, out) = (p("observations.json"), p("a0.json"), p("cal.json"));
    // Command lines that do not parse: exit 2, the parser's one line naming the flags.
    let usage: [(&[&str], &[&str]); 6] = [
        (&["--robust", "huber", "--huber-px", "1"], &["--huber-px", "--robust"]),
        (&["--robust", "cauchy", "--robust-k-px", "2", "--huber-px", "1"], &["--huber-px", "--robust"]),
        (&["--robust-k-px", "2"], &["--robust"]),
        (&["--robust", "l1"], &["l1", "--robust"]),
        (&["--sigma-z-um", "10", "--sigma-z-mm", "0.01"], &["--sigma-z-mm", "--sigma-z-um"]),
        (&["--sigma-px", "wide"], &["--sigma-px", "wide"]),
    ];
    // Values the request refuses: exit 1 (the CLI's bad input value), the flag as given.
    let refused: [(&[&str], &[&str]); 9] = [
        (&["--robust", "cauchy", "--robust-k-px", "-1"], &["--robust-k-px must be positive and finite"]),
        (&["--robust", "huber", "--robust-k-px", "inf"], &["--robust-k-px must be positive and finite"]),
        (&["--huber-px", "-1"], &["--huber-px must be positive"]),
        (&["--sigma-z-um", "-1"], &["--sigma-z-um must be positive"]),
        (&["--sigma-z-mm", "0"], &["--sigma-z-mm must be positive"]),
        (&["--sigma-e-ma", "-0.4"], &["--sigma-e-ma must be positive"]),
        (&["--sigma-px", "nan"], &["--sigma-px must be positive"]),
        (
            &["--method", "per-setting", "--robust", "cauchy"],
            &["--method per-setting takes no --a0, --estimator, --hold-a0 or --robust:"],
        ),
        (&["--method", "per-setting", "--huber-px", "1"], &["takes no --a0, --estimator, --hold-a0 or --huber-px:"]),
    ];
    for (code, cases) in [(2, &usage[..]), (1, &refused[..])] {
        for (extra, needles) in cases {
            let mut args = vec!["calibrate", "--observations", &obs, "--a0", &a0, "--out", &out];
            args.extend_from_slice(extra);
            fails_with(&args, Path::new(&out), code, needles);
        }
    }
}

/// Three views of six corners (the golden observations cut down) leave the principal
/// point unknown to hundreds of px: refused in one line naming the cause and the flag,
/// the earlier file kept; with `--accept-ill-conditioned` written, the symptom first among
/// its warnings.
#[test]
fn a_calibration_the_data_do_not_determine_is_refused_unless_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("fixtures/golden/observations.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    let views: Vec<Value> = v["views"].as_array().unwrap()[..3]
        .iter()
        .map(|w| {
            let mut w = w.clone();
            w["points"] = Value::Array(w["points"].as_array().unwrap()[..6].to_vec());
            w
        })
        .collect();
    v["views"] = Value::Array(views);
    let obs = dir.path().join("tiny.json");
    std::fs::write(&obs, serde_json::to_string(&v).unwrap()).unwrap();
    let out = dir.path().join("cal.json");
    std::fs::write(&out, "an earlier calibration").unwrap();
    let (o, c) = (obs.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, err) = etlcal(&["calibrate", "--observations", o, "--out", c]);
    assert_eq!(code, 1, "{err}");
    let line = err.lines().find(|l| l.contains("error")).unwrap();
    assert!(
        line.contains("the principal point's standard deviation is (") && line.contains("--accept-ill-conditioned"),
        "{err}"
    );
    assert!(line.contains("more than 5 % of the 1936 x 1458 px image") && line.len() < 400, "{line}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "an earlier calibration");
    let (code, _, err) = etlcal(&["calibrate", "--observations", o, "--out", c, "--accept-ill-conditioned"]);
    assert_eq!(code, 0, "{err}");
    let cal: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let first = cal["warnings"][0].as_str().unwrap();
    assert!(first.starts_with("ill-conditioned, kept by --accept-ill-conditioned: the principal point"), "{first}");
    assert!(err.contains(first), "said on stderr too: {err}");
    let std_u0 = cal["std"]["principal_point"][0].as_f64().unwrap();
    assert!(std_u0 > 0.05 * 1936.0, "{std_u0}");
}

/// `--centre`: `fixed` is the default, file for file; `moving` writes the file's
/// `"centre"` (on the paper rig, whose centre is fixed, a move within its uncertainty and
/// the same focal lengths within theirs); `auto` keeps the fixed centre there; a bad word
/// and the baseline are refused, naming the flag, and nothing is written.
#[test]
fn the_centre_flag_fixed_moving_auto() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path());
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let calibrate = |out: &str, extra: &[&str]| calibrate_simulated(dir.path(), out, extra);
    calibrate(&p("plain.json"), &["--estimator", "paper"]);
    let fixed = calibrate(&p("fixed.json"), &["--estimator", "paper", "--centre", "fixed"]);
    assert_eq!(std::fs::read(p("plain.json")).unwrap(), std::fs::read(p("fixed.json")).unwrap());
    assert!(fixed.get("centre").is_none());
    let moving = calibrate(&p("moving.json"), &["--estimator", "paper", "--centre", "moving"]);
    let c = &moving["centre"];
    let dz: Vec<f64> = c["dz_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!((dz.len(), dz[0]), (3, 0.0), "{c}");
    let sd: Vec<f64> =
        moving["std"]["centre"]["dz_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    // The move over 80..225 mA, against its standard deviation (the two terms' stds summed:
    // an upper bound of the move's).
    let mv = |d: &[f64]| (d[1] * (225.0 - 80.0) + d[2] * (225.0f64.powi(2) - 80.0f64.powi(2))).abs();
    let bound = sd[1] * 145.0 + sd[2] * (225.0f64.powi(2) - 80.0f64.powi(2));
    assert!(mv(&dz) < 4.0 * bound, "move {} mm, bound {bound}", mv(&dz));
    assert_eq!(moving["covariance"].as_array().unwrap().len(), 29);
    // Under the paper's noise the move is known to 0.15 mm, 0.2 % of the distance: said.
    let said = moving["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("do not determine the centre's move"));
    assert!(said, "{}", moving["warnings"]);
    assert_eq!(moving["principal_point"][0], c["principal_point_px"][0][0]);
    assert_eq!(moving["principal_point"][1], c["principal_point_px"][1][0]);
    let (auto_out, bad_out) = (p("auto.json"), p("bad.json"));
    let auto = calibrate(&auto_out, &["--estimator", "paper", "--centre", "auto"]);
    let table = auto["model_selection"]["candidates"].as_array().unwrap();
    assert_eq!(table.len(), 2);
    assert!(table.iter().any(|r| r["centre"] == "moving") && auto.get("centre").is_none(), "{table:?}");
    let (obs, a0) = (p("observations.json"), p("a0.json"));
    let args = ["calibrate", "--observations", &obs, "--a0", &a0, "--out", &bad_out, "--centre", "sideways"];
    let (code, _, err) = etlcal(&args);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--centre") && !Path::new(&bad_out).exists(), "{err}");
    let args =
        ["calibrate", "--observations", &obs, "--method", "per-setting", "--out", &bad_out, "--centre", "moving"];
    fails_without_writing(&args, Path::new(&bad_out), "takes no --centre");
}

/// `--setting-views joint`: the simulated setting views solved with the stage views (the
/// paper rig's centre is fixed: a moving centre's move comes back within its uncertainty,
/// now determined); the default is the stage views alone, file for file; refused without
/// setting views, with a setting view of 3 points (named), and beside the per-setting
/// baseline, a robust loss or an `auto` model choice, each in one line, nothing written.
#[test]
fn the_setting_views_flag_joint_and_its_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, _, err) = etlcal(&["simulate", "--out", d, "--observations-only", "--setting-views", "--seed", "7"]);
    assert_eq!(code, 0, "{err}");
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let joint = calibrate_simulated(dir.path(), &p("joint.json"), &["--setting-views", "joint", "--centre", "moving"]);
    let stage = calibrate_simulated(dir.path(), &p("stage.json"), &["--centre", "moving"]);
    let ignored =
        calibrate_simulated(dir.path(), &p("ignored.json"), &["--centre", "moving", "--setting-views", "ignored"]);
    assert_eq!(stage, ignored);
    let dz = |c: &Value, k: usize| c["centre"]["dz_mm"][k].as_f64().unwrap();
    let dz_std = |c: &Value, k: usize| c["std"]["centre"]["dz_mm"][k].as_f64().unwrap();
    // The move over 80..225 mA against the fixed truth (0), and its standard deviation
    // from the two dz numbers' (an upper bound: their correlation left out).
    // The file's dz_mm is (dz0 = 0, dz1, dz2).
    let mv = |c: &Value| dz(c, 1) * 145.0 + dz(c, 2) * (225.0f64.powi(2) - 80.0f64.powi(2));
    let mv_std = |c: &Value| dz_std(c, 1) * 145.0 + dz_std(c, 2) * (225.0f64.powi(2) - 80.0f64.powi(2));
    assert!(mv(&joint).abs() < 4.0 * mv_std(&joint), "move {} std {}", mv(&joint), mv_std(&joint));
    assert!(dz_std(&joint, 1) < 0.6 * dz_std(&stage, 1), "{} vs {}", dz_std(&joint, 1), dz_std(&stage, 1));
    let (obs, a0, out) = (p("observations.json"), p("a0.json"), p("refused.json"));
    let base = ["calibrate", "--observations", obs.as_str(), "--a0", a0.as_str(), "--out", out.as_str()];
    let with = |extra: &[&'static str]| [&base[..], &["--setting-views", "joint"], extra].concat();
    let out_path = Path::new(&out);
    fails_without_writing(&with(&["--robust", "huber"]), out_path, "--setting-views joint does not go with --robust");
    fails_without_writing(&with(&["--centre", "auto"]), out_path, "does not go with --centre auto");
    fails_without_writing(&with(&["--model", "auto"]), out_path, "does not go with --model auto");
    let per_setting =
        ["calibrate", "--observations", &obs, "--method", "per-setting", "--out", &out, "--setting-views", "joint"];
    fails_without_writing(&per_setting, out_path, "does not go with --method per-setting");
    // A setting view of 3 points, named.
    let mut o: Value = serde_json::from_str(&std::fs::read_to_string(&obs).unwrap()).unwrap();
    o["setting_views"][2]["points"].as_array_mut().unwrap().truncate(3);
    let small = p("small.json");
    std::fs::write(&small, serde_json::to_string(&o).unwrap()).unwrap();
    let args = ["calibrate", "--observations", &small, "--a0", &a0, "--out", &out, "--setting-views", "joint"];
    fails_without_writing(&args, out_path, "setting view 2 has 3 points");
    // No setting views at all.
    o["setting_views"] = Value::Array(vec![]);
    std::fs::write(&small, serde_json::to_string(&o).unwrap()).unwrap();
    fails_without_writing(&args, out_path, "--setting-views joint needs setting_views");
}
