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

/// A calibration whose only uncertain numbers are u0 (std 2 px) and v0 (0.5 px),
/// correlated by 0.3, with the covariance that says so.
fn with_principal_point_covariance() -> Calibration {
    let mut c = Calibration::load(&fixture()).unwrap();
    c.std = etl_formats::calibration::ModelStd::zero(&etl_core::calib::Layout::PAPER);
    c.std.principal_point = [2.0, 0.5];
    let mut cov = [[0.0; etl_core::calib::params::MAX_PARAMS]; etl_core::calib::params::MAX_PARAMS];
    cov[14][14] = 4.0;
    cov[15][15] = 0.25;
    cov[14][15] = 0.3 * 2.0 * 0.5;
    cov[15][14] = 0.3 * 2.0 * 0.5;
    c.set_covariance(&cov).unwrap();
    c
}

#[test]
fn an_older_file_without_a_covariance_stays_valid_and_says_it_has_none() {
    let c = Calibration::load(&fixture()).unwrap();
    assert!(c.covariance.is_none());
    assert!(!serde_json::to_string(&c).unwrap().contains("covariance"));
    let e = c.projection_std([0.0, 0.0, 40.0], 150.0, etl_formats::Trust::Refuse).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidInput);
    assert!(e.to_string().contains("no covariance"), "{e}");
}

/// The covariance survives the file exactly, its diagonal is std squared, and the pixel's
/// uncertainty from (u0, v0) alone is (u0, v0)'s own: std (2, 0.5) px, covariance 0.3.
#[test]
fn the_covariance_round_trips_and_gives_the_projection_std() {
    let c = with_principal_point_covariance();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal.json");
    c.save(&out).unwrap();
    let back = Calibration::load(&out).unwrap();
    assert_eq!(back, c);
    let m = back.covariance_matrix().unwrap();
    assert_eq!((m[14][14], m[15][15], m[14][15]), (4.0, 0.25, 0.3));
    let p = back.projection_std([5.0, 4.0, 40.0], 150.0, etl_formats::Trust::Refuse).unwrap();
    assert_eq!(p.std_px, [2.0, 0.5]);
    assert_eq!(p.covariance_px2, [[4.0, 0.3], [0.3, 0.25]]);
    // The range policy holds here too: E_com far outside 80..225 mA is named.
    let e = back.projection_std([5.0, 4.0, 40.0], 400.0, etl_formats::Trust::Refuse).unwrap_err();
    assert!(e.to_string().contains("e_com_ma = 400 is outside [75, 230]"), "{e}");
    assert!(back.projection_std([5.0, 4.0, 40.0], 240.0, etl_formats::Trust::Extrapolate).is_ok());
}

#[test]
fn a_bad_covariance_is_refused_naming_it_and_nothing_is_written() {
    let good = with_principal_point_covariance();
    let dir = tempfile::tempdir().unwrap();
    type Bad = (&'static str, &'static str, fn(&mut Vec<Vec<f64>>));
    let bads: [Bad; 7] = [
        ("rows", "it has 24 rows", |c| {
            c.pop();
        }),
        ("row-length", "row 3 has 24 numbers", |c| {
            c[3].pop();
        }),
        ("nan", "covariance[2][5] = NaN must be finite", |c| c[2][5] = f64::NAN),
        ("asymmetric", "not symmetric: [14][15] = 0.4, [15][14] = 0.3", |c| c[14][15] = 0.4),
        ("negative", "covariance[0][0] = -1 (variance of om1) must be finite and >= 0", |c| c[0][0] = -1.0),
        ("not-std", "variance of u0) is not std squared (std 2)", |c| c[14][14] = 4.5),
        ("cauchy-schwarz", "exceeds sqrt(c_ii c_jj) = 1 (u0, v0)", |c| {
            c[14][15] = 1.5;
            c[15][14] = 1.5;
        }),
    ];
    for (name, message, spoil) in bads {
        let mut c = good.clone();
        spoil(c.covariance.as_mut().unwrap());
        let out = dir.path().join(format!("{name}.json"));
        let e = c.save(&out).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{name}: {e}");
        let text = e.to_string();
        assert!(text.contains(message) && text.contains("covariance"), "{name}: {text}");
        assert_eq!(text.lines().count(), 1, "{name}: {text}");
        assert!(!out.exists(), "{name}: a refused calibration was written");
    }
}

