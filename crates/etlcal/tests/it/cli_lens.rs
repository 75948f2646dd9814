//! `etlcal lens --virtual ...` through the real binary: the documented `--json` keys, the
//! clamping policy (beyond the limits: clamped with a warning, exit 0), NaN refused.
use std::process::Command;

use serde_json::Value;

use super::common::etlcal_run as etlcal;

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

/// Asserts a refusal: exit 1, one line on stderr containing `want`, nothing on stdout.
fn refused(args: &[&str], want: &str) {
    let (code, out, err) = etlcal(args);
    assert_eq!(code, 1, "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(want), "{args:?}: {err}");
    assert!(out.is_empty(), "{args:?}: {out}");
}

#[test]
fn hold_flags_outside_their_ranges_are_refused_in_one_line_without_panicking() {
    fn hold(extra: &[&'static str]) -> Vec<&'static str> {
        [&["lens", "--virtual", "--json", "hold", "--e-com", "150", "--thermal", "paper"][..], extra].concat()
    }
    refused(&hold(&["--duration", "1e30"]), "--duration 1e30 s must lie in 0..=1e7 s");
    refused(&hold(&["--duration", "-1"]), "--duration -1 s must lie in 0..=1e7 s");
    refused(&hold(&["--rate", "1e-30"]), "--rate 1e-30 Hz must be 0 (as fast as possible) or lie in 0.001..=10000 Hz");
    refused(&hold(&["--rate", "inf"]), "--rate inf Hz must be 0");
    refused(&hold(&["--time-scale", "1e308", "--duration", "1"]), "--time-scale 1e308 must lie in (0, 1e6]");
    refused(&hold(&["--warm", "1e308", "--duration", "1"]), "--warm 1e308 degC takes the lens to 1e308 degC");
    refused(&["lens", "--virtual", "--timeout-ms", "0", "info"], "--timeout-ms 0 must lie in 1..=60000 ms");
}

/// A `lens-sim` child serving on a pseudo-terminal, killed (by its pid) when dropped.
struct Sim(std::process::Child, String);

impl Sim {
    fn spawn(args: &[&str]) -> Sim {
        use std::io::BufRead;
        let mut child = Command::new(env!("CARGO_BIN_EXE_etlcal"))
            .arg("lens-sim")
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        Sim(child, line.trim().to_owned())
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[cfg(unix)]
#[test]
fn hold_beyond_the_driver_limits_fails_instead_of_reporting_success() {
    let sim = Sim::spawn(&["--upper-limit", "200", "--ambient", "27"]);
    let (code, out, err) = etlcal(&[
        "lens",
        "--port",
        &sim.1,
        "--json",
        "hold",
        "--e-com",
        "260",
        "--thermal",
        "paper",
        "--duration",
        "1",
    ]);
    assert_eq!(code, 1, "{out} {err}");
    assert!(out.is_empty(), "no success report: {out}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("E_com 260.000 mA needs E_in ") && err.contains("beyond the driver's limits"), "{err}");
    // Within the limits the same driver holds.
    let (code, out, err) = etlcal(&[
        "lens",
        "--port",
        &sim.1,
        "--json",
        "hold",
        "--e-com",
        "150",
        "--thermal",
        "paper",
        "--duration",
        "0.2",
    ]);
    assert_eq!(code, 0, "{err}");
    let h: Value = serde_json::from_str(&out).unwrap();
    assert!(h["worst_e_com_error_ma"].as_f64().unwrap() < 0.04, "{h}");
}

#[test]
fn lens_sim_refuses_an_absurd_ambient_or_time_scale() {
    refused(&["lens-sim", "--ambient", "1e308"], "--ambient 1e308 degC must lie in -40..=125 degC");
    refused(&["lens-sim", "--time-scale", "0"], "--time-scale 0 must lie in (0, 1e6]");
    refused(&["lens-sim", "--upper-limit", "1e308"], "limits [-292.84, 1e308] mA");
}

/// The folder of the port `sim` printed (`TMPDIR/etl-vlens-PID-N/lens`).
#[cfg(unix)]
fn port_folder(sim: &Sim) -> std::path::PathBuf {
    let port = sim.1.rsplit(' ').next().unwrap_or(&sim.1);
    std::path::Path::new(port).parent().unwrap().to_owned()
}

#[cfg(unix)]
#[test]
fn a_stopped_lens_sim_removes_its_folder_and_a_killed_ones_is_swept_by_the_next() {
    use nix::sys::signal::{kill, Signal};
    use nix::unistd::Pid;
    use std::os::unix::process::ExitStatusExt;
    for sig in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        let mut sim = Sim::spawn(&[]);
        let dir = port_folder(&sim);
        assert!(dir.join("lens").exists(), "{}", sim.1);
        kill(Pid::from_raw(sim.0.id() as i32), sig).unwrap();
        let status = sim.0.wait().unwrap();
        assert_eq!(status.signal(), Some(sig as i32), "dies of the signal, as without a handler");
        assert!(!dir.exists(), "{sig}: {} is left", dir.display());
    }
    let mut killed = Sim::spawn(&[]);
    let dir = port_folder(&killed);
    killed.0.kill().unwrap(); // SIGKILL: no code of the process runs
    killed.0.wait().unwrap();
    assert!(dir.exists(), "a SIGKILLed process cannot remove its folder");
    let next = Sim::spawn(&[]);
    assert!(!dir.exists(), "the next lens sweeps {}", dir.display());
    drop(next);
}

/// The published dynamics fixture (fixtures/lens-dynamics).
fn published_dynamics() -> String {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/lens-dynamics/el-10-30-published.json");
    p.to_str().unwrap().to_owned()
}

#[test]
fn the_virtual_lens_takes_dynamics_and_refuses_bad_ones_in_one_line() {
    let good = published_dynamics();
    let (code, out, err) = etlcal(&["lens", "--virtual", "--dynamics", &good, "--json", "set-current", "120"]);
    assert_eq!(code, 0, "{err}");
    assert!(serde_json::from_str::<Value>(&out).unwrap()["commanded_ma"].as_f64().is_some(), "{out}");
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    let text = std::fs::read_to_string(&good).unwrap().replace("\"damping\": 0.28", "\"damping\": 0");
    std::fs::write(&bad, text).unwrap();
    let bad = bad.to_str().unwrap();
    refused(&["lens", "--virtual", "--dynamics", bad, "info"], "damping");
    refused(&["lens-sim", "--dynamics", bad], "damping");
    refused(
        &["lens", "--port", "/dev/null", "--dynamics", &good, "info"],
        "--dynamics FILE describes the virtual lens",
    );
    refused(&["lens", "--virtual", "--dynamics", "/nonexistent/d.json", "info"], "/nonexistent/d.json");
}

#[cfg(unix)]
#[test]
fn lens_sim_serves_a_lens_with_dynamics() {
    let sim = Sim::spawn(&["--dynamics", &published_dynamics()]);
    let (code, out, err) = etlcal(&["lens", "--port", &sim.1, "--json", "set-current", "150"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("commanded_ma"), "{out}");
}

#[test]
fn focal_power_mode_in_the_documented_order_and_its_refusals_in_one_line() {
    let (code, out, err) = etlcal(&["lens", "--virtual", "--json", "set-focal-power", "12.5", "--window", "20", "40"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    for key in ["focal_power_dpt", "requested_dpt", "read_back_dpt", "window_c", "range_dpt", "status", "mode"] {
        assert!(j.get(key).is_some(), "set-focal-power lacks {key}: {j}");
    }
    assert_eq!(j["focal_power_dpt"], 12.5);
    assert!((j["read_back_dpt"].as_f64().unwrap() - 12.5).abs() < 0.01, "{j}");
    assert_eq!(j["window_c"], serde_json::json!([20.0, 40.0]));
    // Without --window: the lens's temperature +-10 degC, said on stderr.
    let (code, out, err) = etlcal(&["lens", "--virtual", "--json", "mode", "focal-power"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("temperature window 17..37 degC (the lens's 27 degC +-10"), "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["mode"], "focal-power");
    let (code, out, _) = etlcal(&["lens", "--virtual", "--json", "mode", "current"]);
    assert_eq!((code, out.trim()), (0, r#"{"mode":"current"}"#));
    let (code, out, _) = etlcal(&["lens", "--virtual", "--json", "focal-power"]);
    assert_eq!(code, 0);
    assert!(serde_json::from_str::<Value>(&out).unwrap()["focal_power_dpt"].as_f64().is_some());
    let w = ["--window", "20", "40"];
    refused(&[&["lens", "--virtual", "set-focal-power", "40"][..], &w].concat(), "focal power (dpt) = 40 is outside [");
    refused(
        &["lens", "--virtual", "set-focal-power", "12", "--window", "40", "20"],
        "--window 40 20 degC must satisfy",
    );
    refused(&["lens", "--virtual", "mode", "focal-power", "--window", "0", "200"], "--window 0 200 degC");
    refused(&[&["lens", "--virtual", "set-focal-power", "NaN"][..], &w].concat(), "focal power NaN dpt must be finite");
}

#[test]
fn characterise_prints_the_documented_keys_writes_the_dynamics_and_refuses_what_it_cannot_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("measured.json");
    let report = dir.path().join("report");
    let f = published_dynamics();
    let args = [
        "lens",
        "--virtual",
        "--dynamics",
        &f,
        "--json",
        "characterise",
        "--camera",
        "sim",
        "--out",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    let (code, stdout, err) = etlcal(&args);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    for key in ["settling_ms", "hysteresis_ma", "creep_tau_s", "creep_fraction", "repeatability_ma"] {
        assert!(j.get(key).is_some(), "characterise lacks {key}: {j}");
    }
    let up = j["settling_ms"]["up"].as_f64().unwrap();
    assert!(j["shaped_settling_ms"]["up"].as_f64().unwrap() * 2.0 <= up, "{j}");
    assert!((10.0..20.0).contains(&up) && j["settling_ms"]["down"].as_f64().is_some(), "{j}");
    let written = etl_formats::LensDynamicsFile::load(&out).unwrap();
    assert!((written.natural_frequency_hz - 150.0).abs() < 15.0, "{written:?}");
    assert!(written.source.unwrap().contains("not measured: the published defaults"));
    // The report: the page with the numbers, the step responses plotted.
    let files: Vec<&str> = j["report"].as_array().unwrap().iter().map(|p| p.as_str().unwrap()).collect();
    assert_eq!(files.len(), 3, "{j}");
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(html.contains(&format!("{up:.2} ms up")) && html.contains("step_responses.png"), "{html:.500}");
    assert!(std::fs::metadata(report.join("step_responses.png")).unwrap().len() > 1000);
    refused(&["lens", "--virtual", "characterise", "--camera", "sim"], "nothing to characterise");
    refused(&["lens", "--virtual", "--dynamics", &f, "characterise", "--camera", "basler:1"], "only `sim` exists yet");
    refused(
        &["lens", "--virtual", "--dynamics", &f, "characterise", "--camera", "sim", "--frame-rate", "0"],
        "--frame-rate",
    );
}

/// `set-current --shaped F`: the step split by the zero-vibration shaper of F's membrane
/// (published: 150 Hz, damping 0.28: 71.4 % at once, the rest 3.47 ms later), the target
/// confirmed; an overdamped membrane has no shaper and is refused in one line.
#[test]
fn set_current_shaped_splits_the_step_by_the_shaper_of_the_dynamics() {
    let f = published_dynamics();
    let (code, stdout, err) = etlcal(&["lens", "--virtual", "--json", "set-current", "100", "--shaped", &f]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    let s = &j["shaper"];
    let fraction = s["first_fraction"].as_f64().unwrap();
    assert!((fraction - 0.7143).abs() < 1e-3 && (s["delay_ms"].as_f64().unwrap() - 3.472).abs() < 1e-3, "{s}");
    assert!((s["first_ma"].as_f64().unwrap() - 100.0 * fraction).abs() < 0.1, "{s}");
    assert!((j["current_ma"].as_f64().unwrap() - 100.0).abs() < 0.1, "{j}");
    let dir = tempfile::tempdir().unwrap();
    let over = dir.path().join("over.json");
    let text = std::fs::read_to_string(&f).unwrap().replace("\"damping\": 0.28", "\"damping\": 1.5");
    std::fs::write(&over, text).unwrap();
    refused(&["lens", "--virtual", "set-current", "100", "--shaped", over.to_str().unwrap()], "no shaper");
}
