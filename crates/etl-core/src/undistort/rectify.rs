//! [`rectify_maps`]: the maps of a rectified image (a stereo pair's, Bouguet's R1 or R2 and
//! P1 or P2) through the camera's full model, in `cv2.remap`'s convention.

use core::ops::Range;

use super::maps::{check_band, check_model};
use super::pinhole::OutputCamera;
use crate::error::{all_finite, Result};
use crate::model::projection::project_camera_point;
use crate::model::rotation::{mat_t_vec, Mat3};
use crate::model::{Distortion, Intrinsics};

/// Fills the maps of the output rows `rows` of the rectified camera `out` (fx', fy', cx',
/// cy' of P's left 3 x 3) whose frame is turned by `rotation` (R1 or R2: camera frame ->
/// rectified frame) from the camera of intrinsics `k` and distortion `d` at one setting:
/// the output pixel (x, y) sees the rectified ray, turned back into the camera's frame
/// and projected by the model,
///
/// ```text
/// p = R^T ((x - cx') / fx', (y - cy') / fy', 1),   (map_x, map_y) = q(p)
/// ```
///
/// with q the model's projection of a camera point (Eq. 15, 17, either family): exactly
/// what `cv2.initUndistortRectifyMap(K, D, R, P, size, CV_32FC1)` computes for OpenCV's
/// model, and the same construction for the paper's. `cv2.remap(image, map_x, map_y)`
/// then gives the rectified image. A ray at or behind the camera's plane (p_z <= 0) gets
/// NaN, which [`super::remap()`] fills with its border value. Rounded once to f32.
///
/// Preconditions and errors as [`super::undistort_maps`], and a non-finite `rotation`
/// ([`crate::Error::NotFinite`]); on error nothing is written.
pub fn rectify_maps(
    k: &Intrinsics,
    d: &Distortion,
    rotation: &Mat3,
    out: &OutputCamera,
    rows: Range<usize>,
    map_x: &mut [f32],
    map_y: &mut [f32],
) -> Result<()> {
    out.validate()?;
    check_model(k, d)?;
    all_finite(rotation.as_flattened(), "rectifying rotation")?;
    check_band(out, &rows, map_x.len(), map_y.len())?;
    let width = out.width_px;
    for (i, y) in rows.enumerate() {
        let span = i * width..(i + 1) * width;
        let (Some(row_x), Some(row_y)) = (map_x.get_mut(span.clone()), map_y.get_mut(span)) else { break };
        let yn = (y as f64 - out.cy_px) / out.fy_px;
        for (x, (mx, my)) in row_x.iter_mut().zip(row_y.iter_mut()).enumerate() {
            let p = mat_t_vec(rotation, [(x as f64 - out.cx_px) / out.fx_px, yn, 1.0]);
            let [u, v] = project_camera_point(p, k, d).unwrap_or([f64::NAN; 2]);
            (*mx, *my) = (u as f32, v as f32);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rotation::{mat_vec, rodrigues_to_matrix};
    use crate::model::CameraModel;
    use crate::undistort::undistort_maps;

    /// With R = I the maps are the undistortion maps; with a rotation, each entry is the
    /// projection of the output pixel's ray turned back, and a camera point's projection
    /// through the rectified camera maps back onto the pixel the model gives it.
    #[test]
    fn rectify_maps_are_the_model_through_the_rotation() {
        for model in [CameraModel::paper_rig(), CameraModel::strong_distortion_rig()] {
            let (k, d) = (model.intrinsics(150.0).unwrap(), model.distortion(150.0).unwrap());
            let out = OutputCamera::new(0.9 * k.fx, 0.9 * k.fx, 950.0, 700.0, 64, 48).unwrap();
            let n = 64 * 48;
            let (mut ax, mut ay, mut bx, mut by) = ([0f32; 64 * 48], [0f32; 64 * 48], [0f32; 64 * 48], [0f32; 64 * 48]);
            let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            rectify_maps(&k, &d, &identity, &out, 0..48, &mut ax, &mut ay).unwrap();
            undistort_maps(&k, &d, &out, 0..48, &mut bx, &mut by).unwrap();
            for i in 0..n {
                assert!((ax[i] - bx[i]).abs() < 2e-3 && (ay[i] - by[i]).abs() < 2e-3, "{i}");
            }
            let r = rodrigues_to_matrix([0.02, -0.04, 0.01]);
            rectify_maps(&k, &d, &r, &out, 0..48, &mut ax, &mut ay).unwrap();
            // A camera point, its rectified pixel (x, y) = P R p on the grid, and the map
            // there: the model's pixel of p.
            let (xi, yi) = (30.0, 20.0);
            let p = mat_t_vec(&r, [(xi - out.cx_px) / out.fx_px, (yi - out.cy_px) / out.fy_px, 1.0]).map(|v| 500.0 * v);
            let q = mat_vec(&r, p);
            assert!((out.fx_px * q[0] / q[2] + out.cx_px - xi).abs() < 1e-9);
            let want = project_camera_point(p, &k, &d).unwrap();
            let i = yi as usize * 64 + xi as usize;
            assert!((ax[i] as f64 - want[0]).abs() < 1e-3 && (ay[i] as f64 - want[1]).abs() < 1e-3);
        }
    }
    #[test]
    fn a_bad_rotation_writes_nothing() {
        let model = CameraModel::paper_rig();
        let (k, d) = (model.intrinsics(150.0).unwrap(), model.distortion(150.0).unwrap());
        let out = OutputCamera::of_intrinsics(&k, 4, 4).unwrap();
        let (mut mx, mut my) = ([7f32; 16], [7f32; 16]);
        let bad = [[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(rectify_maps(&k, &d, &bad, &out, 0..4, &mut mx, &mut my).is_err());
        assert!(mx.iter().chain(my.iter()).all(|&v| v == 7.0));
    }
}
