//! [`CameraAt`]: the camera at one setting, with everything a measurement needs.

use crate::error::Result;
use crate::model::{CameraModel, Distortion, Intrinsics, Ray};
use crate::pnp::{solve_pnp, BoardPose};

/// Which calibrated ranges a setting lies outside of (margins included).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Extrapolated {
    /// The temperature is outside the thermal calibration's range.
    pub temperature: bool,
    /// The driver current is outside the thermal calibration's E_in range.
    pub e_in: bool,
    /// The compensated current is outside the calibrated E_com range.
    pub e_com: bool,
}

impl Extrapolated {
    /// Inside every range.
    pub const NONE: Extrapolated = Extrapolated { temperature: false, e_in: false, e_com: false };

    /// Whether any range was left.
    pub fn any(&self) -> bool {
        self.temperature || self.e_in || self.e_com
    }
}

/// The camera at one setting: E_com, K(E_com), the distortion there, and the pose.
///
/// Built by [`super::Camera::at`]; the methods are those of [`CameraModel`] at this
/// `e_com_ma`, so they agree with it exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraAt {
    model: CameraModel,
    e_in_ma: f64,
    temperature_c: f64,
    e_com_ma: f64,
    intrinsics: Intrinsics,
    distortion: Distortion,
    flags: Extrapolated,
}

impl CameraAt {
    pub(super) fn new(
        model: &CameraModel,
        e_in_ma: f64,
        temperature_c: f64,
        e_com_ma: f64,
        flags: Extrapolated,
    ) -> Result<Self> {
        let intrinsics = model.intrinsics(e_com_ma)?;
        let distortion = model.distortion(e_com_ma)?;
        Ok(CameraAt { model: *model, e_in_ma, temperature_c, e_com_ma, intrinsics, distortion, flags })
    }

    /// Driver current, mA (NaN when built from a known E_com).
    pub fn e_in_ma(&self) -> f64 {
        self.e_in_ma
    }
    /// Lens temperature, degC (NaN when built from a known E_com).
    pub fn temperature_c(&self) -> f64 {
        self.temperature_c
    }
    /// Compensated current E_com, mA (Eq. 7).
    pub fn e_com_ma(&self) -> f64 {
        self.e_com_ma
    }
    /// fx, fy, u0, v0 at E_com (Eq. 16).
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }
    /// k1, p1, p2 at E_com (Eq. 18).
    pub fn distortion(&self) -> &Distortion {
        &self.distortion
    }
    /// Which calibrated ranges this setting is outside of.
    pub fn flags(&self) -> Extrapolated {
        self.flags
    }
    /// Whether any calibrated range was left ([`super::Trust::Extrapolate`]).
    pub fn extrapolated(&self) -> bool {
        self.flags.any()
    }
    /// The camera model this setting was taken from.
    pub fn model(&self) -> &CameraModel {
        &self.model
    }

    /// World point (mm) -> observed pixel ([`CameraModel::project`]).
    pub fn project(&self, world_mm: [f64; 3]) -> Result<[f64; 2]> {
        self.model.project(world_mm, self.e_com_ma)
    }
    /// Observed pixel -> undistorted pixel ([`CameraModel::undistort`]).
    pub fn undistort_point(&self, pixel: [f64; 2]) -> Result<[f64; 2]> {
        self.model.undistort(pixel, self.e_com_ma)
    }
    /// Undistorts `pixels` into `out` (same length); on error `out` holds those before.
    pub fn undistort_points(&self, pixels: &[[f64; 2]], out: &mut [[f64; 2]]) -> Result<()> {
        if out.len() < pixels.len() {
            return Err(crate::Error::BufferTooSmall { what: "out", needed: pixels.len(), got: out.len() });
        }
        for (p, o) in pixels.iter().zip(out.iter_mut()) {
            *o = self.undistort_point(*p)?;
        }
        Ok(())
    }
    /// The world ray of a pixel ([`CameraModel::ray`]).
    pub fn ray(&self, pixel: [f64; 2]) -> Result<Ray> {
        self.model.ray(pixel, self.e_com_ma)
    }
    /// The pose of a planar board (points on its Z = 0) from its pixels ([`solve_pnp`]).
    pub fn solve_pnp(&self, board_mm: &[[f64; 3]], pixels: &[[f64; 2]]) -> Result<BoardPose> {
        solve_pnp(&self.model, self.e_com_ma, board_mm, pixels)
    }
}
