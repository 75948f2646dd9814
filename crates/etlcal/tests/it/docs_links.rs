//! Everything the README, the changelog, docs/ and the generated reports refer to is in the
//! repository: `scripts/check-links.py` (links, repository paths, no reference to material
//! outside the repository) over the documents and over a demo's and a study's freshly
//! written output.

use std::path::Path;
use std::process::Command;

#[test]
fn documents_and_generated_reports_refer_only_to_files_in_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let (demo, study) = (tmp.path().join("demo"), tmp.path().join("study"));
    for args in [
        vec!["demo", "--no-images", "--out", demo.to_str().unwrap()],
        vec!["study", "fig5", "--out", study.to_str().unwrap()],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_etlcal")).args(&args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
    let out = Command::new("python3")
        .arg(root.join("scripts/check-links.py"))
        .args([root.join("README.md"), root.join("CHANGELOG.md"), root.join("docs"), demo, study])
        .output()
        .expect("python3 runs the link checker");
    assert!(
        out.status.success(),
        "check-links found:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
