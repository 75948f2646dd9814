//! What the integration tests share.

use std::path::PathBuf;

/// The JPEG images of `fixtures/NAME` (the repository's, sources in its SOURCE.md), sorted
/// by name.
pub fn fixture_jpegs(name: &str) -> Vec<PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures").join(name);
    let mut images: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "jpg"))
        .collect();
    images.sort();
    images
}
