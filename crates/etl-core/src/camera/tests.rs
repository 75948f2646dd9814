use super::*;
use crate::thermal::{ThermalCalibration, ThermalSurface};

fn paper() -> Camera {
    Camera::new(
        CameraModel::paper_rig(),
        Some(ThermalTrust::from_calibration(&ThermalCalibration::PAPER)),
        [80.0, 225.0],
    )
    .unwrap()
}

#[test]
fn at_is_the_model_at_the_compensated_current() {
    let cam = paper();
    let at = cam.at(150.0, 32.0).unwrap();
    let e_com = ThermalSurface::PAPER.e_com_ma(150.0, 32.0).unwrap();
    assert_eq!(at.e_com_ma(), e_com);
    assert_eq!(*at.intrinsics(), CameraModel::paper_rig().intrinsics(e_com).unwrap());
    let w = [4.5, 6.0, 22.0];
    assert_eq!(at.project(w).unwrap(), CameraModel::paper_rig().project(w, e_com).unwrap());
    let px = at.project(w).unwrap();
    let ray = at.ray(px).unwrap();
    let s = (0..3).map(|i| (w[i] - ray.origin_mm[i]).powi(2)).sum::<f64>().sqrt();
    let back = ray.at(s);
    assert!((0..3).all(|i| (back[i] - w[i]).abs() < 1e-6), "{back:?}");
    assert!(!at.extrapolated());
}

/// Each quantity is named when it is the one out of range; the temperature first.
#[test]
fn out_of_range_names_the_quantity() {
    let cam = paper();
    let what = |r: Result<CameraAt>| match r {
        Err(Error::OutOfRange { what, .. }) => what,
        other => panic!("{other:?}"),
    };
    assert_eq!(what(cam.at(150.0, 80.0)), "temperature_c");
    assert_eq!(what(cam.at(300.0, 80.0)), "temperature_c");
    assert_eq!(what(cam.at(250.0, 30.0)), "e_in_ma");
    // E_in = 60 mA is inside the thermal range (40..240) but E_com ~ 60 is below 80 - 5.
    assert_eq!(what(cam.at(60.0, 30.0)), "e_com_ma");
    // Just inside the margins.
    assert!(cam.at(150.0, 37.9).is_ok());
    assert!(cam.at(150.0, 38.1).is_err());
    assert!(matches!(cam.at(f64::NAN, 30.0), Err(Error::NotFinite { .. })));
}

#[test]
fn extrapolation_is_explicit_and_marked() {
    let cam = paper();
    let at = cam.at_with(60.0, 40.0, Trust::Extrapolate).unwrap();
    assert_eq!(at.flags(), Extrapolated { temperature: true, e_in: false, e_com: true });
    // The operating domain still binds: 300 degC is not a lens temperature.
    assert!(matches!(cam.at_with(150.0, 300.0, Trust::Extrapolate), Err(Error::OutOfRange { .. })));
    let inside = cam.at_with(150.0, 30.0, Trust::Extrapolate).unwrap();
    assert!(!inside.extrapolated());
}

#[test]
fn unknown_ranges_and_missing_thermal() {
    let t = ThermalTrust { surface: ThermalSurface::PAPER, t_range_c: None, e_in_range_ma: None };
    let cam = Camera::new(CameraModel::paper_rig(), Some(t), [80.0, 225.0]).unwrap();
    assert!(matches!(cam.at(150.0, 30.0), Err(Error::InvalidArgument { .. })));
    assert!(cam.at_with(150.0, 30.0, Trust::Extrapolate).unwrap().flags().temperature);
    let bare = Camera::new(CameraModel::paper_rig(), None, [80.0, 225.0]).unwrap();
    assert!(matches!(bare.at(150.0, 30.0), Err(Error::InvalidArgument { .. })));
    let at = bare.at_e_com(150.0, Trust::Refuse).unwrap();
    assert_eq!(at.e_com_ma(), 150.0);
    assert!(bare.at_e_com(400.0, Trust::Refuse).is_err());
}

#[test]
fn the_constructor_checks_its_invariants() {
    let mut m = CameraModel::paper_rig();
    assert!(Camera::new(m, None, [225.0, 80.0]).is_err());
    assert!(Camera::new(m, None, [f64::NAN, 80.0]).is_err());
    m.kf_x[0] = f64::NAN;
    assert!(Camera::new(m, None, [80.0, 225.0]).is_err());
    let bad =
        ThermalTrust { t_range_c: Some([37.0, 27.0]), ..ThermalTrust::from_calibration(&ThermalCalibration::PAPER) };
    assert!(Camera::new(CameraModel::paper_rig(), Some(bad), [80.0, 225.0]).is_err());
}

#[test]
fn camera_is_send_sync_copy() {
    fn assert_bounds<T: Send + Sync + Copy>() {}
    assert_bounds::<Camera>();
    assert_bounds::<CameraAt>();
}
