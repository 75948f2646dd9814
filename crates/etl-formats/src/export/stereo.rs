//! Exports of a calibrated, rectified camera pair at one setting of each camera: OpenCV's
//! stereo FileStorage YAML (what `etlcal stereo --opencv-yaml` writes: `cv2.FileStorage`
//! readable), a ROS stereo `camera_info` pair (left and right, R = R1 / R2, P = P1 / P2 as
//! stereo_image_proc reads them: `P2[0][3] = -fx' B` for a horizontal baseline B) and mrcal
//! `.cameramodel`s with the rig's extrinsics ([`super::mrcal_cameramodel`]).
//!
//! Each camera is written with OpenCV's five coefficients: exact for a calibration of the
//! opencv family, fitted over the image for the paper's ([`super`] module docs, its
//! [`super::header`] stating the fit's error); R1, R2, P1, P2, Q are the pair's
//! rectification as computed from the model ([`Rectification`]).

use etl_core::model::{fit_opencv5, OpenCvFit};
use etl_core::runtime::CameraAt;

use super::{header, list, num, ros_camera_info};
use crate::Result;

/// Bouguet's rectification of a pair, in `cv2.stereoRectify`'s conventions: the
/// rectifying rotations and projections of both cameras and the disparity-to-depth matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rectification {
    /// The left camera's rectifying rotation (its frame to the rectified one).
    pub r1: [[f64; 3]; 3],
    /// The right camera's.
    pub r2: [[f64; 3]; 3],
    /// The left camera's projection in the rectified frame, 3 x 4, px.
    pub p1: [[f64; 4]; 3],
    /// The right camera's, with the baseline in its last column (px mm).
    pub p2: [[f64; 4]; 3],
    /// The disparity-to-depth matrix, 4 x 4.
    pub q: [[f64; 4]; 4],
}

/// One camera of a pair as OpenCV writes it: K and its five coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenCvCamera {
    /// K, px (row-major).
    pub camera_matrix: [[f64; 3]; 3],
    /// k1, k2, p1, p2, k3.
    pub dist_coeffs: [f64; 5],
}

/// A pair for OpenCV's stereo YAML: the cameras, R and T (X_right = R X_left + T, mm),
/// their rectification, and the stereo fit's RMS when there is one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenCvStereo {
    /// Both cameras' image size, px.
    pub image_size: [u32; 2],
    /// The left and right cameras.
    pub cameras: [OpenCvCamera; 2],
    /// R, row-major.
    pub rotation: [[f64; 3]; 3],
    /// T, mm.
    pub translation_mm: [f64; 3],
    /// R1, R2, P1, P2, Q.
    pub rectification: Rectification,
    /// The fit's RMS reprojection error, px (`rms_px`; none for a rig at a setting).
    pub rms_px: Option<f64>,
}

/// One matrix of OpenCV's FileStorage YAML, rows of numbers in full precision.
fn yaml_matrix(name: &str, rows: &[&[f64]]) -> String {
    let cols = rows.first().map_or(0, |r| r.len());
    let data = list(rows.iter().flat_map(|r| r.iter().copied()));
    format!("{name}: !!opencv-matrix\n   rows: {}\n   cols: {cols}\n   dt: d\n   data: [ {data} ]\n", rows.len())
}

/// OpenCV's stereo FileStorage YAML of `pair` after the comment lines `header`:
/// `image_width`, `image_height`, `K1`, `D1`, `K2`, `D2`, `R`, `T`, `R1`, `R2`, `P1`,
/// `P2`, `Q` (and `rms_px` when known), `cv2.FileStorage` readable.
pub fn opencv_stereo_yaml(header: &str, pair: &OpenCvStereo) -> String {
    let m3 = |m: &[[f64; 3]; 3]| -> Vec<Vec<f64>> { m.iter().map(|row| row.to_vec()).collect() };
    let m4 = |m: &[[f64; 4]]| -> Vec<Vec<f64>> { m.iter().map(|row| row.to_vec()).collect() };
    let (t, [l, r], x) = (pair.translation_mm, pair.cameras, &pair.rectification);
    let blocks: [(&str, Vec<Vec<f64>>); 11] = [
        ("K1", m3(&l.camera_matrix)),
        ("D1", vec![l.dist_coeffs.to_vec()]),
        ("K2", m3(&r.camera_matrix)),
        ("D2", vec![r.dist_coeffs.to_vec()]),
        ("R", m3(&pair.rotation)),
        ("T", vec![vec![t[0]], vec![t[1]], vec![t[2]]]),
        ("R1", m3(&x.r1)),
        ("R2", m3(&x.r2)),
        ("P1", m4(&x.p1)),
        ("P2", m4(&x.p2)),
        ("Q", m4(&x.q)),
    ];
    let [w, h] = pair.image_size;
    let mut text = format!("%YAML:1.0\n---\n{header}image_width: {w}\nimage_height: {h}\n");
    for (name, rows) in &blocks {
        let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
        text += &yaml_matrix(name, &rows);
    }
    if let Some(rms) = pair.rms_px {
        text += &format!("rms_px: {}\n", num(rms));
    }
    text
}

/// A camera at its setting as the exports write it: K, the five coefficients (exact or
/// fitted over `image_size`) and the comment lines saying which, with the fit.
pub fn opencv_camera(camera: &CameraAt, image_size: [u32; 2]) -> Result<(OpenCvCamera, OpenCvFit, String)> {
    let k = camera.intrinsics();
    let fit = fit_opencv5(k, camera.distortion(), image_size)?;
    let header = header(camera, &fit);
    Ok((OpenCvCamera { camera_matrix: k.matrix(), dist_coeffs: fit.dist_coeffs }, fit, header))
}

/// The ROS stereo pair's two `camera_info` YAMLs (left, right) of `pair`, the cameras
/// named `names`, each after its camera's comment lines `headers`.
pub fn ros_stereo_pair(pair: &OpenCvStereo, names: [&str; 2], headers: [&str; 2]) -> [String; 2] {
    let x = &pair.rectification;
    let one = |c: usize, r: &[[f64; 3]; 3], p: &[[f64; 4]; 3]| {
        let cam = &pair.cameras[c];
        ros_camera_info(headers[c], names[c], pair.image_size, (&cam.camera_matrix, &cam.dist_coeffs), (r, p))
    };
    [one(0, &x.r1, &x.p1), one(1, &x.r2, &x.p2)]
}
