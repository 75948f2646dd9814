//! `etlcal render` run as the built binary: the image and its corners file, the corners
//! against the model and against `etlcal detect` on the written image, and bad input (one
//! line, non-zero exit, nothing written).

use etl_core::model::CameraModel;
use serde_json::Value;

use super::common::etlcal;

#[test]
fn renders_an_image_whose_detected_corners_are_the_true_ones() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("b.png");
    let out = etlcal(&["render", "--out", img.to_str().unwrap(), "--e-com", "150", "--seed", "3", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let file: Value = serde_json::from_slice(&std::fs::read(dir.path().join("b.png.corners.json")).unwrap()).unwrap();
    assert_eq!(j, file);
    let corners = j["corners_px"].as_array().unwrap();
    assert_eq!(corners.len(), 168);
    // Corner (i, j) is the model's projection of (1.5 i, 1.5 j, z).
    let z = j["z_w_mm"].as_f64().unwrap();
    let p = CameraModel::paper_rig().project([1.5 * 3.0, 1.5 * 2.0, z], 150.0).unwrap();
    let c = &corners[2 * 14 + 3];
    assert!((c[0].as_f64().unwrap() - p[0]).abs() < 1e-9 && (c[1].as_f64().unwrap() - p[1]).abs() < 1e-9);
    // The detector finds them again to a few hundredths of a pixel.
    let det = etlcal(&["detect", img.to_str().unwrap(), "--pattern", "14x12", "--json"]);
    assert!(det.status.success());
    let d: Value = serde_json::from_slice(&det.stdout).unwrap();
    let found = d["images"][0]["corners_px"].as_array().unwrap();
    let in_image = j["in_image"].as_array().unwrap();
    if in_image.iter().all(|b| b.as_bool() == Some(true)) {
        let mut s = 0.0;
        for (a, b) in found.iter().zip(corners) {
            let (du, dv) =
                (a[0].as_f64().unwrap() - b[0].as_f64().unwrap(), a[1].as_f64().unwrap() - b[1].as_f64().unwrap());
            s += du * du + dv * dv;
        }
        let rms = (s / found.len() as f64).sqrt();
        assert!(rms < 0.03, "rms {rms}");
    }
}

#[test]
fn bad_input_fails_in_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("x.png");
    let p = img.to_str().unwrap();
    let bmp = dir.path().join("new/x.bmp");
    let jpg16 = dir.path().join("new/x.jpg");
    // Exit status 2: refused by the argument parser; 1: refused by the verb.
    for (args, needle, code) in [
        (vec!["render", "--out", p, "--bit-depth", "12"], "bit-depth", 1),
        (vec!["render", "--out", p, "--square=-1"], "square", 1),
        (vec!["render", "--out", p, "--pattern", "2x12"], "3", 2),
        (vec!["render", "--out", bmp.to_str().unwrap()], "use .png, .tif, .tiff, .jpg or .jpeg", 1),
        (vec!["render", "--out", jpg16.to_str().unwrap(), "--bit-depth", "16"], "JPEG is 8-bit only", 1),
        (vec!["render", "--out", p, "--e-com", "NaN"], "--e-com NaN mA is outside", 1),
        (vec!["render", "--out", p, "--aperture-mm", "NaN"], "--aperture-mm NaN mm is outside [0, 50] mm", 1),
        // The renderer's largest blur is the flag's largest: no blur quietly clamped.
        (vec!["render", "--out", p, "--blur-px", "64.5"], "--blur-px 64.5 px is outside [0, 64] px", 1),
        (vec!["render", "--out", p, "--noise", "1e308"], "--noise 1e308 grey levels is outside", 1),
    ] {
        let out = etlcal(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!img.exists(), "{args:?} wrote an image");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(code), "{args:?}");
    }
    // A refused extension is refused before any work: not even the directory is made.
    assert!(!dir.path().join("new").exists());
}