/// `covariance_noise` (what the covariance accounts for) round-trips, is optional, and a
/// bad one is refused naming its field, by the writer and by the reader, with nothing
/// written.
#[test]
fn covariance_noise_round_trips_and_a_bad_one_is_refused_naming_the_field() {
    use etl_formats::calibration::CovarianceNoise;
    let dir = tempfile::tempdir().unwrap();
    let mut good = with_principal_point_covariance();
    good.covariance_noise =
        Some(CovarianceNoise { sigma_px: 0.2, sigma_z_mm: Some(0.01), sigma_e_ma: Some(0.4), sigma_p_dpt: None });
    let path = dir.path().join("good.json");
    good.save(&path).unwrap();
    assert_eq!(Calibration::load(&path).unwrap(), good);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"covariance_noise\": {\n    \"sigma_px\": 0.2,"), "{text}");
    let bads: [(&str, CovarianceNoise, &str); 4] = [
        (
            "px",
            CovarianceNoise { sigma_px: -0.1, sigma_z_mm: None, sigma_e_ma: None, sigma_p_dpt: None },
            "covariance_noise.sigma_px = -0.1",
        ),
        (
            "px-nan",
            CovarianceNoise { sigma_px: f64::NAN, sigma_z_mm: None, sigma_e_ma: None, sigma_p_dpt: None },
            "covariance_noise.sigma_px = NaN",
        ),
        (
            "z",
            CovarianceNoise { sigma_px: 0.2, sigma_z_mm: Some(0.0), sigma_e_ma: Some(0.4), sigma_p_dpt: None },
            "covariance_noise.sigma_z_mm = 0",
        ),
        (
            "e",
            CovarianceNoise { sigma_px: 0.2, sigma_z_mm: Some(0.01), sigma_e_ma: Some(-1.0), sigma_p_dpt: None },
            "covariance_noise.sigma_e_ma = -1",
        ),
    ];
    for (name, noise, message) in bads {
        let mut c = good.clone();
        c.covariance_noise = Some(noise);
        let out = dir.path().join(format!("{name}.json"));
        let e = c.save(&out).unwrap_err();
        assert!(e.to_string().contains(message) && e.to_string().lines().count() == 1, "{name}: {e}");
        assert!(!out.exists(), "{name}: a refused calibration was written");
    }
    // The reader refuses the same (a file edited by hand).
    let edited = text.replace("\"sigma_px\": 0.2", "\"sigma_px\": -3");
    let bad = dir.path().join("edited.json");
    std::fs::write(&bad, edited).unwrap();
    let e = Calibration::load(&bad).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parse);
    assert!(e.to_string().contains("covariance_noise.sigma_px = -3"), "{e}");
}

/// The temperature trust policy: inside the calibrated ranges the camera is
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

