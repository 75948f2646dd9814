//! The paper's measurement of a stage move (section 5.2.3, `etlcal measure`): the board's
//! pose in two images at one compensated current by plane-based PnP, and the displacement
//! of the board between them, with its standard deviation from the images' pixel noise
//! and the calibration's covariance together ([`etl_core::pnp::displacement_covariance_mm2`]:
//! the pixel noise estimated from each PnP's residual, the calibration's error moving
//! both poses alike through d pose / d calibration).

use std::path::Path;

use etl_core::pnp::{
    displacement_covariance_mm2, displacement_mm, displacement_std_mm, pose_uncertainty, BoardPose, PixelNoise,
    PoseUncertainty,
};
use etl_core::runtime::CameraAt;

use super::dataset::CornerDetector;
use etl_formats::calibration::Calibration;
use etl_formats::dataset::Board;
use etl_formats::{Error, Result};

/// The board's poses in two images and its displacement between them.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// The compensated current both poses were solved at, mA.
    pub e_com_ma: f64,
    /// The setting lies outside a calibrated range (only with `Trust::Extrapolate`).
    pub extrapolated: bool,
    /// The board's pose in the first and in the second image.
    pub poses: [BoardPose; 2],
    /// Translation of the board from the first pose to the second, camera frame, mm.
    pub displacement_mm: [f64; 3],
    /// Length of `displacement_mm`, mm.
    pub distance_mm: f64,
    /// Each pose's uncertainty (pixel noise estimated from its PnP residual).
    pub pose_uncertainty: [PoseUncertainty; 2],
    /// Covariance of `displacement_mm`, mm^2: pixel noise and, when
    /// `std_includes_calibration`, the calibration's covariance.
    pub displacement_covariance_mm2: [[f64; 3]; 3],
    /// One standard deviation of each component of `displacement_mm`, mm.
    pub displacement_std_mm: [f64; 3],
    /// Whether the standard deviation includes the calibration's uncertainty: false for a
    /// calibration file without a covariance (written before it was recorded), whose
    /// standard deviation is that of the pixel noise alone.
    pub std_includes_calibration: bool,
}

/// Measures the move of `board` between `images` with the calibration `cal` at the
/// setting `camera` (from [`Calibration::at`], E_com = E_in - E_T(T, E_in) through the
/// calibration's thermal surface, or [`Calibration::at_e_com`] at a known E_com: the range
/// policy was applied there): the corners found by `detector` (at their board coordinates,
/// [`Board::corner_mm`], Z = 0), each pose by PnP with the calibrated model at E_com, and
/// the displacement t_b - t_a, with its covariance (module docs).
///
/// Errors: an image missing, unreadable, of another size than the calibration's, or
/// without the board; a PnP failure.
pub fn measure_displacement(
    cal: &Calibration,
    camera: &CameraAt,
    board: &Board,
    images: [&Path; 2],
    detector: &dyn CornerDetector,
) -> Result<Measurement> {
    board.validate()?;
    let mut poses = Vec::with_capacity(2);
    let mut uncertainty = Vec::with_capacity(2);
    for path in images {
        std::fs::metadata(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
        let d = detector.detect(path, board)?;
        super::check_image_size(path, d.image_size, cal.image_size, "the calibration is for")?;
        let pts: Vec<[f64; 3]> = d.board_mm(board, [0, 0]).into_iter().map(|[x, y]| [x, y, 0.0]).collect();
        let px = d.pixels();
        let pose = camera.solve_pnp(&pts, &px)?;
        let u = pose_uncertainty(camera.model(), camera.setting_value(), &pts, &px, &pose, PixelNoise::FromResidual)?;
        uncertainty.push(u);
        poses.push(pose);
    }
    let two_images = || Error::invalid("images", "a measurement needs two images");
    let [a, b]: [BoardPose; 2] = poses.try_into().map_err(|_| two_images())?;
    let [ua, ub]: [PoseUncertainty; 2] = uncertainty.try_into().map_err(|_| two_images())?;
    let d = displacement_mm(&a, &b);
    let distance_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let calibration_covariance = cal.covariance_matrix();
    let cov = displacement_covariance_mm2(&ua, &ub, calibration_covariance.as_ref())?;
    Ok(Measurement {
        e_com_ma: camera.setting_value(),
        extrapolated: camera.extrapolated(),
        poses: [a, b],
        displacement_mm: d,
        distance_mm,
        pose_uncertainty: [ua, ub],
        displacement_covariance_mm2: cov,
        displacement_std_mm: displacement_std_mm(&cov),
        std_includes_calibration: calibration_covariance.is_some(),
    })
}
