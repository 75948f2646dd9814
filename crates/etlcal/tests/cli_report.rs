//! `etlcal report` as the built binary: the figures it lists in `--json` exist, are
//! non-empty and are all shown by index.html, which names its inputs (provenance).
use std::process::Command;

use serde_json::Value;

fn etlcal(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_etlcal")).args(args).output().expect("run etlcal");
    (o.status.code().unwrap_or(-1), String::from_utf8(o.stdout).unwrap(), String::from_utf8(o.stderr).unwrap())
}

#[test]
fn report_writes_every_figure_it_lists_and_index_html_shows_them() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
    let (code, _, err) = etlcal(&["simulate", "--out", &p(""), "--observations-only", "--seed", "7"]);
    assert_eq!(code, 0, "{err}");
    let (obs, a0, cal) = (p("observations.json"), p("a0.json"), p("cal.json"));
    let (code, _, err) =
        etlcal(&["calibrate", "--observations", &obs, "--a0", &a0, "--thermal", "paper", "--out", &cal]);
    assert_eq!(code, 0, "{err}");
    let (code, stdout, err) =
        etlcal(&["report", "--calibration", &cal, "--observations", &obs, "--out", &p("r"), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    let files: Vec<String> = j["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().to_owned()).collect();
    // 9 figures as SVG and PNG, and index.html.
    assert_eq!(files.len(), 19, "{files:?}");
    let html = std::fs::read_to_string(dir.path().join("r/index.html")).unwrap();
    for f in &files {
        assert!(std::fs::metadata(f).unwrap().len() > 0, "{f} empty");
        let name = std::path::Path::new(f).file_name().unwrap().to_str().unwrap();
        if name != "index.html" {
            assert!(html.contains(&format!("\"{name}\"")), "index.html does not reference {name}");
        }
    }
    assert!(html.contains(&cal) && html.contains(&obs), "provenance names the inputs");
}
