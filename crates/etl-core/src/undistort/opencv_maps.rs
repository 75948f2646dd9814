//! Undistortion maps of the opencv distortion family: OpenCV's distortion of each output
//! ray's normalised point, as `cv2.initUndistortRectifyMap` evaluates it.

use core::ops::Range;

use super::camera::OutputCamera;
use crate::model::{Distortion, Intrinsics};

/// Fills the maps of the output rows `rows` (checked by the caller: the band fits the
/// image and the buffers, the model and `out` are valid): the output pixel (x, y) sees the
/// normalised point x' = (x - cx') / fx', y' = (y - cy') / fy', which the model images at
/// (fx x_d + u0, fy y_d + v0), (x_d, y_d) = OpenCV's distortion of (x', y').
pub(super) fn fill(
    k: &Intrinsics,
    d: &Distortion,
    out: &OutputCamera,
    rows: Range<usize>,
    map_x: &mut [f32],
    map_y: &mut [f32],
) {
    let w = out.width_px;
    let (sx, tx) = (1.0 / out.fx_px, -out.cx_px / out.fx_px);
    let (sy, ty) = (1.0 / out.fy_px, -out.cy_px / out.fy_px);
    for (i, y) in rows.enumerate() {
        let span = i * w..(i + 1) * w;
        let (Some(row_x), Some(row_y)) = (map_x.get_mut(span.clone()), map_y.get_mut(span)) else { break };
        let yn = sy * y as f64 + ty;
        for (x, (mx, my)) in row_x.iter_mut().zip(row_y.iter_mut()).enumerate() {
            let [xd, yd] = d.distort_normalised(sx * x as f64 + tx, yn);
            *mx = (k.fx * xd + k.u0) as f32;
            *my = (k.fy * yd + k.v0) as f32;
        }
    }
}
