//! [`RigPose`]: the pose of a rig's camera k relative to camera 0, and how it follows the
//! two cameras' settings.
//!
//! Each camera's projection centre moves along its own +Z with its setting (Eq. C1-C2):
//! a point's coordinates in camera c's frame at setting E are those at the reference
//! setting less the centre's move,
//!
//! ```text
//! X_c(E) = X_c(E_ref) - s_c e_z,    s_c = dz_c(E) - dz_c(E_ref)         (R1)
//! ```
//!
//! With X_k(E_k,ref) = R_k X_0(E_0,ref) + T_k (the rig file's pose, at its reference
//! settings), substitute X_0(E_0,ref) = X_0(E_0) + s_0 e_z and X_k(E_k) = X_k(E_k,ref) - s_k e_z:
//!
//! ```text
//! X_k(E_k) = R_k (X_0(E_0) + s_0 e_z) + T_k - s_k e_z
//!          = R_k X_0(E_0) + T_k(E_0, E_k)
//! T_k(E_0, E_k) = T_k + s_0 R_k e_z - s_k e_z                            (R2)
//! ```
//!
//! The rotation does not change (the centres move, the cameras do not turn). Without a
//! moving centre s_c = 0 and the pose is the file's at every setting.

use crate::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use crate::model::CameraModel;

/// The pose of a camera relative to camera 0: X_k = R X_0 + T (`cv2.stereoCalibrate`'s
/// R, T for the pair (0, k)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigPose {
    /// R, row-major (camera 0's frame to camera k's).
    pub rotation: Mat3,
    /// T, mm.
    pub translation_mm: [f64; 3],
}

impl RigPose {
    /// Camera 0's own pose: R = I, T = 0.
    pub const IDENTITY: RigPose =
        RigPose { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], translation_mm: [0.0; 3] };

    /// The pose of Rodrigues vector `rotation_rodrigues` (rad) and `translation_mm`.
    pub fn from_rodrigues(rotation_rodrigues: [f64; 3], translation_mm: [f64; 3]) -> Self {
        RigPose { rotation: rodrigues_to_matrix(rotation_rodrigues), translation_mm }
    }

    /// A point of camera 0's frame in camera k's: R X_0 + T.
    #[inline]
    pub fn apply(&self, x0_mm: [f64; 3]) -> [f64; 3] {
        let r = mat_vec(&self.rotation, x0_mm);
        [r[0] + self.translation_mm[0], r[1] + self.translation_mm[1], r[2] + self.translation_mm[2]]
    }

    /// Camera k's projection centre in camera 0's frame, mm: -R^T T.
    pub fn centre_mm(&self) -> [f64; 3] {
        let t = self.translation_mm;
        let r = &self.rotation;
        core::array::from_fn(|j| -(r[0][j] * t[0] + r[1][j] * t[1] + r[2][j] * t[2]))
    }

    /// The pose at the settings (E_0, E_k) (module docs, Eq. R2): `self` holds at the
    /// reference settings; `shift_0_mm` = s_0 = dz_0(E_0) - dz_0(E_0,ref) and `shift_k_mm` =
    /// s_k = dz_k(E_k) - dz_k(E_k,ref) are the centres' moves since then
    /// ([`centre_shift_mm`]). T(E_0, E_k) = T + s_0 R e_z - s_k e_z; R unchanged.
    pub fn at_settings(&self, shift_0_mm: f64, shift_k_mm: f64) -> RigPose {
        let r = &self.rotation;
        let t = self.translation_mm;
        RigPose {
            rotation: *r,
            translation_mm: [
                t[0] + shift_0_mm * r[0][2],
                t[1] + shift_0_mm * r[1][2],
                t[2] + shift_0_mm * r[2][2] - shift_k_mm,
            ],
        }
    }
}

/// The move of `model`'s projection centre along its +Z from `reference` to `setting`
/// (both in the model's own setting, mA or dpt): s = dz(E) - dz(E_ref), mm (Eq. C1; 0 for
/// a fixed centre).
pub fn centre_shift_mm(model: &CameraModel, setting: f64, reference: f64) -> f64 {
    model.centre.as_ref().map_or(0.0, |c| c.dz_mm_at(setting) - c.dz_mm_at(reference))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::MovingCentre;

    /// Eq. R2 against a direct construction: a world point seen by two cameras placed in
    /// a world frame, each centre moved along its own axis by its model (Eq. C2), the pose
    /// between them read off at the reference settings and then at other settings.
    #[test]
    fn the_pose_at_settings_is_the_direct_construction() {
        let c0 = MovingCentre { dz_mm: [-8e-3, 1.5e-5], principal_point_slope_px: [0.0; 2] };
        let c1 = MovingCentre { dz_mm: [5e-3, -2e-5], principal_point_slope_px: [0.0; 2] };
        let mut m0 = CameraModel::strong_distortion_rig();
        m0.centre = Some(c0);
        let mut m1 = m0;
        (m1.rotation_rodrigues, m1.translation_mm, m1.centre) = ([0.07, -0.11, 0.03], [-160.0, -40.0, 210.0], Some(c1));
        // The pose from camera 0's frame to camera 1's at settings (e0, e1), built from the
        // world poses: X_c(E) = R_c W + T_c(E).
        let direct = |e0: f64, e1: f64| -> RigPose {
            let (r0, r1) = (m0.rotation_matrix(), m1.rotation_matrix());
            let r: Mat3 = core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| r1[i][k] * r0[j][k]).sum()));
            let (t0, t1) = (m0.translation_at(e0), m1.translation_at(e1));
            let rt0 = mat_vec(&r, t0);
            RigPose { rotation: r, translation_mm: core::array::from_fn(|i| t1[i] - rt0[i]) }
        };
        let (ref0, ref1) = (120.0, 150.0);
        let reference = direct(ref0, ref1);
        for (e0, e1) in [(80.0, 225.0), (200.0, 90.0), (120.0, 150.0), (160.0, 160.0)] {
            let got = reference.at_settings(centre_shift_mm(&m0, e0, ref0), centre_shift_mm(&m1, e1, ref1));
            let want = direct(e0, e1);
            for i in 0..3 {
                assert!((got.translation_mm[i] - want.translation_mm[i]).abs() < 1e-9, "{e0} {e1}: {got:?} {want:?}");
            }
            assert_eq!(got.rotation, reference.rotation);
            // And a world point lands on the same pixel of camera 1 both ways.
            let w = [30.0, -25.0, 60.0];
            let x0 = m0.world_to_camera_at(w, e0);
            let (k1, d1) = (m1.intrinsics(e1).unwrap(), m1.distortion(e1).unwrap());
            let via_rig = crate::model::projection::project_camera_point(got.apply(x0), &k1, &d1).unwrap();
            let direct_px = m1.project(w, e1).unwrap();
            assert!((via_rig[0] - direct_px[0]).abs() < 1e-8 && (via_rig[1] - direct_px[1]).abs() < 1e-8);
        }
        // The shift is not zero here: the test would pass for a constant pose otherwise.
        assert!(centre_shift_mm(&m0, 80.0, ref0).abs() > 0.1);
        assert_eq!(centre_shift_mm(&CameraModel::paper_rig(), 80.0, 150.0), 0.0);
    }

    #[test]
    fn the_centre_of_camera_k_in_camera_0() {
        let p = RigPose::from_rodrigues([0.0, 0.3, 0.0], [-100.0, 2.0, 5.0]);
        let c = p.centre_mm();
        let back = p.apply(c);
        assert!(back.iter().all(|v| v.abs() < 1e-12), "{back:?}");
    }
}
