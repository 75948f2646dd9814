//! The calibration part of a triangulated point's covariance from the joint covariance of
//! all the rig's numbers ([`RigCalibration::covariance`]), the cross-covariances kept: a
//! diagnosis of [`etl_calib::rig::RigAt::triangulate`]'s part, which takes each camera's
//! calibration and each pose as independent groups (the rig file holds no more).
//!
//! X(theta) is the triangulation of the fixed pixels through the models of theta (every
//! camera's numbers, its pose to the stage's world frame among them; the rig's pose from
//! the two world poses, [`relative_pose`], at the settings by Eq. R2);
//! dX/dtheta by central differences, each number stepped by 1e-3 of its standard
//! deviation; Cov = J C J^T.

use etl_calib::rig_calibration::RigCalibration;
use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::model::rotation::Mat3;
use etl_core::model::CameraModel;
use etl_core::runtime::rig::{centre_shift_mm, triangulate, RigPose, TriangulationView};
use etl_core::runtime::{Camera, Trust};
use etl_formats::rig::relative_pose;
use etl_formats::Result;

/// The point triangulated from `pixels` through `models` at `e_com_ma`, in camera 0's
/// frame at its setting.
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

/// J C J^T (module docs) for the point of `pixels` at `e_com_ma` through the rig
/// `calibrated`.
pub fn joint_calibration_part(calibrated: &RigCalibration, e_com_ma: [f64; 2], pixels: [[f64; 2]; 2]) -> Result<Mat3> {
    let models = [calibrated.model(0)?, calibrated.model(1)?];
    let c = &calibrated.covariance;
    let mut jac: Vec<(usize, [f64; 3])> = vec![];
    for k in 0..2 {
        let layout = models[k].layout();
        let theta = to_params(&models[k]);
        for i in 0..layout.len() {
            let g = calibrated.offsets[k] + i;
            let sd = c[(g, g)].max(0.0).sqrt();
            if sd == 0.0 {
                continue;
            }
            let h = 1e-3 * sd;
            let moved = |d: f64| -> Result<[f64; 3]> {
                let mut x = theta;
                x[i] += d;
                let mut m = models;
                m[k] = from_params(&layout, &x);
                triangulate_models(&m, e_com_ma, pixels)
            };
            let (p, m) = (moved(h)?, moved(-h)?);
            jac.push((g, std::array::from_fn(|a| (p[a] - m[a]) / (2.0 * h))));
        }
    }
    let mut cov = [[0.0; 3]; 3];
    for (a, ja) in &jac {
        for (b, jb) in &jac {
            let cab = c[(*a, *b)];
            for p in 0..3 {
                for q in 0..3 {
                    cov[p][q] += ja[p] * cab * jb[q];
                }
            }
        }
    }
    Ok(cov)
}
