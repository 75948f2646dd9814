//! `etlcal.optics/1`: the fixture rigs read back; bad input (wrong lengths, unknown fields,
//! values out of range, singular optics, rays that miss a surface on their way to the stop)
//! is refused with one line naming the field, and a refused file is not written.

use std::path::{Path, PathBuf};

use etl_formats::optics::OpticsFile;
use serde_json::{json, Value};

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json")
}

fn good() -> Value {
    serde_json::from_str(&std::fs::read_to_string(fixture()).unwrap()).unwrap()
}

/// The message of loading `v` (it must fail), checked to be one line.
fn refused(v: &Value, dir: &Path) -> String {
    let path = dir.join("optics.json");
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    let e = OpticsFile::load(&path).unwrap_err().to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn the_fixture_rigs_read_and_write_back_unchanged() {
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let path = fixture().with_file_name(name);
        let f = OpticsFile::load(&path).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o.json");
        f.save(&out).unwrap();
        assert_eq!(OpticsFile::load(&out).unwrap(), f);
        assert!(f.paraxial_focus_distance_mm(80.0).unwrap() > f.paraxial_focus_distance_mm(225.0).unwrap());
    }
}

#[test]
fn each_bad_value_is_refused_naming_its_field() {
    type Spoil = fn(&mut Value);
    let cases: Vec<(Spoil, &str)> = vec![
        (|v| v["sensor"]["size_px"] = json!([1936]), "sensor.size_px: invalid length 1, expected an array of length 2"),
        (|v| v["etl"]["power_law_dpt"] = json!([8.3, 0.04, 0.0]), "etl.power_law_dpt[2]: trailing characters"),
        (|v| v["etl"]["membrane"] = json!(1), "unknown field `membrane`"),
        (|v| v["etl"]["liquid_index"] = json!(0.9), "etl.liquid_index 0.9  is outside [1.01, 3] "),
        (
            |v| v["prime"]["surfaces"][2]["thickness_mm"] = json!(-1.0),
            "prime.surfaces[2].thickness_mm -1 mm is outside [0, 1000] mm",
        ),
        (|v| v["prime"]["surfaces"][1]["radius_mm"] = json!(0.01), "prime.surfaces[1].radius_mm: a radius of 0.01 mm"),
        (|v| v["prime"]["stop"] = json!(2), "prime.stop: surface 2 is not a plane in air"),
        (|v| v["prime"]["stop"] = json!(9), "prime.stop 9 is not one of the 7 surfaces"),
        (|v| v["prime"]["surfaces"] = json!([]), "prime.surfaces: 1 to 64 surfaces, got 0"),
        (|v| v["sensor"]["pixel_pitch_mm"] = json!(0.0), "sensor.pixel_pitch_mm 0 mm is outside [0.0001, 0.1] mm"),
        (
            |v| v["tolerances"]["etl_tilt_deg"] = json!([0.0, 9.0]),
            "tolerances.etl_tilt_deg 9 deg is outside [-5, 5] deg",
        ),
        (|v| v["procedure"]["e_com_ma"] = json!([80, 90]), "procedure.e_com_ma: 3 to 1000 currents, got 2"),
        (|v| v["procedure"]["fan_rings"] = json!(0), "procedure.fan_rings 0: 1 to 32 rings"),
        (
            |v| v["procedure"]["board"]["inner_corners"] = json!([2, 12]),
            "procedure.board: invalid input: inner_corners",
        ),
        (|v| v["procedure"]["pixel_noise_px"] = json!(-0.1), "procedure.pixel_noise_px -0.1 px is outside [0, 100] px"),
        (|v| v["format"] = json!("etlcal.optics/2"), "etlcal.optics/2"),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (spoil, want) in cases {
        let mut v = good();
        spoil(&mut v);
        let e = refused(&v, dir.path());
        assert!(e.contains(want), "{want}\n{e}");
    }
}

/// An ETL of no power in front of a plane stop alone has no power at all.
#[test]
fn singular_optics_are_refused() {
    let mut v = good();
    v["etl"]["power_law_dpt"] = json!([0.0, 0.0]);
    v["prime"] = json!({"surfaces": [{"radius_mm": 0.0, "thickness_mm": 10.0, "index": 1.0, "semi_diameter_mm": 1.0}], "stop": 0});
    let dir = tempfile::tempdir().unwrap();
    let e = refused(&v, dir.path());
    assert!(e.contains("prime.surfaces: the optics are afocal at 0 mA (power 0 dpt): singular"), "{e}");
    // A sensor too close for anything in front to focus on it.
    let mut v = good();
    v["prime"]["surfaces"][6]["thickness_mm"] = json!(1.0);
    let e = refused(&v, dir.path());
    assert!(e.contains("prime.surfaces[6].thickness_mm: at 0 mA no object in front of the lens is in focus"), "{e}");
}

/// Rays filling the stop from the field's edge must pass every surface: a surface (or the
/// ETL's aperture) too small for them is named.
#[test]
fn rays_that_miss_a_surface_on_their_way_to_the_stop_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = good();
    v["prime"]["surfaces"][0]["semi_diameter_mm"] = json!(1.0);
    let e = refused(&v, dir.path());
    assert!(
        e.contains("prime.surfaces[0].semi_diameter_mm: at 0 mA the rays that fill the stop miss prime.surfaces[0]"),
        "{e}"
    );
    let mut v = good();
    v["etl"]["clear_semi_aperture_mm"] = json!(1.5);
    let e = refused(&v, dir.path());
    assert!(e.contains("etl.clear_semi_aperture_mm: at 0 mA the rays that fill the stop miss etl.membrane"), "{e}");
}

#[test]
fn a_refused_file_is_not_written() {
    let mut f = OpticsFile::load(&fixture()).unwrap();
    f.procedure.fan_rings = 0;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.json");
    let e = f.save(&out).unwrap_err().to_string();
    assert!(e.contains("procedure.fan_rings") && !out.exists(), "{e}");
}
