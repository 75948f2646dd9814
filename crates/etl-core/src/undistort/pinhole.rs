//! [`OutputCamera`]: the pinhole camera (no distortion) an undistorted image is seen by,
//! and the image sides every undistortion buffer is checked against ([`MAX_SIDE_PX`]).
//!
//! Named `pinhole` for the camera it holds: the ideal pinhole of the output image, not the
//! ETL camera ([`crate::model::projection`], [`crate::runtime`]).

use crate::error::{Error, Result};
use crate::model::Intrinsics;

/// Largest accepted image width or height, px (2^20). It keeps `width * height` far from
/// `usize` overflow and every pixel coordinate exact in `f32` (exact up to 2^24).
pub const MAX_SIDE_PX: usize = 1 << 20;

/// The most pixels of an undistorted image: 2^28, the limit of the images the readers
/// decode (etl_formats' `MAX_IMAGE_PIXELS`). Its two f32 maps take 2 GiB; a larger size
/// is refused before anything is allocated, instead of aborting on a failed allocation.
pub const MAX_PIXELS: usize = 1 << 28;

/// The camera of the undistorted image: the matrix `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`
/// (px; no skew, no distortion) and the image size.
///
/// Invariants (checked by [`OutputCamera::new`] and by every function taking one, since the
/// fields are public): fx, fy finite and > 0; cx, cy finite; 1 <= width, height <=
/// [`MAX_SIDE_PX`]; width x height <= [`MAX_PIXELS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputCamera {
    /// Focal length along x, px.
    pub fx_px: f64,
    /// Focal length along y, px.
    pub fy_px: f64,
    /// Principal point x, px.
    pub cx_px: f64,
    /// Principal point y, px.
    pub cy_px: f64,
    /// Width of the undistorted image, px.
    pub width_px: usize,
    /// Height of the undistorted image, px.
    pub height_px: usize,
}

impl OutputCamera {
    /// A new camera matrix and size (`cv2.initUndistortRectifyMap`'s `newCameraMatrix` and
    /// `size`). Errors as [`Self::validate`].
    pub fn new(fx_px: f64, fy_px: f64, cx_px: f64, cy_px: f64, width_px: usize, height_px: usize) -> Result<Self> {
        let c = OutputCamera { fx_px, fy_px, cx_px, cy_px, width_px, height_px };
        c.validate()?;
        Ok(c)
    }

    /// The default output camera: the model's own K(E) without distortion, `width_px` x
    /// `height_px` (the calibration's image size).
    pub fn of_intrinsics(k: &Intrinsics, width_px: usize, height_px: usize) -> Result<Self> {
        Self::new(k.fx, k.fy, k.u0, k.v0, width_px, height_px)
    }

    /// Checks the invariants. Errors: a zero or too large side ([`Error::OutOfRange`]
    /// naming it); a focal length that is not finite and positive, a non-finite principal
    /// point ([`Error::InvalidArgument`], "camera matrix").
    pub fn validate(&self) -> Result<()> {
        check_side("output width_px", self.width_px)?;
        check_side("output height_px", self.height_px)?;
        let pixels = self.width_px.saturating_mul(self.height_px);
        if pixels > MAX_PIXELS {
            return Err(Error::OutOfRange {
                what: "output width_px x height_px",
                value: pixels as f64,
                min: 1.0,
                max: MAX_PIXELS as f64,
            });
        }
        if !(self.fx_px > 0.0 && self.fy_px > 0.0 && self.fx_px.is_finite() && self.fy_px.is_finite()) {
            return Err(Error::InvalidArgument { what: "camera matrix: fx and fy must be finite and > 0" });
        }
        if !(self.cx_px.is_finite() && self.cy_px.is_finite()) {
            return Err(Error::InvalidArgument { what: "camera matrix: cx and cy must be finite" });
        }
        Ok(())
    }

    /// Number of pixels, `width_px * height_px` (no overflow under the invariants).
    pub fn pixels(&self) -> usize {
        self.width_px.saturating_mul(self.height_px)
    }
}

/// `Ok` if `1 <= v <= MAX_SIDE_PX`, else [`Error::OutOfRange`] naming `what`.
pub(crate) fn check_side(what: &'static str, v: usize) -> Result<()> {
    if v == 0 || v > MAX_SIDE_PX {
        Err(Error::OutOfRange { what, value: v as f64, min: 1.0, max: MAX_SIDE_PX as f64 })
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_sizes_and_bad_matrices_are_named_errors() {
        let side = |w, h| OutputCamera::new(1000.0, 1000.0, 50.0, 50.0, w, h).unwrap_err();
        assert!(matches!(side(0, 10), Error::OutOfRange { what: "output width_px", .. }));
        assert!(matches!(side(10, 0), Error::OutOfRange { what: "output height_px", .. }));
        assert!(matches!(side(MAX_SIDE_PX + 1, 10), Error::OutOfRange { .. }));
        for (fx, fy, cx) in [(0.0, 1.0, 0.0), (1.0, -1.0, 0.0), (f64::NAN, 1.0, 0.0), (1.0, 1.0, f64::INFINITY)] {
            let e = OutputCamera::new(fx, fy, cx, 0.0, 10, 10).unwrap_err();
            assert!(matches!(e, Error::InvalidArgument { what } if what.starts_with("camera matrix")), "{e:?}");
        }
        assert_eq!(OutputCamera::new(2.0, 3.0, 4.0, 5.0, 6, 7).unwrap().pixels(), 42);
    }
}
