//! ChArUco detection on 1936 x 1458 views of a 12 x 9 board (1.5 mm squares of 150-200 px,
//! the board overflowing the frame; blur sigma 0.5, 1.5, 3 px; noise 2 grey levels), one
//! image per iteration, as `detect_charuco` is called on a decoded image (decoding excluded).
//!
//! The views are the very PNGs `benches/charuco_opencv.py` writes and times OpenCV's
//! `CharucoDetector` on (default `target/charuco-views`, or `ETLCAL_CHARUCO_VIEWS`):
//!
//! ```sh
//! /work/venv/bin/python benches/charuco_opencv.py --etlcal target/release/etlcal
//! cargo bench -p etl-image --features bench --bench charuco
//! ```
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::board::{CharucoBoard, Dictionary};
use etl_image::charuco::detect_charuco;

fn bench(c: &mut Criterion) {
    let dir = std::env::var_os("ETLCAL_CHARUCO_VIEWS")
        .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/charuco-views"), PathBuf::from);
    let board =
        CharucoBoard::new([12, 9], 1.5, 1.1, Dictionary::by_name("DICT_5X5_100").expect("dictionary")).expect("board");
    let mut g = c.benchmark_group("charuco_1936x1458_12x9");
    g.sample_size(20);
    for pose in 0..6 {
        for blur in ["0.5", "1.5", "3.0"] {
            let path = dir.join(format!("charuco_pose{pose}_blur{blur}.png"));
            let img = image::open(&path)
                .unwrap_or_else(|e| panic!("{}: {e} (run benches/charuco_opencv.py first)", path.display()))
                .to_luma8();
            g.bench_function(format!("pose{pose}_blur{blur}"), |b| {
                b.iter(|| detect_charuco(&img, &board).expect("found"))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
