//! The fuzz targets' committed corpora (`fuzz/corpus/<target>/`), replayed on stable by an
//! ordinary `cargo test`: every input that once found a bug (and the seeds) runs through
//! the same body as under `cargo +nightly fuzz run <target>` (`fuzz/src/bodies.rs`), so a
//! regression fails here, in CI, without nightly.

use std::path::Path;

#[path = "../../../fuzz/src/bodies.rs"]
mod bodies;

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
fn image_detect_corpus() {
    replay("image_detect", bodies::image_detect);
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