/// Issue 19: the outliers and warnings of a calibration are optional fields, absent when
/// empty (older readers keep reading files without outliers), kept when present, and a
/// bad outlier entry is refused naming it, with nothing written.
#[test]
fn outliers_and_warnings_are_optional_round_trip_and_are_checked() {
    use etl_formats::calibration::Outlier;
    let good = Calibration::load(&fixture()).unwrap();
    assert!(good.outliers.is_empty() && good.warnings.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.json");
    good.save(&plain).unwrap();
    let text = std::fs::read_to_string(&plain).unwrap();
    assert!(!text.contains("outliers") && !text.contains("warnings"), "empty lists are written");
    let mut c = good.clone();
    c.outliers = vec![Outlier { view: 1, point: 7, residual_px: 412.5 }];
    c.warnings = vec!["1 of 2311 corners (0.04 %) are outliers".into()];
    let with = dir.path().join("with.json");
    c.save(&with).unwrap();
    assert_eq!(Calibration::load(&with).unwrap(), c);
    let n = good.views.len();
    let bads: [(&str, String, Outlier); 2] = [
        (
            "residual",
            "outliers[0].residual_px = -1 must be a number >= 0".into(),
            Outlier { view: 0, point: 0, residual_px: -1.0 },
        ),
        (
            "view",
            format!("outliers[0].view = {n} must name one of the {n} views"),
            Outlier { view: n, point: 0, residual_px: 9.0 },
        ),
    ];
    for (name, message, o) in bads {
        let mut c = good.clone();
        c.outliers = vec![o];
        let out = dir.path().join(format!("{name}.json"));
        let e = c.save(&out).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{name}: {e}");
        assert!(e.to_string().contains(&message), "{name}: {e}");
        assert_eq!(e.to_string().lines().count(), 1);
        assert!(!out.exists(), "{name}: a refused calibration was written");
    }
}

/// Issue 16: a file of the paper's model is written exactly as before the distortion
/// families (no `"distortion_model"`, kf of 4, distortion_a of 9), byte for byte.
#[test]
fn a_paper_model_file_is_written_byte_for_byte_as_before() {
    let text = std::fs::read_to_string(fixture()).unwrap();
    assert!(!text.contains("distortion_model"));
    let c = Calibration::load(&fixture()).unwrap();
    assert_eq!(c.distortion_model().unwrap(), etl_core::model::DistortionModel::Paper);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("again.json");
    c.save(&out).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), text);
    // And the model built from the file is the paper's layout.
    assert_eq!(c.model().unwrap().layout(), etl_core::calib::Layout::PAPER);
}

/// An opencv-family calibration with quintic focal polynomials and a covariance of its
/// 35 numbers round-trips exactly; its file names the family.
#[test]
fn an_opencv_family_calibration_round_trips() {
    use etl_core::calib::params::MAX_PARAMS;
    use etl_core::model::{CameraModel, FocalPoly};
    let mut model = CameraModel::strong_distortion_rig();
    model.kf_x = FocalPoly::new(&[1500.0, -1.96, 0.0056, -8.4e-6, 1e-10, -2e-13]).unwrap();
    model.kf_y = FocalPoly::new(&[1510.0, -1.96, 0.0056, -8.4e-6, 1e-10, -2e-13]).unwrap();
    let mut c = Calibration::from_model(&model, [1936, 1458], [80.0, 225.0]);
    let layout = model.layout();
    assert_eq!(layout.len(), 35);
    let s: Vec<f64> = (0..layout.len()).map(|i| 1e-3 * (i + 1) as f64).collect();
    c.std = etl_formats::calibration::ModelStd::from_params(&layout, &s);
    let mut cov = [[0.0; MAX_PARAMS]; MAX_PARAMS];
    for (i, si) in s.iter().enumerate() {
        cov[i][i] = si * si;
    }
    cov[3][34] = 0.5 * s[3] * s[34];
    cov[34][3] = cov[3][34];
    c.set_covariance(&cov).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opencv.json");
    c.save(&out).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("\"distortion_model\": \"opencv\""), "{text}");
    let back = Calibration::load(&out).unwrap();
    assert_eq!(back, c);
    assert_eq!(back.model().unwrap(), model);
    assert_eq!(back.covariance_matrix().unwrap()[3][34], cov[3][34]);
    assert_eq!(back.distortion_a.len(), 15);
}

/// A spoiled calibration: a name, the message it must give, the spoiling.
type Named = (&'static str, &'static str, fn(&mut Calibration));

