//! `etlcal.calibration/1`: one validator for the reader, the text parser and the writer,
//! and no silent thermal surface. The fixture is the demo's calibration
//! (fixtures/service/SOURCE.md).

use std::path::{Path, PathBuf};

use etl_formats::{Calibration, ErrorKind};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/service/calibration.json")
}

/// A way to spoil a good calibration, named by the field it spoils.
type Spoil = (&'static str, fn(&mut Calibration));

#[test]
fn the_reader_the_parser_and_the_writer_apply_the_same_checks() {
    let good = Calibration::load(&fixture()).unwrap();
    let text = std::fs::read_to_string(fixture()).unwrap();
    assert_eq!(Calibration::parse(&text, &fixture()).unwrap(), good);
    let dir = tempfile::tempdir().unwrap();
    let bads: [Spoil; 4] = [
        ("image_size", |c| c.image_size = [0, 1458]),
        ("e_com_range_ma", |c| c.e_com_range_ma = [225.0, 80.0]),
        ("rms_reprojection_px", |c| c.rms_reprojection_px = -1.0),
        ("kf_x", |c| c.kf_x[1] = f64::INFINITY),
    ];
    for (what, spoil) in bads {
        let mut c = good.clone();
        spoil(&mut c);
        let out = dir.path().join(format!("{what}.json"));
        let e = c.save(&out).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{what}: {e}");
        assert!(!out.exists(), "{what}: a refused calibration was written");
        // The same file, written past the check, is refused by both readers.
        etl_formats::write_json(&out, &c).unwrap();
        assert_eq!(Calibration::load(&out).unwrap_err().kind(), ErrorKind::Parse, "{what}");
        let text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(Calibration::parse(&text, &out).unwrap_err().kind(), ErrorKind::Parse, "{what}");
    }
}

#[test]
fn a_calibration_without_a_thermal_surface_gets_none_assumed() {
    let mut c = Calibration::load(&fixture()).unwrap();
    assert!(c.thermal_surface().is_ok());
    c.thermal = None;
    let e = c.thermal_surface().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidInput);
    assert!(e.to_string().contains("no temperature compensation"), "{e}");
}

/// The temperature trust policy (issue 17): inside the calibrated ranges the camera is
/// returned; outside, the quantity that left its range is named; extrapolation is explicit
/// and marked.
#[test]
fn the_camera_at_a_setting_refuses_outside_the_calibrated_ranges() {
    use etl_formats::Trust;
    let c = Calibration::load(&fixture()).unwrap();
    let at = c.at(150.0, 35.0, Trust::Refuse).unwrap();
    assert!(!at.extrapolated());
    let e_com = etl_formats::ThermalSurface::PAPER.e_com_ma(150.0, 35.0).unwrap();
    assert_eq!(at.e_com_ma(), e_com);
    for (e_in, t, what) in [(150.0, 80.0, "temperature_c"), (260.0, 30.0, "e_in_ma"), (60.0, 30.0, "e_com_ma")] {
        let e = c.at(e_in, t, Trust::Refuse).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Precondition, "{e}");
        assert!(e.to_string().contains(what), "{what}: {e}");
        assert!(!e.to_string().contains('\n'));
        let x = c.at(e_in, t, Trust::Extrapolate).unwrap();
        assert!(x.extrapolated(), "{what}");
    }
}

/// A file written before the thermal ranges were kept stays readable; its camera refuses
/// (E_in, T) lookups unless extrapolation is asked for, and says why.
#[test]
fn an_older_thermal_part_without_ranges_is_read_and_not_trusted() {
    use etl_formats::Trust;
    let text = std::fs::read_to_string(fixture()).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let coefficients = v["thermal"]["coefficients"].clone();
    v["thermal"] = serde_json::json!({ "coefficients": coefficients });
    let old = Calibration::parse(&v.to_string(), &fixture()).unwrap();
    assert!(old.thermal.as_ref().unwrap().t_range_c.is_none());
    let e = old.at(150.0, 35.0, Trust::Refuse).unwrap_err();
    assert!(e.to_string().contains("no calibrated ranges"), "{e}");
    assert!(old.at(150.0, 35.0, Trust::Extrapolate).unwrap().flags().temperature);
    // Written back, it is the same file: nothing invented.
    let back: serde_json::Value = serde_json::to_value(&old).unwrap();
    assert_eq!(back["thermal"], serde_json::json!({ "coefficients": coefficients }));
}

#[test]
fn a_bad_thermal_part_is_refused_by_the_reader() {
    let good = Calibration::load(&fixture()).unwrap();
    let spoils: [Spoil; 3] = [
        ("t_range_c", |c| c.thermal.as_mut().unwrap().t_range_c = Some([37.0, 27.0])),
        ("e_in_range_ma", |c| c.thermal.as_mut().unwrap().e_in_range_ma = Some([f64::NAN, 1.0])),
        ("rms_ma", |c| c.thermal.as_mut().unwrap().rms_ma = Some(-1.0)),
    ];
    for (what, spoil) in spoils {
        let mut c = good.clone();
        spoil(&mut c);
        let text = serde_json::to_string(&c).unwrap();
        let e = Calibration::parse(&text, &fixture()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{what}: {e}");
    }
}
