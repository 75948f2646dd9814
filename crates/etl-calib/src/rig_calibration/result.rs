//! [`RigCalibration`]: what [`super::calibrate_rig`] gives, and its `etlcal.rig/1`.

use std::path::Path;

use etl_core::calib::jacobian::to_params;
use etl_core::calib::params::MAX_PARAMS;
use etl_core::model::CameraModel;
use etl_formats::calibration::{Calibration, ModelStd};
use etl_formats::rig::{JointCovariance, RigCamera, RigExtrinsics, RigFile};
use etl_formats::{Result, SettingKind};
use nalgebra::DMatrix;

use crate::request::CalibrationRequest;

/// One camera of a calibrated rig.
#[derive(Debug, Clone)]
pub struct RigCameraResult {
    /// Its name.
    pub name: String,
    /// Its image size, px.
    pub image_size: [u32; 2],
    /// Its calibration from the joint solve (numbers, standard deviations and covariance
    /// from the joint covariance, RMS and view corrections of the joint solve).
    pub calibration: Calibration,
    /// Its own calibration, alone (the joint solve's start).
    pub own: Calibration,
    /// Its RMS reprojection distance in the joint solve, px.
    pub rms_px: f64,
    /// The request it was calibrated with alone (the rig's or its own).
    pub request: CalibrationRequest,
}

/// A calibrated rig (module docs of [`super`]).
#[derive(Debug, Clone)]
pub struct RigCalibration {
    /// The cameras, in the dataset's order.
    pub cameras: Vec<RigCameraResult>,
    /// The pose of each camera k >= 1 relative to camera 0 at E = 0 of both
    /// (`reference_setting` [0, 0]), with its 6 x 6 covariance (rad, mm).
    pub extrinsics: Vec<RigExtrinsics>,
    /// The covariance of every camera's numbers jointly, each camera's in its layout's
    /// order, cameras stacked ([`Self::offsets`]).
    pub covariance: DMatrix<f64>,
    /// Where each camera's numbers start in [`Self::covariance`].
    pub offsets: Vec<usize>,
    /// The estimated stage correction of each rig view, mm (zeros with the paper's
    /// estimator).
    pub dz_mm: Vec<f64>,
    /// Each free view's board pose (Rodrigues, translation mm), board to world (the
    /// stage's frame), in the dataset's order.
    pub free_view_poses: Vec<([f64; 3], [f64; 3])>,
    /// `"eiv"` or `"paper"`.
    pub estimator: String,
    /// Iterations of the joint solve.
    pub iterations: usize,
    /// The cost (sum of squared normalised residuals and priors) at the start and at the
    /// end of the joint solve.
    pub cost: [f64; 2],
    /// Whether the joint steps took the sparse path.
    pub sparse: bool,
}

impl RigCalibration {
    /// Camera k's model from the joint solve.
    pub fn model(&self, k: usize) -> Result<CameraModel> {
        self.cameras[k].calibration.model()
    }

    /// The distance between camera 0's and camera k's centres at E = 0, mm: |T| (the
    /// centre of camera 0 seen from camera k is T, so |T| is the baseline).
    pub fn baseline_mm(&self, k: usize) -> Option<f64> {
        let e = self.extrinsics.iter().find(|e| e.camera == k)?;
        Some(e.translation_mm.iter().map(|t| t * t).sum::<f64>().sqrt())
    }

    /// The rig as `etlcal.rig/1`, each calibration inline, with [`Self::covariance`] as
    /// its `joint_covariance` (the extrinsics are the relative poses of the calibrations'
    /// poses to the stage, as the format asks).
    pub fn rig_file(&self) -> RigFile {
        let cameras = self
            .cameras
            .iter()
            .map(|c| RigCamera {
                name: c.name.clone(),
                image_size: c.image_size,
                calibration: Some(Box::new(c.calibration.clone())),
                calibration_path: None,
            })
            .collect();
        let n = self.covariance.nrows();
        let matrix = (0..n)
            .map(|i| (0..n).map(|j| 0.5 * (self.covariance[(i, j)] + self.covariance[(j, i)])).collect())
            .collect();
        RigFile {
            joint_covariance: Some(JointCovariance { cameras: (0..self.cameras.len()).collect(), matrix }),
            ..RigFile::new(cameras, self.extrinsics.clone())
        }
    }

    /// Writes [`Self::rig_file`] atomically after its checks (nothing written if they fail).
    pub fn save(&self, path: &Path) -> Result<()> {
        self.rig_file().save(path)
    }
}

/// `own` with the numbers of `m`, the standard deviations and covariance of `cov` (the
/// layout's square), the RMS `rms_px`, each view's corrections and the iterations.
pub(super) fn joint_calibration(
    own: &Calibration,
    m: &CameraModel,
    cov: &DMatrix<f64>,
    (rms_px, corrections): (f64, &[[f64; 2]]),
    iterations: usize,
) -> Result<Calibration> {
    let fresh = Calibration::from_model(m, own.image_size, own.e_com_range_ma);
    let mut c = own.clone();
    c.rotation_rodrigues = fresh.rotation_rodrigues;
    c.translation_mm = fresh.translation_mm;
    c.kf_x = fresh.kf_x;
    c.kf_y = fresh.kf_y;
    c.principal_point = fresh.principal_point;
    c.distortion_a = fresh.distortion_a;
    c.centre = fresh.centre;
    let layout = m.layout();
    let p = layout.len();
    let std: Vec<f64> = (0..p).map(|i| cov[(i, i)].max(0.0).sqrt()).collect();
    c.std = ModelStd::from_params(&layout, &std);
    let mut full = [[0.0; MAX_PARAMS]; MAX_PARAMS];
    for (i, row) in full.iter_mut().enumerate().take(p) {
        for (j, x) in row.iter_mut().enumerate().take(p) {
            *x = cov[(i, j)];
        }
    }
    c.set_covariance(&full)?;
    c.rms_reprojection_px = rms_px;
    c.iterations = iterations;
    let focal_power = own.setting_kind() == SettingKind::FocalPower;
    for (v, [dz, de]) in c.views.iter_mut().zip(corrections) {
        v.dz_mm = *dz;
        if focal_power {
            v.de_dpt = Some(*de);
        } else {
            v.de_ma = *de;
        }
    }
    Ok(c)
}

/// The pose numbers (om, t) of `m`, and their indices in its layout.
pub(super) fn pose_of(m: &CameraModel) -> ([f64; 6], [usize; 6]) {
    let x = to_params(m);
    let l = m.layout();
    let idx = [
        l.rotation().at(0),
        l.rotation().at(1),
        l.rotation().at(2),
        l.translation().at(0),
        l.translation().at(1),
        l.translation().at(2),
    ];
    (idx.map(|i| x[i]), idx)
}