/// Bad families and lengths are one-line errors naming the field, and nothing is
/// written.
#[test]
fn a_bad_family_or_length_is_refused_naming_the_field() {
    let good = Calibration::load(&fixture()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let bads: [Named; 6] = [
        ("family", "distortion_model = \"brown\" is not a distortion model", |c| {
            c.distortion_model = Some("brown".into())
        }),
        ("a-length", "distortion_a has 9 numbers: the opencv distortion model has 15", |c| {
            c.distortion_model = Some("opencv".into())
        }),
        ("a-short", "distortion_a has 8 numbers: the paper distortion model has 9", |c| {
            c.distortion_a.pop();
        }),
        ("kf-long", "kf_x has 7 numbers: a focal polynomial needs 2..=6", |c| {
            c.kf_x.extend([0.0, 0.0, 0.0]);
        }),
        ("kf-mismatch", "kf_y has 5 numbers and kf_x 4", |c| {
            c.kf_y.push(0.0);
        }),
        ("std-length", "std.distortion_a has 8 numbers", |c| {
            c.std.distortion_a.pop();
        }),
    ];
    for (name, message, spoil) in bads {
        let mut c = good.clone();
        spoil(&mut c);
        let out = dir.path().join(format!("{name}.json"));
        let e = c.save(&out).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parse, "{name}: {e}");
        let text = e.to_string();
        assert!(text.contains(message), "{name}: {text}");
        assert_eq!(text.lines().count(), 1, "{name}: {text}");
        assert!(!out.exists(), "{name}: a refused calibration was written");
        // The same text read back is refused by the parser too.
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(Calibration::parse(&json, &out).unwrap_err().kind(), ErrorKind::Parse, "{name}");
    }
}

/// Issue 26: `"temperature_compensation": "none"` says a calibration has no temperature
/// compensation. Absent (older files, files with a thermal part) nothing changes, byte for
/// byte; present, it round-trips; beside a thermal part, or another word, it is refused.
#[test]
fn temperature_compensation_none_is_optional_and_checked() {
    use etl_formats::calibration::{TemperatureCompensation, NO_TEMPERATURE_COMPENSATION};
    let text = std::fs::read_to_string(fixture()).unwrap();
    assert!(!text.contains("temperature_compensation"));
    let dir = tempfile::tempdir().unwrap();
    // An older file without a thermal part reads and writes as it was.
    let mut old = Calibration::load(&fixture()).unwrap();
    old.thermal = None;
    let old_path = dir.path().join("old.json");
    etl_formats::write_json(&old_path, &old).unwrap();
    let old_text = std::fs::read_to_string(&old_path).unwrap();
    let read = Calibration::load(&old_path).unwrap();
    assert_eq!(read.temperature_compensation, None);
    assert_eq!(read.temperature_compensation_warning(), None);
    read.save(&old_path).unwrap();
    assert_eq!(std::fs::read_to_string(&old_path).unwrap(), old_text);
    // "none" round-trips, and is used at a known E_com only.
    let mut none = old.clone();
    none.temperature_compensation = TemperatureCompensation::of(None);
    assert_eq!(TemperatureCompensation::of(old.thermal.as_ref()), Some(TemperatureCompensation::None));
    let path = dir.path().join("none.json");
    none.save(&path).unwrap();
    let written = std::fs::read_to_string(&path).unwrap();
    assert!(written.contains("\"temperature_compensation\": \"none\""), "{written}");
    let back = Calibration::load(&path).unwrap();
    assert_eq!(back, none);
    assert_eq!(back.temperature_compensation_warning(), Some(NO_TEMPERATURE_COMPENSATION));
    let at = back.at_e_com(150.0, etl_formats::Trust::Refuse).unwrap();
    let model = back.model().unwrap();
    assert_eq!(at.project([3.0, 4.5, 60.0]).unwrap(), model.project([3.0, 4.5, 60.0], 150.0).unwrap());
    assert!(at.e_in_ma().is_nan() && !at.extrapolated());
    let e = back.at_e_com(240.0, etl_formats::Trust::Refuse).unwrap_err().to_string();
    assert!(e.contains("e_com_ma = 240 is outside [75, 230]"), "{e}");
    assert!(back.at_e_com(240.0, etl_formats::Trust::Extrapolate).unwrap().extrapolated());
    assert!(back.at(150.0, 30.0, etl_formats::Trust::Refuse).unwrap_err().to_string().contains("at_e_com"));
    // Beside a thermal part: refused by the writer and by the reader.
    let mut both = Calibration::load(&fixture()).unwrap();
    both.temperature_compensation = Some(TemperatureCompensation::None);
    let bad = dir.path().join("both.json");
    let e = both.save(&bad).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parse);
    assert!(
        e.to_string().contains("temperature_compensation = \"none\" but the calibration has a thermal part"),
        "{e}"
    );
    assert!(!bad.exists());
    // Another word is not a value of the field.
    let word = written.replace("\"temperature_compensation\": \"none\"", "\"temperature_compensation\": \"partial\"");
    let e = Calibration::parse(&word, &bad).unwrap_err().to_string();
    assert!(e.contains("partial") && e.contains("none"), "{e}");
}