#[test]
fn writes_the_format_its_extension_names_and_creates_the_directory() {
    let dir = tempfile::tempdir().unwrap();
    // (file, bit depth, the format's magic bytes, grey levels the decoder must give back).
    for (name, depth, magic) in [
        ("a/b.png", "16", &b"\x89PNG"[..]),
        ("a/b.tif", "16", b"II*\0"),
        ("a/b.TIFF", "8", b"II*\0"),
        ("a/b.jpg", "8", b"\xff\xd8\xff"),
    ] {
        let path = dir.path().join(name);
        let out = etlcal(&["render", "--out", path.to_str().unwrap(), "--bit-depth", depth, "--noise", "0"]);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(magic), "{name}: starts {:02x?}", &bytes[..4]);
        let img = image::load_from_memory(&bytes).unwrap();
        assert_eq!((img.width(), img.height()), (CameraModel::PAPER_IMAGE_SIZE[0], CameraModel::PAPER_IMAGE_SIZE[1]));
        let want_16 = depth == "16";
        assert_eq!(matches!(img, image::DynamicImage::ImageLuma16(_)), want_16, "{name}: {:?}", img.color());
    }
    // The JPEG is found by the detector like the PNG.
    let det = etlcal(&["detect", dir.path().join("a/b.jpg").to_str().unwrap(), "--pattern", "14x12", "--json"]);
    assert!(det.status.success(), "{}", String::from_utf8_lossy(&det.stderr));
}

/// `--board FILE` renders a ChArUco board: at the near stage position at 225 mA it
/// overflows the frame, and the corners file lists the corners inside it with their ids,
/// each the model's projection of OpenCV's corner coordinates. A bad board file fails in
/// one line naming the field, and nothing is written.
#[test]
fn renders_a_charuco_board_from_its_file_with_the_visible_ids() {
    let dir = tempfile::tempdir().unwrap();
    let charuco = r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}"#;
    let board = dir.path().join("board.json");
    std::fs::write(&board, charuco).unwrap();
    let img = dir.path().join("c.png");
    let (b, i) = (board.to_str().unwrap(), img.to_str().unwrap());
    let out = etlcal(&["render", "--out", i, "--board", b, "--e-com", "225", "--z-mm", "2", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["board"]["type"], "charuco");
    let ids: Vec<u64> = j["ids"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    let px = j["corners_px"].as_array().unwrap();
    assert_eq!(ids.len(), px.len());
    // Part of the 14 x 12 corners only, in increasing id order.
    assert!(ids.len() > 20 && ids.len() < 168, "{}", ids.len());
    assert!(ids.windows(2).all(|w| w[0] < w[1]));
    let truth = CameraModel::paper_rig();
    for (&id, p) in ids.iter().zip(px) {
        let (c, r) = ((id % 14) as f64, (id / 14) as f64);
        let q = truth.project([1.5 * (c + 1.0), 1.5 * (r + 1.0), 2.0], 225.0).unwrap();
        let (u, v) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        assert!((u - q[0]).abs() < 1e-9 && (v - q[1]).abs() < 1e-9, "{id}");
        assert!((0.0..=1935.0).contains(&u) && (0.0..=1457.0).contains(&v), "{id}");
    }
    // Bad boards and flag conflicts: one line, nothing written.
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, charuco.replace("DICT_5X5_100", "DICT_5X5_10")).unwrap();
    let x = dir.path().join("x.png");
    for (args, needle, code) in [
        (vec!["--board", bad.to_str().unwrap()], "dictionary \"DICT_5X5_10\" is not one of OpenCV's", 1),
        (vec!["--board", "/nonexistent/board.json"], "/nonexistent/board.json", 1),
        (vec!["--board", b, "--pattern", "5x5"], "--pattern", 2),
    ] {
        let mut all = vec!["render", "--out", x.to_str().unwrap()];
        all.extend(args);
        let out = etlcal(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{all:?}: {err}");
        assert!(err.contains(needle), "{all:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!x.exists());
    }
}
