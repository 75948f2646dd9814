//! `etlcal board` run as the built binary: the SVG at true size (width and height in mm,
//! a viewBox in mm), the PNG at its dpi (exactly the board, its resolution recorded), and
//! bad input (one line, non-zero exit, nothing written). The comparison with OpenCV's
//! `CharucoBoard.generateImage` is crates/etl-py/tests/test_board.py.
use std::path::Path;

use serde_json::Value;

use super::common::etlcal;

const CHARUCO: &str = r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}"#;

fn board_file(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_owned()
}

#[test]
fn the_svg_is_at_true_size_and_the_png_at_its_dpi() {
    let dir = tempfile::tempdir().unwrap();
    let b = board_file(dir.path(), "b.json", CHARUCO);
    let svg = dir.path().join("new/b.svg");
    let out = etlcal(&["board", "--board", &b, "--out", svg.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    // 12 x 9 squares of 1.5 mm and a margin of one square (the default) each side.
    assert_eq!(
        (j["width_mm"].as_f64(), j["height_mm"].as_f64(), j["margin_mm"].as_f64()),
        (Some(21.0), Some(16.5), Some(1.5))
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains(r#"width="21mm" height="16.5mm" viewBox="0 0 21 16.5""#), "{}", &text[..300]);
    assert_eq!(text.matches("<path id=\"marker-").count(), 54);
    // The first black square starts at the margin, 1.5 mm in, and is 1.5 mm wide.
    assert!(text.contains(r#"d="M1.5 1.5h1.5v1.5h-1.5z"#));

    let png = dir.path().join("b.png");
    let out = etlcal(&["board", "--board", &b, "--out", png.to_str().unwrap(), "--dpi", "2540", "--margin-mm", "0.5"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("at 2540 dpi"));
    // 100 px per mm: (18 + 1) x (13.5 + 1) mm.
    let img = image::open(&png).unwrap().to_luma8();
    assert_eq!((img.width(), img.height()), (1900, 1450));
    assert_eq!(img.get_pixel(25, 25).0[0], 255); // margin
    assert_eq!(img.get_pixel(125, 125).0[0], 0); // square (0, 0)
                                                 // Marker 0 in square (1, 0): its border starts 0.2 mm into the square, at 220 px.
    assert_eq!(img.get_pixel(50 + 150 + 19, 50 + 60).0[0], 255);
    assert_eq!(img.get_pixel(50 + 150 + 21, 50 + 60).0[0], 0);
    let bytes = std::fs::read(&png).unwrap();
    let phys = bytes.windows(4).position(|w| w == b"pHYs").expect("a pHYs chunk");
    let ppm = u32::from_be_bytes(bytes[phys + 4..phys + 8].try_into().unwrap());
    assert_eq!((ppm, bytes[phys + 12]), (100_000, 1)); // pixels per metre
}

#[test]
fn bad_input_fails_in_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = board_file(dir.path(), "b.json", CHARUCO);
    let bad_dict = board_file(dir.path(), "d.json", &CHARUCO.replace("DICT_5X5_100", "DICT_5X5_99"));
    let big_marker = board_file(dir.path(), "m.json", &CHARUCO.replace("1.1", "1.5"));
    let small_dict = board_file(dir.path(), "s.json", &CHARUCO.replace("DICT_5X5_100", "DICT_5X5_50"));
    let zero = board_file(dir.path(), "z.json", &CHARUCO.replace("\"square_mm\": 1.5", "\"square_mm\": 0"));
    let negative = board_file(dir.path(), "n.json", &CHARUCO.replace("[12, 9]", "[12, -9]"));
    let out_dir = dir.path().join("out");
    let svg = out_dir.join("b.svg");
    let png = out_dir.join("b.png");
    let (s, p) = (svg.to_str().unwrap(), png.to_str().unwrap());
    let pdf = out_dir.join("b.pdf");
    for (args, needle, code) in [
        (vec!["--board", &good, "--out", pdf.to_str().unwrap()], "unsupported extension \"pdf\": use .svg", 1),
        (vec!["--board", &good, "--out", s, "--dpi", "300"], "--dpi 300 applies to a .png only", 1),
        (vec!["--board", &good, "--out", p, "--dpi", "0"], "--dpi 0 dpi is outside", 1),
        (vec!["--board", &good, "--out", p, "--margin-mm", "-1"], "--margin-mm -1 mm is outside", 1),
        (vec!["--board", &good, "--out", p, "--dpi", "1e9"], "--dpi 1e9 dpi is outside", 1),
        (vec!["--board", &good, "--out", p, "--dpi", "90000"], "at most 32768 px a side", 1),
        (vec!["--board", &bad_dict, "--out", s], "dictionary \"DICT_5X5_99\" is not one of OpenCV's", 1),
        (vec!["--board", &big_marker, "--out", s], "marker_mm must be smaller than square_mm", 1),
        (vec!["--board", &small_dict, "--out", s], "DICT_5X5_50 has 50 markers, the board 54", 1),
        (vec!["--board", &zero, "--out", s], "square_mm must be positive and finite (square_mm 0", 1),
        (vec!["--board", &negative, "--out", s], "squares [12, -9] must be whole numbers", 1),
        (vec!["--board", "/nonexistent/b.json", "--out", s], "/nonexistent/b.json", 1),
        (vec!["--board", &good, "--out", &good], "", 1),
        (vec!["--board", &good], "--out", 2),
    ] {
        let mut all = vec!["board"];
        all.extend(args);
        let out = etlcal(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{all:?}: {err}");
        assert!(err.contains(needle), "{all:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{all:?}: {err}");
        assert!(!out_dir.exists(), "{all:?} wrote something");
    }
    assert_eq!(std::fs::read_to_string(&good).unwrap(), CHARUCO);
}
