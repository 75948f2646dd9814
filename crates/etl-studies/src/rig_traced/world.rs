//! A triangulated point in the stage's world frame, with its covariance: the
//! frame-independent measure of the traced rig's acceptance (module docs of
//! [`super`]).
//!
//! The rig triangulates X in camera 0's frame at its setting E_0 (the calibrated model's
//! frame, whose origin is wherever the calibration put camera 0's centre). Camera 0's
//! calibrated pose to the stage (R_0, t_0(E_0) = t_0 - dz_0(E_0) e_z: Eq. C2) maps it to
//! the world, where the truth is exact (board corners at known stage positions):
//!
//! ```text
//! W = R_0' (X - t_0(E_0))
//! Cov_W = R_0' Cov_pixels R_0 + J Sigma_joint J'
//! ```
//!
//! with Sigma_joint the joint calibration's covariance of every camera's numbers (camera
//! 0's pose among them) and J = dW/dtheta by central differences: W re-triangulated
//! through the models with number i stepped by 1e-3 of its standard deviation (the step
//! of `etl_calib::rig::RigAt::triangulate`'s own derivatives), the poses between the
//! cameras recomputed from the models' poses to the world (what the joint covariance
//! means). The cross-covariance between X and camera 0's pose, which the camera-frame
//! covariance cannot carry, is in J.

use etl_core::model::rotation::{mat_t_vec, Mat3};
use etl_core::model::CameraModel;
use etl_core::runtime::rig::{centre_shift_mm, triangulate, RigPose, TriangulationView};
use etl_core::runtime::{Camera, Trust};
use etl_formats::rig::relative_pose;
use etl_formats::Result;
use nalgebra::DMatrix;

/// The point seen at `pixels` through `models` (camera 0 first; each with its pose to
/// the world) at compensated currents `e_com_ma`, in camera 0's frame at its setting:
/// camera 1's pose from the models' poses to the world at E = 0, moved to the settings
/// by Eq. R2 (each moving centre's shift).
pub fn triangulate_models(models: &[CameraModel; 2], e_com_ma: [f64; 2], pixels: [[f64; 2]; 2]) -> Result<[f64; 3]> {
    let at = |k: usize| -> Result<_> {
        let e = e_com_ma[k];
        Ok(Camera::new(models[k], None, [e, e])?.at_e_com(e, Trust::Extrapolate)?)
    };
    let (c0, c1) = (at(0)?, at(1)?);
    let pose = |m: &CameraModel| (m.rotation_rodrigues, m.translation_mm);
    let (om, t) = relative_pose(pose(&models[0]), pose(&models[1]));
    let shift = |k: usize| centre_shift_mm(&models[k], e_com_ma[k], 0.0);
    let pose1 = RigPose::from_rodrigues(om, t).at_settings(shift(0), shift(1));
    let views = [
        TriangulationView { camera: &c0, pose: RigPose::IDENTITY, pixel: pixels[0] },
        TriangulationView { camera: &c1, pose: pose1, pixel: pixels[1] },
    ];
    Ok(triangulate(&views, 1.0)?.point_mm)
}

/// Camera 0's frame at `e0_ma` to the world: W = R_0' (X - t_0(E_0)).
pub fn to_world(model0: &CameraModel, e0_ma: f64, camera_mm: [f64; 3]) -> [f64; 3] {
    let t = model0.translation_at(e0_ma);
    mat_t_vec(&model0.rotation_matrix(), [camera_mm[0] - t[0], camera_mm[1] - t[1], camera_mm[2] - t[2]])
}

/// The world point of `pixels` through `models` (module docs).
pub fn world_point(models: &[CameraModel; 2], e_com_ma: [f64; 2], pixels: [[f64; 2]; 2]) -> Result<[f64; 3]> {
    Ok(to_world(&models[0], e_com_ma[0], triangulate_models(models, e_com_ma, pixels)?))
}

/// dW/dtheta (3 x n) over both models' numbers in the joint covariance's order (each
/// model's parameter vector, camera 0's first), each number stepped by 1e-3 of its
/// standard deviation in `joint` (skipped where that is 0).
pub fn world_jacobian(
    models: &[CameraModel; 2],
    e_com_ma: [f64; 2],
    pixels: [[f64; 2]; 2],
    joint: &DMatrix<f64>,
) -> Result<Vec<[f64; 3]>> {
    use etl_core::calib::jacobian::{from_params, to_params};
    let mut jac = vec![];
    for k in 0..2 {
        let layout = models[k].layout();
        let theta = to_params(&models[k]);
        for i in 0..layout.len() {
            let n = jac.len();
            let h = 1e-3 * joint[(n, n)].max(0.0).sqrt();
            if h == 0.0 {
                jac.push([0.0; 3]);
                continue;
            }
            let moved = |d: f64| {
                let mut x = theta;
                x[i] += d;
                let mut m = *models;
                m[k] = from_params(&layout, &x);
                world_point(&m, e_com_ma, pixels)
            };
            let (p, m) = (moved(h)?, moved(-h)?);
            jac.push(std::array::from_fn(|a| (p[a] - m[a]) / (2.0 * h)));
        }
    }
    Ok(jac)
}

/// J Sigma J' (3 x 3) for `jac` (n rows of dW/dtheta_i) and the n x n `joint`.
pub fn propagate(jac: &[[f64; 3]], joint: &DMatrix<f64>) -> Mat3 {
    let mut cov = [[0.0; 3]; 3];
    for (a, ja) in jac.iter().enumerate() {
        for (b, jb) in jac.iter().enumerate() {
            let s = joint[(a, b)];
            if s == 0.0 {
                continue;
            }
            for p in 0..3 {
                for q in 0..3 {
                    cov[p][q] += ja[p] * s * jb[q];
                }
            }
        }
    }
    cov
}

/// R' C R: a camera-frame covariance in the world (R world to camera).
pub fn rotate_to_world(r: &Mat3, c: &Mat3) -> Mat3 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..3).map(|a| (0..3).map(|b| r[a][i] * c[a][b] * r[b][j]).sum::<f64>()).sum())
    })
}