/// A calibration with a moving centre (Eq. C1-C3): its `"centre"` round-trips, and the
/// camera at a setting has the principal point of that setting.
fn with_centre() -> Calibration {
    let mut c = Calibration::load(&fixture()).unwrap();
    let pp = c.principal_point;
    c.centre = Some(etl_formats::calibration::CentreField {
        dz_mm: vec![0.0, -0.006, 1.2e-5],
        principal_point_px: vec![vec![pp[0], 0.02], vec![pp[1], -0.01]],
    });
    c.std.centre = Some(etl_formats::calibration::CentreField {
        dz_mm: vec![0.0, 1e-4, 1e-7],
        principal_point_px: vec![vec![c.std.principal_point[0], 1e-3], vec![c.std.principal_point[1], 1e-3]],
    });
    c.covariance = None;
    c
}

#[test]
fn a_moving_centre_round_trips_and_moves_the_principal_point() {
    let c = with_centre();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.json");
    c.save(&out).unwrap();
    let back = Calibration::load(&out).unwrap();
    assert_eq!(back, c);
    let m = back.model().unwrap();
    assert_eq!(m.layout().len(), 29);
    let e = 150.0;
    let k = back.at_e_com(e, etl_core::runtime::Trust::Refuse).unwrap();
    let want = [c.principal_point[0] + 0.02 * e, c.principal_point[1] - 0.01 * e];
    let got = m.intrinsics(e).unwrap();
    assert!((got.u0 - want[0]).abs() < 1e-9 && (got.v0 - want[1]).abs() < 1e-9, "{got:?}");
    assert_eq!(k.e_com_ma(), e);
    // A file without the field reads as the fixed centre, as before.
    assert!(Calibration::load(&fixture()).unwrap().model().unwrap().centre.is_none());
}

#[test]
fn a_bad_centre_is_refused_naming_the_field_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let bads: [Spoil; 5] = [
        ("centre.dz_mm has 2 numbers", |c| {
            c.centre.as_mut().unwrap().dz_mm.pop();
        }),
        ("centre.dz_mm[0] = 0.5 must be 0", |c| c.centre.as_mut().unwrap().dz_mm[0] = 0.5),
        ("centre.principal_point_px must be [[u0, u1], [v0, v1]]", |c| {
            c.centre.as_mut().unwrap().principal_point_px[1].push(0.0);
        }),
        ("centre.principal_point_px[0][0]", |c| c.centre.as_mut().unwrap().principal_point_px[0][0] += 1.0),
        ("std.centre.dz_mm has 4 numbers", |c| c.std.centre.as_mut().unwrap().dz_mm.push(0.0)),
    ];
    for (i, (message, spoil)) in bads.into_iter().enumerate() {
        let mut c = with_centre();
        spoil(&mut c);
        let out = dir.path().join(format!("{i}.json"));
        let e = c.save(&out).unwrap_err();
        let text = e.to_string();
        assert!(text.contains(message), "{message}: {text}");
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(!out.exists(), "{message}: a refused calibration was written");
        // The reader refuses the same text.
        let json = serde_json::to_string(&c).unwrap();
        assert!(Calibration::parse(&json, Path::new("c.json")).is_err(), "{message}");
    }
    // A moving centre's std without the centre: the lengths differ.
    let mut c = with_centre();
    c.centre = None;
    assert!(c.save(&dir.path().join("x.json")).unwrap_err().to_string().contains("std"), "std.centre alone");
}

