//! What [`super::stereo_calibrate`] returns.

use etl_core::model::rotation::rodrigues_to_matrix;

use super::options::StereoMode;
use crate::zhang::ZhangResult;

/// A calibrated fixed-focus pair.
#[derive(Debug, Clone)]
pub struct StereoResult {
    /// The left camera: its own Zhang calibration ([`StereoMode::FixedIntrinsics`]), or the
    /// joint estimate ([`StereoMode::Joint`]: its numbers, their standard deviations from
    /// the joint covariance, its RMS and poses over the pairs; no projection uncertainty,
    /// `uncertainty` is `None`).
    pub left: ZhangResult,
    /// The right camera, as `left`.
    pub right: ZhangResult,
    /// For each view of `left` (its poses, per-view RMS, outliers' `view`), the index of
    /// its pair in the input.
    pub left_pairs: Vec<usize>,
    /// The same for `right`.
    pub right_pairs: Vec<usize>,
    /// R as a Rodrigues vector: X_r = R X_l + T takes a point from the left camera's frame
    /// to the right's (`cv2.stereoCalibrate`'s R).
    pub rotation_rodrigues: [f64; 3],
    /// T, mm (`cv2.stereoCalibrate`'s T).
    pub translation_mm: [f64; 3],
    /// The covariance of (om, T) (rad, mm), OpenCV's scaling: sigma^2 (J^T J)^-1
    /// marginalised over the poses (and in the joint mode the intrinsics), with
    /// sigma^2 = cost / (2 points - free numbers - 6 pairs); with the intrinsics held, plus
    /// A Cov(kappa) A^T, the held intrinsics' covariance carried through
    /// A = d(om, T)/d(kappa) (they came from noisy views too).
    pub covariance: [[f64; 6]; 6],
    /// RMS reprojection distance over both cameras' points of the pairs used, px:
    /// sqrt(sum |q - u|^2 / points), `cv2.stereoCalibrate`'s return value.
    pub rms_px: f64,
    /// Each pair's RMS, [left, right], px (`cv2.stereoCalibrateExtended`'s perViewErrors).
    pub per_view_rms_px: Vec<[f64; 2]>,
    /// The input indices of the pairs used (seen by both cameras), in order.
    pub pairs_used: Vec<usize>,
    /// Each pair's board pose in the left camera (Rodrigues, translation mm), as
    /// `pairs_used`.
    pub poses: Vec<([f64; 3], [f64; 3])>,
    /// The mode fitted.
    pub mode: StereoMode,
    /// Levenberg-Marquardt iterations of the stereo refinement.
    pub iterations: usize,
}

impl StereoResult {
    /// One standard deviation of (om, T): the square roots of the covariance's diagonal.
    pub fn std(&self) -> [f64; 6] {
        core::array::from_fn(|k| self.covariance[k][k].max(0.0).sqrt())
    }

    /// R as a matrix.
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        rodrigues_to_matrix(self.rotation_rodrigues)
    }

    /// The distance between the cameras' centres, |C_r - C_l| = |T|, mm.
    pub fn baseline_mm(&self) -> f64 {
        let t = self.translation_mm;
        (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()
    }

    /// The number of pairs used.
    pub fn views_used(&self) -> usize {
        self.pairs_used.len()
    }
}
