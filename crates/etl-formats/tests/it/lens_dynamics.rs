//! `etlcal.lens-dynamics/1`: the published fixture is `LensDynamics::PUBLISHED`, files
//! read back as written, and bad input (a number out of range, a missing or unknown key,
//! another format) is refused in one line naming the field, with nothing written.

use std::path::{Path, PathBuf};

use etl_core::physics::dynamics::LensDynamics;
use etl_formats::LensDynamicsFile;
use serde_json::{json, Value};

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/lens-dynamics/el-10-30-published.json")
}

fn good() -> Value {
    serde_json::from_str(&std::fs::read_to_string(fixture()).unwrap()).unwrap()
}

/// The message of loading `v` (it must fail), checked to be one line.
fn refused(v: &Value, dir: &Path) -> String {
    let path = dir.join("dynamics.json");
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    let e = LensDynamicsFile::load(&path).unwrap_err().to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn the_published_fixture_is_the_core_s_defaults_and_files_read_back_as_written() {
    let f = LensDynamicsFile::load(&fixture()).unwrap();
    assert_eq!(f.dynamics(), LensDynamics::PUBLISHED);
    assert!(f.source.as_deref().is_some_and(|s| s.contains("150 Hz")));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.json");
    let mine = LensDynamicsFile::new(&LensDynamics { hysteresis_ma: 1.25, ..LensDynamics::PUBLISHED }, None);
    mine.save(&out).unwrap();
    assert_eq!(LensDynamicsFile::load(&out).unwrap(), mine);
    assert!(!std::fs::read_to_string(&out).unwrap().contains("source"));
}

#[test]
fn each_bad_value_is_refused_naming_its_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("natural_frequency_hz", json!(0.0), "natural_frequency_hz"),
        ("damping", json!(-0.5), "damping"),
        ("creep_fraction", json!(0.75), "creep_fraction"),
        ("creep_tau_s", json!(0.001), "creep_tau_s"),
        ("hysteresis_ma", json!(60.0), "hysteresis_ma"),
        ("thermal_tau_s", json!(0.0), "thermal_tau_s"),
        ("self_heating_c_per_ma", json!(-0.01), "self_heating_c_per_ma"),
        ("damping", json!("0.3"), "damping"),
        ("extra", json!(1), "unknown field `extra`"),
        ("format", json!("etlcal.lens-dynamics/2"), "etlcal.lens-dynamics/2"),
    ];
    for (key, value, expected) in cases {
        let mut v = good();
        v[key] = value;
        let e = refused(&v, dir.path());
        assert!(e.contains(expected), "{key}: {e}");
    }
    let mut v = good();
    v.as_object_mut().unwrap().remove("hysteresis_ma");
    let e = refused(&v, dir.path());
    assert!(e.contains("missing field `hysteresis_ma`"), "{e}");
}

#[test]
fn a_refused_file_is_not_written_and_an_earlier_one_stays_whole() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.json");
    let fresh = LensDynamicsFile::new(&LensDynamics { damping: 20.0, ..LensDynamics::PUBLISHED }, None);
    let e = fresh.save(&out).unwrap_err().to_string();
    assert!(e.contains("damping") && !out.exists(), "{e}");
    std::fs::copy(fixture(), &out).unwrap();
    let before = std::fs::read(&out).unwrap();
    assert!(fresh.save(&out).is_err());
    assert_eq!(std::fs::read(&out).unwrap(), before);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "a temporary left behind");
}
