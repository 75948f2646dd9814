//! [`RigAt::stereo_rectify`]: Bouguet's rectification of a pair of the rig's cameras at
//! their settings, and the maps of both images exact to the model
//! ([`RigAt::stereo_rectify_maps`]).
//!
//! The pair (i, j) is posed at the settings (X_j = R X_i + T, R = R_j R_i^T,
//! T = T_j - R T_i with each pose at the settings: Eq. R2), then rectified as
//! `cv2.stereoRectify` does with `CALIB_ZERO_DISPARITY` and alpha = -1
//! ([`crate::stereo::rectify_cameras`]). A camera of the opencv family is at its setting
//! an OpenCV camera (K, and its five coefficients), and its image corners are undistorted
//! by OpenCV's own 5 iterations, so R1, R2, P1, P2, Q are `cv2.stereoRectify`'s for that
//! camera; a paper-family camera's corners are undistorted by its model's exact inverse.
//!
//! The maps: for each rectified pixel (x, y), the ray P^-1 (x, y, 1) turned back by R^T
//! and projected through the camera's full model at its setting
//! ([`etl_core::undistort::rectify_maps`]): `cv2.initUndistortRectifyMap`'s maps for an
//! opencv-family camera, the same construction for the paper's, so `cv2.remap(image,
//! map_x, map_y)` gives the rectified image of either family, exactly to the model.

use etl_core::model::rotation::{matrix_to_rodrigues, Mat3};
use etl_core::model::DistortionModel;
use etl_core::undistort::OutputCamera;
use etl_formats::{CameraAt, Error, Result};
use etl_image::undistort::{rectify_maps, UndistortMaps};

use super::RigAt;
use crate::stereo::{rectify_cameras, undistort_opencv, Rectification, RectifyCamera};

/// A rectified pair of the rig's cameras at their settings.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoRectification {
    /// The cameras (left, right): indices into the rig.
    pub pair: [usize; 2],
    /// Both cameras' image size, px.
    pub image_size: [u32; 2],
    /// R of X_right = R X_left + T at the settings, as a Rodrigues vector, rad.
    pub rotation_rodrigues: [f64; 3],
    /// R as a matrix.
    pub rotation: Mat3,
    /// T, mm.
    pub translation_mm: [f64; 3],
    /// R1, R2, P1, P2, Q (`cv2.stereoRectify`'s).
    pub rectification: Rectification,
}

impl StereoRectification {
    /// The baseline |T|, mm.
    pub fn baseline_mm(&self) -> f64 {
        self.translation_mm.iter().map(|v| v * v).sum::<f64>().sqrt()
    }
}

/// The rectification maps of both images of a pair, in `cv2.remap`'s convention.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoRectifyMaps {
    /// The left camera's (map_x, map_y).
    pub left: UndistortMaps,
    /// The right camera's.
    pub right: UndistortMaps,
}

/// The pixel -> normalised undistorted point of `c` for the corners (module docs).
fn normaliser(c: &CameraAt) -> Box<dyn Fn([f64; 2]) -> etl_core::Result<[f64; 2]> + '_> {
    let k = *c.intrinsics();
    let d = *c.distortion().padded();
    match c.distortion().model() {
        DistortionModel::OpenCv => Box::new(move |p| Ok(undistort_opencv([k.fx, k.fy, k.u0, k.v0], &d, p))),
        DistortionModel::Paper => Box::new(move |p| {
            let [x, y] = c.undistort_point(p)?;
            Ok([(x - k.u0) / k.fx, (y - k.v0) / k.fy])
        }),
    }
}

impl RigAt {
    /// Bouguet's rectification of cameras (`left`, `right`) at their settings (module
    /// docs). `alpha`: `cv2.stereoRectify`'s free scaling; only -1 (its default: no
    /// scaling to the valid region) is implemented, others are refused rather than
    /// ignored.
    ///
    /// Errors (one line): an index outside the rig or a camera paired with itself
    /// (`"pair"`), images of different sizes, `alpha` other than -1 (`"alpha"`), a zero
    /// baseline.
    pub fn stereo_rectify(&self, left: usize, right: usize, alpha: f64) -> Result<StereoRectification> {
        let pose = self.relative_pose(left, right)?;
        if left == right {
            return Err(Error::invalid_value(
                "pair",
                left,
                format!("pair: camera {left} cannot be paired with itself"),
            ));
        }
        if alpha != -1.0 {
            return Err(Error::invalid_value(
                "alpha",
                alpha,
                format!("alpha {alpha}: only -1 (cv2.stereoRectify's default, no scaling) is implemented"),
            ));
        }
        let (sl, sr) = (self.image_size(left).unwrap_or_default(), self.image_size(right).unwrap_or_default());
        if sl != sr {
            return Err(Error::invalid(
                "pair",
                format!("pair: cameras {left} and {right} have images of {sl:?} and {sr:?} px: rectification needs one size"),
            ));
        }
        let (cl, cr) = (&self.cameras()[left], &self.cameras()[right]);
        let (nl, nr) = (normaliser(cl), normaliser(cr));
        let focal = |c: &CameraAt| [c.intrinsics().fx, c.intrinsics().fy];
        let rotation_rodrigues = matrix_to_rodrigues(&pose.rotation);
        let rectification = rectify_cameras(
            (
                &RectifyCamera { focal_px: focal(cl), normalise: &*nl },
                &RectifyCamera { focal_px: focal(cr), normalise: &*nr },
            ),
            sl,
            (rotation_rodrigues, pose.translation_mm),
            true,
        )?;
        Ok(StereoRectification {
            pair: [left, right],
            image_size: sl,
            rotation_rodrigues,
            rotation: pose.rotation,
            translation_mm: pose.translation_mm,
            rectification,
        })
    }

    /// The maps of both images of `rect` (a rectification of this rig at these settings,
    /// [`Self::stereo_rectify`]) through each camera's full model (module docs), f32,
    /// image-sized. Errors: `rect` of cameras not in this rig, maps above the memory budget.
    pub fn stereo_rectify_maps(&self, rect: &StereoRectification) -> Result<StereoRectifyMaps> {
        let [l, r] = rect.pair;
        self.check_index(l, "pair")?;
        self.check_index(r, "pair")?;
        let [w, h] = rect.image_size.map(|v| v as usize);
        let x = &rect.rectification;
        let maps = |c: &CameraAt, rot: &Mat3, p: &[[f64; 4]; 3]| -> Result<UndistortMaps> {
            let out = OutputCamera::new(p[0][0], p[1][1], p[0][2], p[1][2], w, h)?;
            rectify_maps(c.intrinsics(), c.distortion(), rot, &out)
        };
        Ok(StereoRectifyMaps {
            left: maps(&self.cameras()[l], &x.r1, &x.p1)?,
            right: maps(&self.cameras()[r], &x.r2, &x.p2)?,
        })
    }
}
