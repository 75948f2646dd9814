//! [`RigAt`]: the rig at one setting and temperature per camera.

use etl_core::runtime::rig::RigPose;
use etl_formats::calibration::Calibration;
use etl_formats::rig::{JointCovariance, RigExtrinsics};
use etl_formats::{CameraAt, Error, Result};

use super::Rig;

/// The rig at one moment: each camera at its setting and its pose relative to camera 0 at
/// these settings ([`Rig::at`]).
#[derive(Debug, Clone)]
pub struct RigAt {
    names: Vec<String>,
    image_sizes: Vec<[u32; 2]>,
    calibrations: Vec<Calibration>,
    extrinsics: Vec<Option<RigExtrinsics>>,
    cameras: Vec<CameraAt>,
    poses: Vec<RigPose>,
    joint_covariance: Option<JointCovariance>,
}

impl RigAt {
    pub(super) fn new(rig: &Rig, cameras: Vec<CameraAt>, poses: Vec<RigPose>) -> Self {
        let n = rig.len();
        RigAt {
            names: (0..n).map(|k| rig.name(k).to_owned()).collect(),
            image_sizes: rig.file().cameras.iter().map(|c| c.image_size).collect(),
            calibrations: rig.calibrations().to_vec(),
            extrinsics: (0..n).map(|k| rig.extrinsics(k).cloned()).collect(),
            cameras,
            poses,
            joint_covariance: rig.file().joint_covariance.clone(),
        }
    }

    /// Number of cameras.
    pub fn len(&self) -> usize {
        self.cameras.len()
    }

    /// Never empty (at least 2 cameras); for the `len`/`is_empty` convention.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Each camera at its setting, in the rig's order.
    pub fn cameras(&self) -> &[CameraAt] {
        &self.cameras
    }

    /// Each camera's pose relative to camera 0 at these settings (X_k = R X_0 + T; camera
    /// 0's the identity), in the rig's order.
    pub fn poses(&self) -> &[RigPose] {
        &self.poses
    }

    /// Camera `k`'s name.
    pub fn name(&self, k: usize) -> &str {
        self.names.get(k).map_or("", String::as_str)
    }

    /// Camera `k`'s image size, px.
    pub fn image_size(&self, k: usize) -> Option<[u32; 2]> {
        self.image_sizes.get(k).copied()
    }

    /// Camera `k`'s calibration.
    pub fn calibration(&self, k: usize) -> Option<&Calibration> {
        self.calibrations.get(k)
    }

    /// Camera `k`'s pose as the rig file gives it, at its reference settings (camera 0:
    /// None).
    pub fn extrinsics_file(&self, k: usize) -> Option<&RigExtrinsics> {
        self.extrinsics.get(k).and_then(Option::as_ref)
    }

    /// The rig file's joint covariance of the cameras' numbers, if it has one.
    pub fn joint_covariance(&self) -> Option<&JointCovariance> {
        self.joint_covariance.as_ref()
    }

    /// Whether any camera is outside its calibrated ranges (`Trust::Extrapolate`).
    pub fn extrapolated(&self) -> bool {
        self.cameras.iter().any(CameraAt::extrapolated)
    }

    /// The index `k` checked against the rig (`what` names the argument in the error).
    pub(super) fn check_index(&self, k: usize, what: &str) -> Result<()> {
        if k < self.len() {
            return Ok(());
        }
        Err(Error::invalid_value(
            what,
            k,
            format!("{what}: camera {k} is not one of the rig's cameras 0..{}", self.len() - 1),
        ))
    }

    /// The pose of camera `j` relative to camera `i` at these settings: X_j = R X_i + T
    /// with R = R_j R_i^T, T = T_j - R T_i.
    pub fn relative_pose(&self, i: usize, j: usize) -> Result<RigPose> {
        self.check_index(i, "pair")?;
        self.check_index(j, "pair")?;
        let (a, b) = (&self.poses[i], &self.poses[j]);
        let r: [[f64; 3]; 3] =
            std::array::from_fn(|p| std::array::from_fn(|q| (0..3).map(|k| b.rotation[p][k] * a.rotation[q][k]).sum()));
        let rt = etl_core::model::rotation::mat_vec(&r, a.translation_mm);
        let t = std::array::from_fn(|p| b.translation_mm[p] - rt[p]);
        Ok(RigPose { rotation: r, translation_mm: t })
    }
}
