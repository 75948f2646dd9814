//! The fuzz targets' committed corpora (`fuzz/corpus/<target>/`), replayed on stable by an
//! ordinary `cargo test`: every input that once found a bug (and the seeds) runs through
//! the same body as under `cargo +nightly fuzz run <target>` (`fuzz/src/bodies.rs`), so a
//! regression fails here, in CI, without nightly.

use std::path::Path;

use super::bodies;

/// Runs `body` on every file of `fuzz/corpus/<target>/`; there must be at least one.
fn replay(target: &str, body: fn(&[u8])) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus").join(target);
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        let data = std::fs::read(&path).unwrap();
        let outcome = std::panic::catch_unwind(|| body(&data));
        assert!(outcome.is_ok(), "{target}: {} fails", path.display());
        n += 1;
    }
    assert!(n > 0, "{target}: empty corpus");
}

#[test]
fn json_readers_corpus() {
    replay("json_readers", bodies::json_readers);
}

#[test]
fn text_readers_corpus() {
    replay("text_readers", bodies::text_readers);
}

#[test]
fn image_detect_corpus() {
    replay("image_detect", bodies::image_detect);
}

#[test]
fn charuco_detect_corpus() {
    replay("charuco_detect", bodies::charuco_detect);
}

#[test]
fn board_parser_corpus() {
    replay("board_parser", bodies::board_parser);
}

#[test]
fn calibrate_observations_corpus() {
    replay("calibrate_observations", bodies::calibrate_observations);
}

#[test]
fn thermal_inverse_corpus() {
    replay("thermal_inverse", bodies::thermal_inverse);
}

/// The calibration target starts from data that calibrate: the empty input (no edit) is the
/// noise-free paper rig, so the fuzzer's edits reach the whole pipeline.
#[test]
fn the_calibration_target_starts_from_data_that_calibrate() {
    assert!(bodies::calibrate_edited(&[]));
}

/// The ChArUco target starts from images in which its board is found (crops of the
/// fixtures, through each input path: 8-bit and 16-bit PNG, raw grey), so the fuzzer's
/// mutations reach the marker decoding and the corner refinement, not only the reader.
#[test]
fn the_charuco_target_starts_from_images_in_which_the_board_is_found() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/charuco_detect");
    for (seed, least) in [
        ("opencv-4x4_50-crop-half.png", 4),
        ("raw-opencv-4x4_50-crop-third.bin", 4),
        ("opencv-5x5_100-crop-half-16bit.png", 4),
        ("opencv-apriltag_36h11-crop-half.png", 4),
        ("deepcharuco-crop-grey.png", 1),
    ] {
        let found = bodies::charuco_found(&std::fs::read(dir.join(seed)).unwrap());
        assert!(found >= least, "{seed}: {found} corners, expected at least {least}");
    }
}

/// The board target starts from boards the inline reader accepts, of both types (the files'
/// and the datasets' forms), so the mutations reach the writer and the geometry checks.
#[test]
fn the_board_target_starts_from_boards_that_read() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/board_parser");
    let mut types = Vec::new();
    for seed in ["charuco-12x9-5x5_100.json", "checkerboard-14x12.json", "inline-checkerboard-before-the-format.json"] {
        let board: etl_formats::board::Board = serde_json::from_slice(&std::fs::read(dir.join(seed)).unwrap()).unwrap();
        types.push(board.type_name());
    }
    assert_eq!(types, ["charuco", "checkerboard", "checkerboard"]);
}
