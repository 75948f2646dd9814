//! Behaviour kept across the architecture move: the JSON of every case in
//! `fixtures/golden/cases.txt`, recorded by `scripts/golden-record.sh` with the binary of
//! before the move, is reproduced by this build, numbers to 1e-12 relative. Keys that
//! name a time or a temporary path (`seconds`, `out`) are not compared.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

const REL_TOL: f64 = 1e-12;
const IGNORED_KEYS: [&str; 2] = ["seconds", "out"];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where `a` and `b` differ (a JSON path and the two values), or None.
fn diff(a: &Value, b: &Value, at: &str) -> Option<String> {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64()?, y.as_f64()?);
            let scale = x.abs().max(y.abs());
            ((x - y).abs() > REL_TOL * scale).then(|| format!("{at}: {x} != {y}"))
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return Some(format!("{at}: length {} != {}", x.len(), y.len()));
            }
            x.iter().zip(y).enumerate().find_map(|(i, (x, y))| diff(x, y, &format!("{at}[{i}]")))
        }
        (Value::Object(x), Value::Object(y)) => {
            let keys = |m: &serde_json::Map<String, Value>| {
                m.keys().filter(|k| !IGNORED_KEYS.contains(&k.as_str())).cloned().collect::<Vec<_>>()
            };
            if keys(x) != keys(y) {
                return Some(format!("{at}: keys {:?} != {:?}", keys(x), keys(y)));
            }
            keys(x).iter().find_map(|k| diff(&x[k], &y[k], &format!("{at}.{k}")))
        }
        _ => (a != b).then(|| format!("{at}: {a} != {b}")),
    }
}

#[test]
fn every_golden_case_reproduces_its_recorded_json() {
    let root = root();
    let cases = std::fs::read_to_string(root.join("fixtures/golden/cases.txt")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let mut n = 0;
    for line in cases.lines().filter(|l| !l.trim().is_empty()) {
        let (name, args) = line.split_once('|').unwrap();
        let out = Command::new("sh")
            .arg("-c")
            .arg(format!("\"$bin\" {args}"))
            .env("bin", env!("CARGO_BIN_EXE_etlcal"))
            .env("tmp", tmp.path())
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let got: Value = serde_json::from_slice(&out.stdout).unwrap();
        let file = root.join(format!("fixtures/golden/{name}.json"));
        let want: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        if let Some(d) = diff(&got, &want, name) {
            panic!("{name} differs from {}: {d}", file.display());
        }
        n += 1;
    }
    assert_eq!(n, 10, "every case in cases.txt ran");
}

#[test]
fn the_comparison_sees_a_change_in_the_13th_digit_and_ignores_times() {
    let a: Value = serde_json::json!({"x": [1.0, 2.0], "seconds": 1.0});
    let b: Value = serde_json::json!({"x": [1.0, 2.0 * (1.0 + 1e-11)], "seconds": 9.0});
    let c: Value = serde_json::json!({"x": [1.0, 2.0 * (1.0 + 1e-14)], "seconds": 9.0});
    assert!(diff(&a, &b, "").is_some());
    assert!(diff(&a, &c, "").is_none());
}
