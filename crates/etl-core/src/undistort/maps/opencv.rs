//! Undistortion maps of the opencv distortion family: OpenCV's distortion of each output
//! ray's normalised point, as `cv2.initUndistortRectifyMap` evaluates it.
//!
//! A child of [`super`] rather than its sibling: it fills rows through the parent's
//! `FillRow`, and the parent dispatches to it (siblings importing each other would be a
//! cycle).

use super::FillRow;
use crate::model::{Distortion, Intrinsics};
use crate::undistort::pinhole::OutputCamera;

/// The opencv family's rows (the band is checked by the caller: it fits the image and the
/// buffers, the model and `out` are valid): the output pixel (x, y) sees the normalised
/// point x' = (x - cx') / fx', y' = (y - cy') / fy', which the model images at
/// (fx x_d + u0, fy y_d + v0), (x_d, y_d) = OpenCV's distortion of (x', y').
pub(super) struct OpenCvRow<'a> {
    /// The model at the current.
    model: (&'a Intrinsics, &'a Distortion),
    /// (s, t) of x' = s x + t and of y' = s y + t.
    normalised: [(f64, f64); 2],
}

impl<'a> OpenCvRow<'a> {
    #[inline(always)]
    pub(super) fn new(k: &'a Intrinsics, d: &'a Distortion, out: &OutputCamera) -> Self {
        let x = (1.0 / out.fx_px, -out.cx_px / out.fx_px);
        let y = (1.0 / out.fy_px, -out.cy_px / out.fy_px);
        OpenCvRow { model: (k, d), normalised: [x, y] }
    }
}

impl FillRow for OpenCvRow<'_> {
    #[inline(always)]
    fn fill(&self, y: usize, row_x: &mut [f32], row_y: &mut [f32]) {
        let ((k, d), [(sx, tx), (sy, ty)]) = (self.model, self.normalised);
        let yn = sy * y as f64 + ty;
        for (x, (mx, my)) in row_x.iter_mut().zip(row_y.iter_mut()).enumerate() {
            let [xd, yd] = d.distort_normalised(sx * x as f64 + tx, yn);
            *mx = (k.fx * xd + k.u0) as f32;
            *my = (k.fy * yd + k.v0) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::projection::project_camera_point;
    use crate::model::CameraModel;
    use crate::undistort::{undistort_maps, OutputCamera};

    /// Every entry of the strong lens's maps over its whole image, at three currents and
    /// two output cameras, is the model's own projection of the output pixel's ray (f32
    /// rounding aside).
    #[test]
    fn maps_are_the_models_projection_of_each_ray() {
        const W: usize = 1936;
        let cam = CameraModel::strong_distortion_rig();
        let (mut mx, mut my) = ([0.0f32; W], [0.0f32; W]);
        for e in [80.0, 150.0, 225.0] {
            let (k, d) = (cam.intrinsics(e).unwrap(), cam.distortion(e).unwrap());
            let cams = [
                OutputCamera::of_intrinsics(&k, W, 1458).unwrap(),
                OutputCamera::new(0.7 * k.fx, 0.72 * k.fy, 900.0, 700.0, W, 1400).unwrap(),
            ];
            for out in cams {
                let mut worst = 0.0f64;
                for y in (0..out.height_px).step_by(7) {
                    undistort_maps(&k, &d, &out, y..y + 1, &mut mx, &mut my).unwrap();
                    for x in 0..out.width_px {
                        let pc = [(x as f64 - out.cx_px) / out.fx_px, (y as f64 - out.cy_px) / out.fy_px, 1.0];
                        let p = project_camera_point(pc, &k, &d).unwrap();
                        worst = worst.max((mx[x] as f64 - p[0]).abs()).max((my[x] as f64 - p[1]).abs());
                    }
                }
                assert!(worst < 2.5e-4, "E = {e}: worst {worst} px");
            }
        }
    }
}
