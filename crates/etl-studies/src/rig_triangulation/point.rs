//! One random point of a trial: a random pair of settings inside the cameras' calibrated
//! ranges, a random point both true cameras see, its noisy true pixels triangulated by
//! the estimated rig, and its error against the propagated covariance.

use etl_calib::rig::{CalibrationPart, Rig};
use etl_core::model::rotation::Mat3;
use etl_core::model::CameraModel;
use etl_formats::{Error, Result, Trust};
use etl_sim::multi_camera::{MULTI_CAMERA_BOARD, STAGE_TRAVEL_MM};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::{gauss, in_image, settings_of};

/// How many random points are drawn before a trial gives up finding one both cameras see.
const MAX_DRAWS: usize = 1000;

/// The error of one triangulated point against its propagated covariance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PointError {
    /// Each camera's compensated current, mA (drawn uniformly in its calibrated range).
    pub e_com_ma: [f64; 2],
    /// The point's depth in camera 0's frame, mm.
    pub depth_mm: f64,
    /// error_i / sqrt(Cov_ii) per axis of camera 0's frame (pixel + calibration part).
    pub z_scores: [f64; 3],
    /// The Mahalanobis distance squared, e' Cov^-1 e (chi-square, 3 dof, mean 3).
    pub d2: f64,
    /// The same with the pixel part alone.
    pub d2_pixels_only: f64,
    /// trace(calibration part) / trace(covariance).
    pub calibration_share: f64,
    /// sqrt(Cov_ii) per axis, mm.
    pub std_mm: [f64; 3],
    /// error_i / sigma_i with the calibration part from independent groups (the rig file
    /// without its joint covariance) instead of the joint covariance.
    pub z_scores_independent: [f64; 3],
    /// d^2 with that covariance.
    pub d2_independent: f64,
}

/// A point of the stage's volume (X, Y over the board, Z over the travel) that both true
/// cameras see at `e_com_ma`; None after [`MAX_DRAWS`] draws.
fn draw_point(truths: &[CameraModel], e_com_ma: [f64; 2], rng: &mut ChaCha8Rng) -> Option<[f64; 3]> {
    let b = &MULTI_CAMERA_BOARD;
    let span = |n: usize| b.square_mm * (n - 1) as f64;
    let [z0, z1] = STAGE_TRAVEL_MM;
    (0..MAX_DRAWS).find_map(|_| {
        let w = [
            b.origin_mm[0] + rng.random_range(0.0..=span(b.inner_corners[0])),
            b.origin_mm[1] + rng.random_range(0.0..=span(b.inner_corners[1])),
            rng.random_range(z0..=z1),
        ];
        truths.iter().zip(e_com_ma).all(|(m, e)| m.project(w, e).is_ok_and(in_image)).then_some(w)
    })
}

/// e' C^-1 e for a symmetric positive definite 3 x 3 C.
pub(crate) fn mahalanobis2(c: &Mat3, e: [f64; 3]) -> Result<f64> {
    let m = nalgebra::Matrix3::from_fn(|i, j| c[i][j]);
    let chol = m.cholesky().ok_or_else(|| Error::invalid("covariance", "covariance: not positive definite"))?;
    let v = nalgebra::Vector3::from(e);
    Ok(v.dot(&chol.solve(&v)))
}

/// One point (module docs) with the estimated `rig` (and the same rig `independent`
/// without its joint covariance) against the simulation's `truths`,
/// pixel noise `sigma_px`, at the lens temperature `temperature_c`; `ranges` each
/// camera's calibrated range of E_com.
pub fn point_error(
    (rig, independent): (&Rig, &Rig),
    truths: &[CameraModel],
    (ranges, temperature_c): ([[f64; 2]; 2], f64),
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> Result<PointError> {
    let e_com_ma = ranges.map(|[lo, hi]| rng.random_range(lo..=hi));
    let w = draw_point(truths, e_com_ma, rng)
        .ok_or_else(|| Error::invalid("point", "point: no point seen by both cameras at these settings"))?;
    let truth_mm = truths[0].world_to_camera_at(w, e_com_ma[0]);
    let mut observed = [[0.0; 2]; 2];
    for ((m, e), o) in truths.iter().zip(e_com_ma).zip(&mut observed) {
        let p = m.project(w, e)?;
        *o = [p[0] + gauss(sigma_px, rng), p[1] + gauss(sigma_px, rng)];
    }
    let settings = settings_of(&e_com_ma, temperature_c)?;
    let triangulate = |r: &Rig| {
        r.at(&settings, &[temperature_c; 2], Trust::Refuse)?.triangulate(
            &observed.map(Some),
            sigma_px,
            CalibrationPart::Include,
        )
    };
    let t = triangulate(rig)?;
    let independent_cov = triangulate(independent)?.covariance_mm2;
    let e: [f64; 3] = std::array::from_fn(|i| t.point_mm[i] - truth_mm[i]);
    let std_mm = t.std_mm();
    let calibration = t.from_calibration.unwrap_or_default();
    let trace = |c: &Mat3| c[0][0] + c[1][1] + c[2][2];
    Ok(PointError {
        e_com_ma,
        depth_mm: truth_mm[2],
        z_scores: std::array::from_fn(|i| e[i] / std_mm[i]),
        d2: mahalanobis2(&t.covariance_mm2, e)?,
        d2_pixels_only: mahalanobis2(&t.from_pixels, e)?,
        calibration_share: trace(&calibration) / trace(&t.covariance_mm2),
        std_mm,
        z_scores_independent: std::array::from_fn(|i| e[i] / independent_cov[i][i].sqrt()),
        d2_independent: mahalanobis2(&independent_cov, e)?,
    })
}
