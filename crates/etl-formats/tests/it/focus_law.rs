//! The optional `"focus_law"` of `etlcal.calibration/1`: files without one stay valid and
//! are written byte for byte as before; a bad law is refused by the one validator; and the
//! focus functions go through the thermal surface and refuse what is out of range.

use std::path::{Path, PathBuf};

use etl_core::focus::{FocusLaw, FocusSample};
use etl_core::thermal::ThermalSurface;
use etl_formats::{Calibration, ErrorKind};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/service/calibration.json")
}

/// E_com = -40 + 14 V - 0.05 V^2 (V = 1000 / d) over 50..120 mm: 73..220 mA.
fn law() -> FocusLaw {
    let samples: Vec<FocusSample> = (0..15)
        .map(|k| {
            let d = 50.0 + 5.0 * k as f64;
            let v = 1000.0 / d;
            FocusSample { e_com_ma: -40.0 + 14.0 * v - 0.05 * v * v, distance_mm: d }
        })
        .collect();
    FocusLaw::fit(&samples).unwrap()
}

#[test]
fn a_file_without_a_focus_law_is_valid_and_written_as_before() {
    let text = std::fs::read_to_string(fixture()).unwrap();
    let c = Calibration::load(&fixture()).unwrap();
    assert!(c.focus_law.is_none());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.json");
    c.save(&out).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(!written.contains("focus_law"));
    // The same writer, the same bytes (the fixture is one of its files).
    assert_eq!(written, text);
    let e = c.focus_e_in(80.0, 27.0, etl_formats::Trust::Refuse).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidInput);
    assert!(e.to_string().contains("this calibration has no focus law"), "{e}");
    assert!(c
        .focus_distance_mm(150.0, 27.0, etl_formats::Trust::Refuse)
        .unwrap_err()
        .to_string()
        .contains("has no focus law"));
}

#[test]
fn the_law_round_trips_and_converts_through_the_thermal_surface() {
    let mut c = Calibration::load(&fixture()).unwrap();
    c.focus_law = Some(law());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.json");
    c.save(&out).unwrap();
    let back = Calibration::load(&out).unwrap();
    assert_eq!(back, c);
    let (d, t) = (80.0, 31.0);
    let e_in = back.focus_e_in(d, t, etl_formats::Trust::Refuse).unwrap();
    let v = 1000.0 / d;
    let e_com = -40.0 + 14.0 * v - 0.05 * v * v;
    let surface = back.thermal_surface().unwrap();
    assert!((surface.e_com_ma(e_in, t).unwrap() - e_com).abs() < 1e-8);
    assert_eq!(surface, ThermalSurface { coefficients: c.thermal.unwrap().coefficients });
    assert!((back.focus_distance_mm(e_in, t, etl_formats::Trust::Refuse).unwrap() - d).abs() < 1e-8);
}

#[test]
fn out_of_range_inputs_are_refused_naming_the_quantity() {
    let mut c = Calibration::load(&fixture()).unwrap();
    c.focus_law = Some(law());
    for (r, name) in [
        (c.focus_e_in(200.0, 27.0, etl_formats::Trust::Refuse), "distance_mm"),
        (c.focus_e_in(30.0, 27.0, etl_formats::Trust::Refuse), "distance_mm"),
        // The setting is checked by the one range policy (Calibration::at) first.
        (c.focus_distance_mm(260.0, 27.0, etl_formats::Trust::Refuse), "e_in_ma"),
        (c.focus_distance_mm(20.0, 27.0, etl_formats::Trust::Refuse), "e_in_ma"),
        (c.focus_e_in(80.0, 80.0, etl_formats::Trust::Refuse), "temperature_c = 80 is outside [26, 38]"),
        (c.focus_e_in(80.0, 300.0, etl_formats::Trust::Refuse), "temperature_c"),
        (c.focus_distance_mm(150.0, f64::NAN, etl_formats::Trust::Refuse), "temperature_c"),
        // Extrapolating in temperature leaves the law's own range in force.
        (c.focus_distance_mm(260.0, 27.0, etl_formats::Trust::Extrapolate), "e_com_ma"),
        (c.focus_e_in(80.0, 300.0, etl_formats::Trust::Extrapolate), "t_c"),
    ] {
        let e = r.unwrap_err();
        assert!(e.to_string().contains(name), "{name}: {e}");
        assert_eq!(e.to_string().lines().count(), 1);
    }
    c.thermal = None;
    assert!(c
        .focus_e_in(80.0, 27.0, etl_formats::Trust::Refuse)
        .unwrap_err()
        .to_string()
        .contains("no temperature compensation"));
}

/// A way to spoil a good law, named by what the error says.
type Spoil = (&'static str, fn(&mut FocusLaw));

#[test]
fn a_bad_focus_law_is_refused_and_nothing_is_written() {
    let good = Calibration::load(&fixture()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let spoils: [Spoil; 4] = [
        ("monotone", |l| l.coefficients_ma = [0.0, 10.0, -0.5]),
        ("distance_range_mm", |l| l.distance_range_mm = [120.0, 50.0]),
        ("rms_ma", |l| l.rms_ma = -1.0),
        ("coefficients_ma", |l| l.coefficients_ma[0] = f64::NAN),
    ];
    for (what, spoil) in spoils {
        let mut l = law();
        spoil(&mut l);
        let c = Calibration { focus_law: Some(l), ..good.clone() };
        let out = dir.path().join(format!("{what}.json"));
        let e = c.save(&out).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{what}: {e}");
        assert!(e.to_string().contains(what), "{what}: {e}");
        assert!(!out.exists(), "{what}: written");
    }
    // Unknown keys inside the law are refused like everywhere else.
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(fixture()).unwrap()).unwrap();
    let mut l = serde_json::to_value(law()).unwrap();
    l["offset_mm"] = serde_json::json!(1.0);
    v["focus_law"] = l;
    let e = Calibration::parse(&v.to_string(), Path::new("x.json")).unwrap_err();
    assert!(e.to_string().contains("unknown field"), "{e}");
}
