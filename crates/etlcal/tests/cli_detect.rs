//! `etlcal detect` on real photographs (fixtures/detect/SOURCE.md): JSON per image, the
//! exit status on unreadable files, the pattern parser.

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/detect")
}

#[test]
fn cli_prints_json_per_image_and_fails_on_unreadable_files() {
    let exe = env!("CARGO_BIN_EXE_etlcal");
    let good = fixtures().join("stereo_left01.jpg");
    let run = |args: &[&std::ffi::OsStr]| std::process::Command::new(exe).args(args).output().unwrap();
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "9x6".as_ref(), "--json".as_ref()]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"][0]["found"], true);
    assert_eq!(v["images"][0]["corners_px"].as_array().unwrap().len(), 54);
    // A board not found is a result (exit 0) with its reason.
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "10x6".as_ref(), "--json".as_ref()]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"][0]["found"], false);
    assert!(v["images"][0]["error"].as_str().unwrap().contains("board not found"));
    // An unreadable file: still listed, exit status 1, the reason on stderr.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.png");
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\n truncated").unwrap();
    let out = run(&[
        "detect".as_ref(),
        good.as_os_str(),
        bad.as_os_str(),
        "--pattern".as_ref(),
        "9x6".as_ref(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"][0]["found"], true);
    assert_eq!(v["images"][1]["found"], false);
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.png"));
    // A bad pattern is refused by the argument parser.
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "9by6".as_ref()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("pattern"));
}
