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
