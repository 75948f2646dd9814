//! `etlcal report` as the built binary: the figures it lists in `--json` exist, are
//! non-empty and are all shown by index.html, which names its inputs (provenance).
use std::process::Command;

use serde_json::Value;

use crate::common::tree;

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

/// `report` run from the repository root on a committed calibration with
/// `SOURCE_DATE_EPOCH` set to `epoch`, into `out`.
fn report_at(epoch: &str, out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_etlcal"))
        .args(["report", "--calibration", "fixtures/service/calibration.json", "--out", out.to_str().unwrap()])
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .env("SOURCE_DATE_EPOCH", epoch)
        .output()
        .expect("run etlcal")
}

/// Every file of `dir` and its bytes.
fn files(dir: &std::path::Path) -> std::collections::BTreeMap<std::ffi::OsString, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| (e.file_name(), std::fs::read(e.path()).unwrap()))
        .collect()
}

#[test]
fn source_date_epoch_fixes_the_reports_time_and_a_bad_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    // 2026-12-02 12:34:56 UTC: the report says the minute, and two runs write the same bytes.
    for out in [&a, &b] {
        let o = report_at("1796214896", out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let html = std::fs::read_to_string(a.join("index.html")).unwrap();
    assert!(html.contains("<td>report written</td><td>2026-12-02 12:34 UTC</td>"), "{html}");
    assert_eq!(files(&a), files(&b));
    let before = files(&a);
    for bad in ["", "-1", "1.5", "12 ", "+5", "253402300800", "yesterday"] {
        let o = report_at(bad, &a);
        let err = String::from_utf8(o.stderr).unwrap();
        assert_eq!(o.status.code(), Some(1), "{bad:?}: {err}");
        assert!(err.starts_with("etlcal: error: ") && err.lines().count() == 1, "{bad:?}: {err}");
        assert!(err.contains("SOURCE_DATE_EPOCH"), "{bad:?}: {err}");
        assert_eq!(files(&a), before, "{bad:?}: the earlier report is kept");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2, "no temporary left");
}

#[test]
fn with_source_date_epoch_set_demo_and_study_write_the_same_bytes_twice() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_etlcal"))
            .args(args)
            .env("SOURCE_DATE_EPOCH", "1796214896")
            .output()
            .expect("run etlcal");
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    for name in ["demo-a", "demo-b"] {
        run(&["demo", "--no-images", "--out", &out(name)]);
    }
    for name in ["fig6-a", "fig6-b"] {
        run(&["study", "fig6", "--trials", "1", "--out", &out(name)]);
    }
    let (demo, fig6) = (tree(&dir.path().join("demo-a")), tree(&dir.path().join("fig6-a")));
    assert!(demo.len() > 3 && !fig6.is_empty(), "{:?} {:?}", demo.keys(), fig6.keys());
    // Before, the elapsed seconds were written into summary.md, index.html and fig6.json.
    assert_eq!(demo, tree(&dir.path().join("demo-b")), "demo's files differ between two runs");
    assert_eq!(fig6, tree(&dir.path().join("fig6-b")), "study fig6's files differ between two runs");
    let json: Value = serde_json::from_slice(&fig6[std::path::Path::new("fig6.json")]).unwrap();
    assert!(json["seconds"].is_null(), "{json}");
}
