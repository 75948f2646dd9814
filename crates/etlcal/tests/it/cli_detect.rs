//! `etlcal detect` on real photographs (fixtures/detect/SOURCE.md): JSON per image, exit
//! status 1 and one stderr line per failed image (board not found, unreadable, missing),
//! the pattern parser.

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/detect")
}

#[test]
fn cli_prints_json_per_image_and_fails_on_any_failed_image() {
    let exe = env!("CARGO_BIN_EXE_etlcal");
    let good = fixtures().join("stereo_left01.jpg");
    let run = |args: &[&std::ffi::OsStr]| std::process::Command::new(exe).args(args).output().unwrap();
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "9x6".as_ref(), "--json".as_ref()]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"][0]["found"], true);
    assert_eq!(v["images"][0]["corners_px"].as_array().unwrap().len(), 54);
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    // A board not found fails the run (exit 1), listed with its reason, named on stderr.
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "10x6".as_ref(), "--json".as_ref()]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"][0]["found"], false);
    assert!(v["images"][0]["error"].as_str().unwrap().contains("board not found"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().collect::<Vec<_>>().len(), 1, "{err}");
    assert!(err.starts_with("etlcal: error: ") && err.contains("stereo_left01.jpg: board not found"), "{err}");
    // An unreadable file and a missing one among good ones: every image listed, exit 1,
    // one stderr line for each failed image and none for the good ones.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.png");
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\n truncated").unwrap();
    let missing = dir.path().join("missing.png");
    let out = run(&[
        "detect".as_ref(),
        good.as_os_str(),
        bad.as_os_str(),
        missing.as_os_str(),
        "--pattern".as_ref(),
        "9x6".as_ref(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let found: Vec<_> = v["images"].as_array().unwrap().iter().map(|i| i["found"].as_bool().unwrap()).collect();
    assert_eq!(found, [true, false, false]);
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(lines[0].starts_with("etlcal: error: ") && lines[0].contains("bad.png"), "{err}");
    assert!(lines[1].starts_with("etlcal: error: ") && lines[1].contains("missing.png"), "{err}");
    assert!(!err.contains("stereo_left01"), "{err}");
    // Without --json too: exit 1 and the failed image on stderr.
    let out = run(&["detect".as_ref(), missing.as_os_str(), "--pattern".as_ref(), "9x6".as_ref()]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(String::from_utf8_lossy(&out.stderr).lines().count(), 1);
    // A bad pattern is refused by the argument parser.
    let out = run(&["detect".as_ref(), good.as_os_str(), "--pattern".as_ref(), "9by6".as_ref()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("pattern") && err.contains("see etlcal detect --help"), "{err}");
}

/// `--board FILE`: a ChArUco board's corners with their ids (OpenCV's, as OpenCV finds them
/// on the fixture: fixtures/charuco/opencv.json), a checkerboard file like `--pattern` with
/// ids; a failed image named on stderr; a bad board file refused in one line; `--board` and
/// `--pattern` together, or neither, refused by the parser.
#[test]
fn board_file_gives_corners_with_ids() {
    let exe = env!("CARGO_BIN_EXE_etlcal");
    let run = |args: &[&std::ffi::OsStr]| std::process::Command::new(exe).args(args).output().unwrap();
    let charuco = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/charuco");
    let image = charuco.join("opencv_DICT_5X5_100.png");
    let dir = tempfile::tempdir().unwrap();
    let board = dir.path().join("board.json");
    std::fs::write(
        &board,
        r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [8, 6], "square_mm": 25, "marker_mm": 18, "dictionary": "DICT_5X5_100"}"#,
    )
    .unwrap();
    let photo = fixtures().join("stereo_left01.jpg");
    let out = run(&[
        "detect".as_ref(),
        image.as_os_str(),
        photo.as_os_str(),
        "--board".as_ref(),
        board.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1), "the checkerboard photograph holds no ChArUco board");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let reference: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(charuco.join("opencv.json")).unwrap()).unwrap();
    let opencv =
        &reference["images"].as_array().unwrap().iter().find(|e| e["file"] == "opencv_DICT_5X5_100.png").unwrap();
    let first = &v["images"][0];
    assert_eq!(first["found"], true);
    assert_eq!(first["ids"], opencv["ids"]);
    assert_eq!(first["corners_px"].as_array().unwrap().len(), 35);
    let second = &v["images"][1];
    assert_eq!((&second["found"], second["ids"].as_array().unwrap().len()), (&serde_json::json!(false), 0));
    assert!(second["error"].as_str().unwrap().contains("board not found"), "{second}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("stereo_left01.jpg: board not found"), "{err}");
    // Without --json: one line per corner, `id u v`.
    let out = run(&["detect".as_ref(), image.as_os_str(), "--board".as_ref(), board.as_os_str()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 36, "{text}");
    assert_eq!(lines[1].split_whitespace().count(), 3, "{text}");
    // A checkerboard file: the same corners as --pattern, ids 0..54.
    let checker = dir.path().join("checker.json");
    std::fs::write(
        &checker,
        r#"{"format": "etlcal.board/1", "type": "checkerboard", "inner_corners": [9, 6], "square_mm": 25}"#,
    )
    .unwrap();
    let a = run(&["detect".as_ref(), photo.as_os_str(), "--board".as_ref(), checker.as_os_str(), "--json".as_ref()]);
    let b = run(&["detect".as_ref(), photo.as_os_str(), "--pattern".as_ref(), "9x6".as_ref(), "--json".as_ref()]);
    assert!(a.status.success() && b.status.success());
    assert_eq!(a.stdout, b.stdout);
    let v: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    assert_eq!(v["images"][0]["ids"], serde_json::json!((0..54).collect::<Vec<u32>>()));
    // A bad board file: one line naming the field, exit 1, nothing on stdout.
    std::fs::write(
        &board,
        r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [8, 6], "square_mm": 25, "marker_mm": 18, "dictionary": "DICT_5X5_99"}"#,
    )
    .unwrap();
    let out = run(&["detect".as_ref(), image.as_os_str(), "--board".as_ref(), board.as_os_str(), "--json".as_ref()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("dictionary") && err.contains("DICT_5X5_99"), "{err}");
    assert!(out.stdout.is_empty());
    // --board with --pattern, or neither: the parser's one line, exit 2.
    for args in [
        vec![
            "detect".as_ref(),
            image.as_os_str(),
            "--board".as_ref(),
            checker.as_os_str(),
            "--pattern".as_ref(),
            "9x6".as_ref(),
        ],
        vec!["detect".as_ref(), image.as_os_str()],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("--board") && err.contains("see etlcal detect --help"), "{err}");
    }
}
