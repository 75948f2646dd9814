//! ChArUco detection on images, for profilers and for `benches/charuco_opencv.py` before a
//! release build of the `etlcal` binary is at hand: prints what `etlcal detect --board FILE
//! --json` prints (`{"images": [{"path", "found", "error"?, "corners_px", "ids"}]}`).
//!
//! `charuco_detect BOARD.json IMAGE... [--repeat N]` (the board: `{"squares", "square_mm",
//! "marker_mm", "dictionary"}` of an `etlcal.board/1` ChArUco file).
use etl_core::board::{CharucoBoard, Dictionary};
use etl_image::charuco::detect_charuco_file;
use serde_json::{json, Value};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repeat = args.iter().position(|a| a == "--repeat").and_then(|i| args.get(i + 1)?.parse().ok()).unwrap_or(1);
    let files: Vec<&String> = args.iter().filter(|a| !a.starts_with("--") && a.parse::<usize>().is_err()).collect();
    let Some((board_path, images)) = files.split_first() else {
        eprintln!("usage: charuco_detect BOARD.json IMAGE... [--repeat N]");
        std::process::exit(2);
    };
    let spec: Value = serde_json::from_str(&std::fs::read_to_string(board_path).expect("board file")).expect("JSON");
    let squares =
        [spec["squares"][0].as_u64().expect("squares") as u32, spec["squares"][1].as_u64().expect("squares") as u32];
    let dict = Dictionary::by_name(spec["dictionary"].as_str().expect("dictionary")).expect("a known dictionary");
    let board = CharucoBoard::new(
        squares,
        spec["square_mm"].as_f64().expect("square_mm"),
        spec["marker_mm"].as_f64().expect("marker_mm"),
        dict,
    )
    .expect("a valid board");
    let mut out = Vec::new();
    for path in images {
        let t0 = std::time::Instant::now();
        let mut r = detect_charuco_file(path.as_ref(), &board);
        for _ in 1..repeat {
            r = detect_charuco_file(path.as_ref(), &board);
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / repeat as f64;
        out.push(match r {
            Ok(d) => json!({"path": path, "found": true, "corners_px": d.corners_px, "ids": d.ids, "ms": ms, "markers": d.markers.iter().map(|m| (m.id, m.corners_px[0])).collect::<Vec<_>>()}),
            Err(e) => json!({"path": path, "found": false, "error": e.to_string(), "corners_px": [], "ids": [], "ms": ms}),
        });
    }
    println!("{}", json!({ "images": out }));
}