/// The point seen at a pixel, at a distance or in its direction: with the covariance on
/// (u0, v0) alone every such point's std is (u0, v0)'s own; a distance that is not a finite
/// number > 0, a file without a covariance and a current outside the range are refused.
#[test]
fn pixel_projection_std_refuses_bad_distances_and_passes_the_principal_point() {
    let c = with_principal_point_covariance();
    let refuse = etl_formats::Trust::Refuse;
    for d in [Some(40.0), Some(1e6), None] {
        let p = c.pixel_projection_std([300.0, 1200.0], 150.0, d, refuse).unwrap();
        assert!((p.std_px[0] - 2.0).abs() < 1e-12 && (p.std_px[1] - 0.5).abs() < 1e-12, "{d:?}: {:?}", p.std_px);
    }
    for d in [0.0, -3.0, f64::NAN, f64::INFINITY] {
        let e = c.pixel_projection_std([300.0, 1200.0], 150.0, Some(d), refuse).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput);
        assert!(e.to_string().contains("must be a finite number > 0"), "{e}");
    }
    let e = c.pixel_projection_std([300.0, 1200.0], 400.0, None, refuse).unwrap_err();
    assert!(e.to_string().contains("e_com_ma = 400 is outside [75, 230]"), "{e}");
    let e =
        Calibration::load(&fixture()).unwrap().pixel_projection_std([300.0, 1200.0], 150.0, None, refuse).unwrap_err();
    assert!(e.to_string().contains("no covariance"), "{e}");
}

/// A calibration made a focal-power one writes no key in mA: the range, the views' setting
/// and correction, the focus law and the noise in dpt; it reads back the same. A file
/// mixing the two kinds is refused naming what is wrong, and nothing is written.
#[test]
fn a_focal_power_calibration_names_its_keys_in_dpt_and_a_mix_is_refused() {
    let mut good = Calibration::load(&fixture()).unwrap();
    good.thermal = None;
    // The fixture predates the focus law and the noise: a law of 15 views and the paper's.
    let samples: Vec<etl_core::focus::FocusSample> = (0..15)
        .map(|k| etl_core::focus::FocusSample { e_com_ma: 80.0 + 10.0 * k as f64, distance_mm: 120.0 - 5.0 * k as f64 })
        .collect();
    good.focus_law = Some(etl_core::focus::FocusLaw::fit(&samples).unwrap());
    good.covariance_noise = Some(etl_formats::calibration::CovarianceNoise {
        sigma_px: 0.2,
        sigma_z_mm: Some(0.01),
        sigma_e_ma: Some(0.4),
        sigma_p_dpt: None,
    });
    // Its numbers are a current calibration's; the range, as a focal power's would be.
    good.e_com_range_ma = [12.4, 18.8];
    let fp = good.clone().into_focal_power(Some([25.0, 35.0]));
    let text = serde_json::to_string(&fp).unwrap();
    for key in ["e_com_range_ma", "e_com_ma", "de_ma", "coefficients_ma", "rms_ma", "sigma_e_ma"] {
        assert!(!text.contains(&format!("\"{key}\"")), "{key} in {text:.400}");
    }
    for key in ["focal_power_range_dpt", "focal_power_dpt", "de_dpt", "coefficients_dpt", "rms_dpt"] {
        assert!(text.contains(&format!("\"{key}\"")), "{key} missing");
    }
    let back = Calibration::parse(&text, Path::new("fp.json")).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), text, "it reads back the same (NaN marks what is absent)");
    assert_eq!(back.setting_range(), good.e_com_range_ma);
    let mixed = text.replacen("\"rms_dpt\"", "\"rms_ma\"", 1);
    let err = Calibration::parse(&mixed, Path::new("fp.json")).unwrap_err().to_string();
    assert!(err.contains("not a mix"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let spoils: [Spoil; 3] = [
        ("thermal part", |c| c.thermal = Calibration::load(&fixture()).unwrap().thermal),
        ("e_com_ma", |c| c.views[2].e_com_ma = 150.0),
        ("focal_power_t_range_c", |c| c.focal_power_t_range_c = Some([35.0, 25.0])),
    ];
    for (what, spoil) in spoils {
        let mut c = fp.clone();
        spoil(&mut c);
        let path = dir.path().join("c.json");
        let err = c.save(&path).unwrap_err().to_string();
        assert!(err.contains(what), "{what}: {err}");
        assert!(!path.exists());
    }
}
