//! The paper's measurement of a stage move (section 5.2.3, `etlcal measure`): the board's
//! pose in two images at one compensated current by plane-based PnP, and the displacement
//! of the board between them.

use std::path::Path;

use etl_core::camera::Trust;
use etl_core::pnp::{displacement_mm, BoardPose};

use super::dataset::CornerDetector;
use etl_formats::calibration::Calibration;
use etl_formats::dataset::Board;
use etl_formats::{Error, Result};

/// The board's poses in two images and its displacement between them.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// The compensated current both poses were solved at, mA.
    pub e_com_ma: f64,
    /// The setting lies outside a calibrated range (only with [`Trust::Extrapolate`]).
    pub extrapolated: bool,
    /// The board's pose in the first and in the second image.
    pub poses: [BoardPose; 2],
    /// Translation of the board from the first pose to the second, camera frame, mm.
    pub displacement_mm: [f64; 3],
    /// Length of `displacement_mm`, mm.
    pub distance_mm: f64,
}

/// Measures the move of `board` between `images` at the driver current `e_in_ma` and the
/// lens temperature `temperature_c`: E_com = E_in - E_T(T, E_in) through the calibration's
/// thermal surface, the corners found by `detector` (corner (i, j) at (i s, j s, 0) mm on
/// the board), each pose by PnP with the calibrated model at E_com, and the displacement
/// t_b - t_a.
///
/// Errors: a setting outside the calibrated ranges (temperature, E_in, E_com, with the
/// margins of [`etl_core::camera`]) unless `trust` is [`Trust::Extrapolate`]; an image
/// missing, unreadable, of another size than the calibration's, or without the board; a
/// PnP failure.
pub fn measure_displacement(
    cal: &Calibration,
    e_in_ma: f64,
    temperature_c: f64,
    trust: Trust,
    board: &Board,
    images: [&Path; 2],
    detector: &dyn CornerDetector,
) -> Result<Measurement> {
    board.validate()?;
    let camera = cal.at(e_in_ma, temperature_c, trust)?;
    let mut poses = Vec::with_capacity(2);
    for path in images {
        std::fs::metadata(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
        let d = detector.detect(path, board.inner_corners)?;
        super::check_image_size(path, d.image_size, cal.image_size, "the calibration is for")?;
        let sq = board.square_mm;
        let pts: Vec<[f64; 3]> = d.corners.iter().map(|(ij, _)| [ij[0] as f64 * sq, ij[1] as f64 * sq, 0.0]).collect();
        let px: Vec<[f64; 2]> = d.corners.iter().map(|c| c.1).collect();
        poses.push(camera.solve_pnp(&pts, &px)?);
    }
    let [a, b]: [BoardPose; 2] =
        poses.try_into().map_err(|_| Error::InvalidInput("a measurement needs two images".into()))?;
    let d = displacement_mm(&a, &b);
    let distance_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    Ok(Measurement {
        e_com_ma: camera.e_com_ma(),
        extrapolated: camera.extrapolated(),
        poses: [a, b],
        displacement_mm: d,
        distance_mm,
    })
}
