//! Bouguet's rectification of a calibrated pair, as `cv2.stereoRectify` computes it with
//! its defaults (`CALIB_ZERO_DISPARITY`, `alpha = -1`: no scaling to the valid region).
//!
//! With om the Rodrigues vector of R, each camera turns by half of it towards the other,
//! r = R(-om / 2), which makes the two image planes parallel; t = r T is the baseline in
//! that frame, along axis i (x when |t_x| > |t_y|, else y). A second rotation w about
//! t x e_i, by acos(|t_i| / |t|), brings the baseline onto e_i:
//!
//! ```text
//! R1 = W r^T,   R2 = W r,   t' = R2 T
//! ```
//!
//! The new focal length f is the mean of the two cameras' focal lengths across the
//! baseline (fy for a horizontal baseline), as OpenCV 5 takes it (OpenCV 4 took the
//! smaller, each reduced by a negative k1 as f (1 + k1 (w^2 + h^2) / (4 f^2))). Each
//! camera's new principal point centres its image: the four image corners are undistorted
//! (OpenCV's 5 fixed-point iterations, its float32 points), rotated by R_k and projected
//! with f, and c_k = ((w - 1) / 2, (h - 1) / 2) minus their mean; with
//! `CALIB_ZERO_DISPARITY` both cameras take the mean of c_1 and c_2. Then
//!
//! ```text
//! P1 = [f 0 cx 0; 0 f cy 0; 0 0 1 0],   P2 = P1 with P2[i][3] = t'_i f
//! Q  = [1 0 0 -cx; 0 1 0 -cy; 0 0 0 f; 0 0 -1/t'_i (c1_i - c2_i)/t'_i]
//! ```
//!
//! (Q maps (u, v, disparity, 1) to homogeneous 3-D points in the rectified left frame;
//! with zero disparity the last term is 0.)

use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use etl_formats::{Error, Result};

use crate::zhang::ZhangResult;

/// What [`rectify`] returns (etl-formats', which the exports write).
pub use etl_formats::export::stereo::Rectification;

/// One camera as Bouguet's rectification sees it: its focal lengths, px, and the
/// normalised undistorted point ((u - u0) / fx, (v - v0) / fy after undistortion) of an
/// image pixel, by which the image's corners are centred.
pub struct RectifyCamera<'a> {
    /// fx, fy, px.
    pub focal_px: [f64; 2],
    /// Pixel -> normalised undistorted point.
    pub normalise: &'a dyn Fn([f64; 2]) -> etl_core::Result<[f64; 2]>,
}

/// OpenCV's `cvUndistortPoints` of one pixel with 5 fixed-point iterations (its default
/// criterion), camera `[fx, fy, u0, v0]`, OpenCV's model `k` = [k1, k2, p1, p2, k3]: the
/// normalised point.
pub fn undistort_opencv([fx, fy, u0, v0]: [f64; 4], k: &[f64; 5], [u, v]: [f64; 2]) -> [f64; 2] {
    let (x0, y0) = ((u - u0) / fx, (v - v0) / fy);
    let (mut x, mut y) = (x0, y0);
    for _ in 0..5 {
        let r2 = x * x + y * y;
        let icdist = 1.0 / (1.0 + ((k[4] * r2 + k[1]) * r2 + k[0]) * r2);
        if icdist < 0.0 {
            return [x0, y0];
        }
        let dx = 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x);
        let dy = k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y;
        x = (x0 - dx) * icdist;
        y = (y0 - dy) * icdist;
    }
    [x, y]
}

/// The centring principal point of one camera (module docs): `((w - 1) / 2, (h - 1) / 2)`
/// minus the mean of its four image corners undistorted, rotated by `r` and projected
/// with focal length `f` about 0, float32 where OpenCV's points are.
fn centring(cam: &RectifyCamera<'_>, r: &Mat3, f: f64, [w, h]: [f64; 2]) -> Result<[f64; 2]> {
    let f32r = |x: f64| x as f32 as f64;
    let mut sum = [0.0; 2];
    for (u, v) in [(0.0, 0.0), (w - 1.0, 0.0), (0.0, h - 1.0), (w - 1.0, h - 1.0)] {
        let [x, y] = (cam.normalise)([u, v])?.map(f32r);
        let p = mat_vec(r, [x, y, 1.0]);
        sum[0] += f32r(f * p[0] / p[2]);
        sum[1] += f32r(f * p[1] / p[2]);
    }
    Ok([(w - 1.0) / 2.0 - sum[0] / 4.0, (h - 1.0) / 2.0 - sum[1] / 4.0])
}

/// The rectifying rotations (R1, R2), the baseline t' = R2 T and its axis i (module docs).
fn rotations(rotation_rodrigues: [f64; 3], translation_mm: [f64; 3]) -> Result<(Mat3, Mat3, [f64; 3], usize)> {
    let r = rodrigues_to_matrix(rotation_rodrigues.map(|v| -0.5 * v));
    let t = mat_vec(&r, translation_mm);
    let i = if t[0].abs() > t[1].abs() { 0 } else { 1 };
    let nt = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    if !(nt > 0.0) {
        return Err(Error::invalid("translation_mm", "rectification needs a non-zero baseline T"));
    }
    let mut e = [0.0; 3];
    e[i] = if t[i] > 0.0 { 1.0 } else { -1.0 };
    let mut w = [t[1] * e[2] - t[2] * e[1], t[2] * e[0] - t[0] * e[2], t[0] * e[1] - t[1] * e[0]];
    let nw = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    if nw > 0.0 {
        let s = (t[i].abs() / nt).min(1.0).acos() / nw;
        w = w.map(|v| v * s);
    }
    let wr = rodrigues_to_matrix(w);
    let mul = |a: &Mat3, b: &Mat3, bt: bool| -> Mat3 {
        core::array::from_fn(|p| {
            core::array::from_fn(|q| (0..3).map(|k| a[p][k] * if bt { b[q][k] } else { b[k][q] }).sum())
        })
    };
    let (r1, r2) = (mul(&wr, &r, true), mul(&wr, &r, false));
    Ok((r1, r2, mat_vec(&r2, translation_mm), i))
}

