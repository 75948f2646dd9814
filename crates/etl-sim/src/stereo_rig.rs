//! A synthetic two-camera ETL rig with known truth (`etlcal.rig/1`, calibrations inline):
//! the ground truth of the rig's run-time tests (triangulation, the pose at settings,
//! rectification) and of the fixture `fixtures/rig/`.
//!
//! Both cameras are the strong-distortion lens on the paper rig's sensor
//! ([`CameraModel::strong_distortion_rig`], 1936 x 1458 px), in the family asked for (the
//! paper family keeps the focal polynomials and takes the paper rig's distortion), with
//! moving centres (Eq. C1-C3) and the paper's thermal part. Camera 1 sits 100 mm to the
//! right of camera 0 (centre (100, 1.5, -2) mm in camera 0's frame), turned 3.4 degrees
//! towards it: X_1 = R X_0 + T at the reference settings E_com = (150, 140) mA.
//!
//! Each calibration carries a diagonal covariance (standard deviations: 2e-4 of each focal
//! coefficient, 0.5 px on the principal point, 1e-3 of each distortion number, 5 % of each
//! centre number, none on the calibration's own board pose); the pose carries 1e-4 rad
//! and 0.1 mm per component.

use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_core::model::{CameraModel, DistortionA, DistortionModel, FocalPoly, MovingCentre};
use etl_formats::calibration::{Calibration, ModelStd, ThermalRef};
use etl_formats::rig::{RigCamera, RigExtrinsics, RigFile};

/// Camera 1's pose relative to camera 0 at the reference settings: Rodrigues vector, rad.
pub const ROTATION_RODRIGUES: [f64; 3] = [0.004, 0.06, 0.003];
/// Camera 1's centre in camera 0's frame, mm.
pub const CENTRE_1_MM: [f64; 3] = [100.0, 1.5, -2.0];
/// The reference settings (E_com of camera 0, of camera 1), mA.
pub const REFERENCE_SETTING_MA: [f64; 2] = [150.0, 140.0];

/// The two cameras' models (family `family`), with their moving centres.
pub fn models(family: DistortionModel) -> [CameraModel; 2] {
    let mut m0 = CameraModel::strong_distortion_rig();
    if family == DistortionModel::Paper {
        // The paper rig's numbers are for its 4850 px focal length; at 1300 px its
        // decentering would be 180 px at the corners: a barrel of k1 = -5e-8 / px^2
        // (-7 % at the corners) and decentering p1 = 2e-7, p2 = -1e-7 / px, varying with
        // w = 1 / f as the paper's (Eq. 18).
        m0.distortion_a = DistortionA::paper([-0.05, -2e-5, -3e-8, 0.0, 1e-4, 1.2e-7, 0.0, 0.0, -1e-7]);
    }
    m0.centre = Some(MovingCentre { dz_mm: [-6e-3, 1.2e-5], principal_point_slope_px: [0.01, -0.005] });
    let mut m1 = m0;
    let scale = |p: &FocalPoly, s: f64| {
        let mut q = *p;
        q.coefficients_mut()[0] *= s;
        q
    };
    (m1.kf_x, m1.kf_y) = (scale(&m0.kf_x, 1.02), scale(&m0.kf_y, 1.02));
    m1.principal_point = [955.0, 735.0];
    m1.centre = Some(MovingCentre { dz_mm: [4e-3, -1e-5], principal_point_slope_px: [-0.008, 0.004] });
    [m0, m1]
}

/// Camera 1's translation T = -R C_1, mm.
pub fn translation_mm() -> [f64; 3] {
    mat_vec(&rodrigues_to_matrix(ROTATION_RODRIGUES), CENTRE_1_MM).map(|v| -v)
}

/// The calibration of `model`: over 80..225 mA, the paper's thermal part, and the diagonal
/// covariance of the module docs.
pub fn calibration(model: &CameraModel) -> Calibration {
    let mut cal = Calibration::from_model(model, CameraModel::PAPER_IMAGE_SIZE, [80.0, 225.0]);
    cal.thermal = Some(ThermalRef::paper());
    let layout = model.layout();
    let theta = etl_core::calib::jacobian::to_params(model);
    let mut std = [0.0; etl_core::calib::params::MAX_PARAMS];
    for (i, s) in std.iter_mut().enumerate().take(layout.len()) {
        let relative = |r: f64| r * theta[i].abs();
        *s = if layout.kf_x().contains(i) || layout.kf_y().contains(i) {
            relative(2e-4)
        } else if layout.principal_point().contains(i) {
            0.5
        } else if layout.distortion_a().contains(i) {
            relative(1e-3)
        } else if i >= layout.centre_dz().start {
            relative(0.05)
        } else {
            0.0
        };
    }
    cal.std = ModelStd::from_params(&layout, &std);
    let mut c = [[0.0; etl_core::calib::params::MAX_PARAMS]; etl_core::calib::params::MAX_PARAMS];
    for (i, s) in std.iter().enumerate() {
        c[i][i] = s * s;
    }
    // The model is valid by construction: `set_covariance` fails only on an invalid one.
    cal.set_covariance(&c).ok();
    cal
}

/// The rig (calibrations inline) of family `family`.
pub fn rig_file(family: DistortionModel) -> RigFile {
    let [m0, m1] = models(family);
    let camera = |name: &str, m: &CameraModel| RigCamera {
        name: name.into(),
        image_size: CameraModel::PAPER_IMAGE_SIZE,
        calibration: Some(Box::new(calibration(m))),
        calibration_path: None,
    };
    let mut cov = [[0.0; 6]; 6];
    for (i, row) in cov.iter_mut().enumerate() {
        row[i] = if i < 3 { 1e-8 } else { 1e-2 };
    }
    RigFile::new(
        vec![camera("left", &m0), camera("right", &m1)],
        vec![RigExtrinsics {
            camera: 1,
            rotation_rodrigues: ROTATION_RODRIGUES,
            translation_mm: translation_mm(),
            covariance: Some(cov),
            reference_setting: Some(REFERENCE_SETTING_MA),
        }],
    )
}
