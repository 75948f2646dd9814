//! [`FocusMaps`]: the undistortion maps at any current of a calibrated range, exact, fast
//! enough to follow every focus change.

use etl_core::model::{CameraModel, Distortion, Intrinsics};

use super::{undistort_maps_into, OutputCamera, UndistortMaps};
use crate::{Error, Result};

/// The camera an undistorted image is seen by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OutputChoice {
    /// The model's own K(E) without distortion at each current (the default of
    /// `undistort_maps`), with this image size (px).
    ModelCamera {
        /// Width, px.
        width_px: usize,
        /// Height, px.
        height_px: usize,
    },
    /// One fixed camera matrix and size for every current.
    Camera(OutputCamera),
}

impl OutputChoice {
    /// The output camera when the model's intrinsics are `k`. Errors as
    /// [`OutputCamera::validate`].
    pub fn at(&self, k: &Intrinsics) -> Result<OutputCamera> {
        Ok(match *self {
            OutputChoice::ModelCamera { width_px, height_px } => OutputCamera::of_intrinsics(k, width_px, height_px)?,
            OutputChoice::Camera(c) => {
                c.validate()?;
                c
            }
        })
    }
}

/// The undistortion maps of a calibrated model at any compensated current of its range.
///
/// Why no cache: the maps are a forward evaluation of the model (about 20 flops per pixel,
/// no iteration), so computing them at the new current is both exact and faster than
/// interpolating cached ones. Interpolation would read at least two cached maps (4 x 11 MB
/// for 1936 x 1458) to write one (2 x 11 MB), and linear interpolation in E of the paper
/// rig's maps over 80..225 mA needs 12 cached currents (271 MB) to stay within 0.0075 px
/// (measured by `benches/undistort_interpolation.py`: 0.50 px with 2 currents, 0.053 with 5,
/// 0.018 with 8, 0.0075 with 12, 0.0040 with 16). Here the error bound is f32 rounding
/// alone: 1.2e-4 px over the whole image (etl-core's test against the model's projection),
/// and the time is that of [`super::undistort_maps_into`] (buffers reused, the loops
/// dispatched to AVX-512 or AVX2 where the CPU has them): for 1936 x 1458, 0.7 ms of one
/// core with AVX-512 (3.1 ms with the baseline's SSE2), 1.9 ms median on the 2 shared cores
/// under a load average of 12 (docs/PERFORMANCE-HISTORY.md, "Undistortion"; current: docs/BENCHMARKS.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocusMaps {
    model: CameraModel,
    e_com_range_ma: [f64; 2],
    output: OutputChoice,
}

impl FocusMaps {
    /// The maps of `model` over `e_com_range_ma` (mA, the calibrated range) for the output
    /// camera `output`.
    ///
    /// Errors: a model with a non-finite number; a range that is not finite and ordered; a
    /// focal length that is not positive at either end of the range; an invalid output
    /// camera.
    pub fn new(model: &CameraModel, e_com_range_ma: [f64; 2], output: OutputChoice) -> Result<Self> {
        model.validate()?;
        let [lo, hi] = e_com_range_ma;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Error::invalid_value(
                "e_com_range_ma",
                e_com_range_ma,
                format!("e_com_range_ma {e_com_range_ma:?} must be a finite [min, max]"),
            ));
        }
        for e in [lo, hi] {
            output.at(&model.intrinsics(e)?)?;
            model.distortion(e)?;
        }
        Ok(FocusMaps { model: *model, e_com_range_ma, output })
    }

    /// The compensated current range the maps are given over, mA.
    pub fn e_com_range_ma(&self) -> [f64; 2] {
        self.e_com_range_ma
    }

    /// The model's intrinsics and distortion, and the output camera, at `e_com_ma`.
    ///
    /// Errors: `e_com_ma` outside the range (refused, never extrapolated:
    /// [`etl_core::Error::OutOfRange`] naming e_com_ma) or not finite.
    pub fn camera_at(&self, e_com_ma: f64) -> Result<(Intrinsics, Distortion, OutputCamera)> {
        let [lo, hi] = self.e_com_range_ma;
        if !(e_com_ma >= lo && e_com_ma <= hi) {
            return Err(etl_core::Error::OutOfRange {
                what: "e_com_ma (mA) of the undistortion maps",
                value: e_com_ma,
                min: lo,
                max: hi,
            }
            .into());
        }
        let k = self.model.intrinsics(e_com_ma)?;
        Ok((k, self.model.distortion(e_com_ma)?, self.output.at(&k)?))
    }

    /// The maps at `e_com_ma` into `maps` (its buffers reused: no allocation when the size
    /// is unchanged). Exact (f32 rounding, 1.2e-4 px). Errors as [`Self::camera_at`]; on
    /// error `maps` is left as it was.
    pub fn maps_at(&self, e_com_ma: f64, maps: &mut UndistortMaps) -> Result<()> {
        let (k, d, out) = self.camera_at(e_com_ma)?;
        undistort_maps_into(&k, &d, &out, maps)
    }
}
