//! The wheel's build (maturin builds `etl-py` alone) reuses the artifacts of the test
//! build (`cargo test --workspace`, where the dev-dependencies' features are unified into
//! every crate) only if each crate the wheel needs has the same features in both: a crate
//! whose features differ is compiled again, with every crate above it (for serde, nearly
//! the whole tree: about two minutes of the test command on 2 cores). `etl-py`'s manifest
//! names the missing features; this test says when a dependency change makes the lists
//! differ again, and which entries to add.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// Package -> its enabled features, as `cargo tree` lists them for `args`.
fn features(args: &[&str]) -> BTreeMap<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new(env!("CARGO"))
        .current_dir(&root)
        .args(["tree", "--locked", "--offline", "--prefix", "none", "-f", "{p}|{f}"])
        .args(args)
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| l.trim_end_matches(" (*)").split_once('|'))
        .map(|(p, f)| (p.to_owned(), f.to_owned()))
        .collect()
}

#[test]
fn the_wheel_build_has_the_test_build_s_features() {
    let wheel = features(&["-p", "etl-py", "-e", "normal,build"]);
    let tests = features(&["--workspace", "-e", "normal,build,dev"]);
    let differ: Vec<String> = wheel
        .iter()
        .filter(|(p, f)| tests.get(*p).is_some_and(|t| t != *f))
        .map(|(p, f)| format!("{p}: the wheel has [{f}], the tests [{}]", tests[p]))
        .collect();
    assert!(wheel.len() > 50, "cargo tree listed {} packages", wheel.len());
    assert!(differ.is_empty(), "name the tests' features in crates/etl-py/Cargo.toml:\n{}", differ.join("\n"));
}