/// Bouguet's rectification of a pair in OpenCV's model (module docs): `left`, `right` the
/// cameras (each with OpenCV's `dist_coeffs`), `image_size` px (both cameras'), R, T from
/// the left camera's frame to the right's; `zero_disparity`: OpenCV's
/// `CALIB_ZERO_DISPARITY` (one principal point for both, its default).
///
/// Errors: a camera of the paper's family (`"model"`: OpenCV's rectification is defined
/// for its model; [`rectify_cameras`] takes any camera), a zero baseline
/// (`"translation_mm"`).
pub fn rectify(
    (left, right): (&ZhangResult, &ZhangResult),
    image_size: [u32; 2],
    pose: ([f64; 3], [f64; 3]),
    zero_disparity: bool,
) -> Result<Rectification> {
    let (Some(dl), Some(dr)) = (left.dist_coeffs(), right.dist_coeffs()) else {
        return Err(Error::invalid("model", "rectification in OpenCV's conventions needs --model opencv"));
    };
    let kl = [left.fx, left.fy, left.u0, left.v0];
    let kr = [right.fx, right.fy, right.u0, right.v0];
    let nl = move |p: [f64; 2]| Ok(undistort_opencv(kl, &dl, p));
    let nr = move |p: [f64; 2]| Ok(undistort_opencv(kr, &dr, p));
    rectify_cameras(
        (
            &RectifyCamera { focal_px: [left.fx, left.fy], normalise: &nl },
            &RectifyCamera { focal_px: [right.fx, right.fy], normalise: &nr },
        ),
        image_size,
        pose,
        zero_disparity,
    )
}

/// Bouguet's rectification (module docs) of any two cameras: as [`rectify`], with each
/// image corner normalised by the camera's own `normalise` (OpenCV's 5 iterations for
/// `cv2.stereoRectify`'s numbers, or a model's exact inverse).
///
/// Errors: a zero baseline (`"translation_mm"`), a corner the camera cannot undistort.
pub fn rectify_cameras(
    (left, right): (&RectifyCamera<'_>, &RectifyCamera<'_>),
    image_size: [u32; 2],
    (rotation_rodrigues, translation_mm): ([f64; 3], [f64; 3]),
    zero_disparity: bool,
) -> Result<Rectification> {
    let (r1, r2, t, i) = rotations(rotation_rodrigues, translation_mm)?;
    let size = [image_size[0] as f64, image_size[1] as f64];
    let across = |c: &RectifyCamera<'_>| if i == 0 { c.focal_px[1] } else { c.focal_px[0] };
    let f = 0.5 * (across(left) + across(right));
    let mut c = [centring(left, &r1, f, size)?, centring(right, &r2, f, size)?];
    if zero_disparity {
        let mean = [0.5 * (c[0][0] + c[1][0]), 0.5 * (c[0][1] + c[1][1])];
        c = [mean, mean];
    } else {
        let j = 1 - i;
        let mean = 0.5 * (c[0][j] + c[1][j]);
        c[0][j] = mean;
        c[1][j] = mean;
    }
    let p = |cc: [f64; 2]| [[f, 0.0, cc[0], 0.0], [0.0, f, cc[1], 0.0], [0.0, 0.0, 1.0, 0.0]];
    let (p1, mut p2) = (p(c[0]), p(c[1]));
    p2[i][3] = t[i] * f;
    let q = [
        [1.0, 0.0, 0.0, -c[0][0]],
        [0.0, 1.0, 0.0, -c[0][1]],
        [0.0, 0.0, 0.0, f],
        [0.0, 0.0, -1.0 / t[i], (c[0][i] - c[1][i]) / t[i]],
    ];
    Ok(Rectification { r1, r2, p1, p2, q })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
        core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    }

    /// The rectified frames are parallel (R2 R R1^T = I, the relative rotation removed) and
    /// the baseline lies along x (horizontal pair) or y (vertical pair) in them.
    #[test]
    fn rectified_frames_are_parallel_with_the_baseline_on_an_axis() {
        for (t, axis) in [([-120.0, 1.5, 4.0], 0), ([3.0, 95.0, -6.0], 1)] {
            let om = [0.01, -0.14, 0.005];
            let (r1, r2, tp, i) = rotations(om, t).unwrap();
            assert_eq!(i, axis);
            let r = rodrigues_to_matrix(om);
            let r1t: Mat3 = core::array::from_fn(|a| core::array::from_fn(|b| r1[b][a]));
            let m = mul(&mul(&r2, &r), &r1t);
            for (a, row) in m.iter().enumerate() {
                for (b, v) in row.iter().enumerate() {
                    assert!((v - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15, "{m:?}");
                }
            }
            let n = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            assert!((tp[axis].abs() - n).abs() < 1e-12 && tp[1 - axis].abs() < 1e-12 && tp[2].abs() < 1e-12, "{tp:?}");
        }
        assert!(rotations([0.0; 3], [0.0; 3]).is_err());
    }
}
