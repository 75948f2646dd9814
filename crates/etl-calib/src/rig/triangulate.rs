//! [`RigAt::triangulate`]: a point from its pixels in two or more of the rig's cameras,
//! with its covariance from the pixel noise and from the calibration.
//!
//! The point X (camera 0's frame at its setting) is etl-core's least-squares
//! triangulation through each camera's full model ([`etl_core::runtime::rig::triangulate`]):
//! Cov_pixels = sigma_px^2 (J^T J)^-1, J the stacked 2 x 3 Jacobians of the views' pixels.
//!
//! The calibration's part: X depends on every number theta the views' projections use:
//! each used camera's model numbers (its focal polynomials, principal point, distortion,
//! moving centre: the calibration file's parameter vector, `covariance`'s order), camera
//! 0's too when its centre moves (its dz moves every pose, Eq. R2), and each used camera
//! k > 0's pose (R_k, T_k: the rig file's `rotation_rodrigues`, `translation_mm`). At the
//! minimum of C(X, theta) = |r(X, theta)|^2 the gradient J^T r vanishes; to first order
//! (residuals small against the Jacobians' change), dX/dtheta = -(J^T J)^-1 J^T dr/dtheta,
//! and
//!
//! ```text
//! Cov_calibration = sum_g A_g C_g A_g^T,   A_g = -(J^T J)^-1 J^T dr/dtheta_g
//! ```
//!
//! **With the rig file's `joint_covariance`** (a rig calibrated jointly: `etlcal
//! calibrate-rig`), theta is every camera's model numbers together, each camera's pose
//! (om, t) to the shared world among them, and the poses between the cameras follow from
//! those (R_k = R(om_k) R(om_0)^T, T_k = t_k - R_k t_0, then Eq. R2 at the settings), so
//! that a camera's pose enters through every extrinsic it makes:
//!
//! ```text
//! Cov_calibration = A Sigma_joint A^T,   A = -(J^T J)^-1 J^T dr/dtheta   (3 x sum of layouts)
//! ```
//!
//! the cross-covariances kept (a camera's focal polynomial with its pose to the stage,
//! both cameras through the shared stage's corrections): they cancel much of the depth
//! error. [`Triangulated::calibration_covariance`] is then
//! [`CalibrationCovariance::Joint`].
//!
//! **Without it**, the sum runs over independent groups g: each camera's calibration
//! (covariance C_g from its file) and each pose (its 6 x 6 `covariance`), assumed
//! independent of each other and of the pixel noise (each camera calibrated on its own
//! views, the poses from a stereo fit that held them); the calibration's pose numbers (om,
//! T of its board frame) then do not enter a rig's projection (their columns are zero).
//! For a rig calibrated jointly this over-states the depth sigma 2-3x (the
//! cross-covariances are dropped): [`CalibrationCovariance::Independent`] says so. In
//! both, the thermal part's uncertainty is not included (E_com is taken as exact).
//!
//! dr/dtheta: analytic for a pose (d pixel / d camera point, times I for T and
//! d(R(om) p)/d om = -R [p]x J_r(om) for om, with p = X + s_0 e_z), central differences
//! for the model's numbers (the joint path's poses to the world among them): each number
//! stepped by 1e-3 of its own standard deviation (sqrt of its variance in the file, the
//! calibration's or the joint one), small against the scale on which the projection
//! bends, large against rounding; a number with zero variance adds nothing and is skipped.

use etl_core::calib::jacobian::{from_params, project_camera_point_jacobian, rotate_point_jacobian, to_params};
use etl_core::model::projection::project_camera_point;
use etl_core::model::rotation::Mat3;
use etl_core::model::CameraModel;
use etl_core::runtime::rig::{centre_shift_mm, triangulate, RigPose, Triangulation, TriangulationView};
use etl_formats::rig::{relative_pose, JointCovariance};
use etl_formats::{Error, Result};

use super::RigAt;

/// Whether [`RigAt::triangulate`] adds the calibration's part of the covariance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationPart {
    /// Add it; a camera or pose without a covariance is refused.
    Include,
    /// The pixel noise alone (`from_calibration` is then `None`).
    PixelOnly,
}

/// Which covariance of the calibration [`RigAt::triangulate`] propagated (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationCovariance {
    /// The rig file's `joint_covariance`, cross-covariances kept.
    Joint,
    /// Each calibration and each pose as an independent group: for a rig calibrated
    /// jointly this over-states the depth sigma.
    Independent,
}

impl CalibrationCovariance {
    /// `"joint"` or `"independent"`.
    pub fn as_str(self) -> &'static str {
        match self {
            CalibrationCovariance::Joint => "joint",
            CalibrationCovariance::Independent => "independent",
        }
    }
}

/// A triangulated point and its covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct Triangulated {
    /// The point in camera 0's frame at its setting, mm.
    pub point_mm: [f64; 3],
    /// Its covariance, mm^2: `from_pixels` plus `from_calibration` (when included).
    pub covariance_mm2: Mat3,
    /// The pixel noise's part, sigma_px^2 (J^T J)^-1, mm^2.
    pub from_pixels: Mat3,
    /// The calibration's part (module docs), mm^2; None when not asked for.
    pub from_calibration: Option<Mat3>,
    /// Which covariance of the calibration `from_calibration` comes from; None when not
    /// asked for.
    pub calibration_covariance: Option<CalibrationCovariance>,
    /// The cameras whose pixels were used.
    pub cameras_used: Vec<usize>,
    /// RMS reprojection distance over them, px.
    pub rms_px: f64,
    /// Whether any camera is outside its calibrated ranges.
    pub extrapolated: bool,
}

impl Triangulated {
    /// One standard deviation per axis, mm: the square roots of the covariance's diagonal.
    pub fn std_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| self.covariance_mm2[i][i].max(0.0).sqrt())
    }
}

impl RigAt {
    /// The point seen at `pixels` (one entry per camera, in the rig's order: the observed
    /// pixel, or None for a camera that does not see it; at least two), with pixel noise
    /// `sigma_px` per coordinate, and the calibration's part of its covariance as `part`
    /// says (module docs).
    ///
    /// Errors (one line naming what is wrong): a count of pixels that is not the number of
    /// cameras (`"pixels"`); fewer than two pixels; rays nearly parallel; the point behind
    /// a camera; with [`CalibrationPart::Include`], a used camera's calibration without a
    /// covariance or a used pose without one (`"covariance"`, naming the camera).
    pub fn triangulate(
        &self,
        pixels: &[Option<[f64; 2]>],
        sigma_px: f64,
        part: CalibrationPart,
    ) -> Result<Triangulated> {
        if pixels.len() != self.len() {
            return Err(Error::invalid(
                "pixels",
                format!(
                    "pixels: the rig has {} cameras, got {} entries (one per camera, None where unseen)",
                    self.len(),
                    pixels.len()
                ),
            ));
        }
        let used: Vec<usize> = (0..self.len()).filter(|&k| pixels[k].is_some()).collect();
        let views: Vec<TriangulationView<'_>> = used
            .iter()
            .map(|&k| TriangulationView {
                camera: &self.cameras()[k],
                pose: self.poses()[k],
                pixel: pixels[k].unwrap_or_default(),
            })
            .collect();
        let t = triangulate(&views, sigma_px).map_err(|e| Error::from(e).within("triangulate", Some("pixels")))?;
        let (from_calibration, calibration_covariance) = match part {
            CalibrationPart::PixelOnly => (None, None),
            CalibrationPart::Include => {
                let (c, source) = self.calibration_covariance(&views, &used, &t)?;
                (Some(c), Some(source))
            }
        };
        let mut covariance_mm2 = t.covariance_mm2;
        if let Some(c) = &from_calibration {
            for i in 0..3 {
                for j in 0..3 {
                    covariance_mm2[i][j] += c[i][j];
                }
            }
        }
        Ok(Triangulated {
            point_mm: t.point_mm,
            covariance_mm2,
            from_pixels: t.covariance_mm2,
            from_calibration,
            calibration_covariance,
            extrapolated: used.iter().any(|&k| self.cameras()[k].extrapolated()),
            cameras_used: used,
            rms_px: t.rms_px,
        })
    }

    /// Cov_calibration (module docs) at the solution `t` of `views` (cameras `used`), and
    /// which covariance it propagated.
    fn calibration_covariance(
        &self,
        views: &[TriangulationView<'_>],
        used: &[usize],
        t: &Triangulation,
    ) -> Result<(Mat3, CalibrationCovariance)> {
        let x = t.point_mm;
        let jacobians: Vec<[[f64; 3]; 2]> =
            views.iter().map(|v| v.residual(x).map(|(_, j)| j)).collect::<etl_core::Result<_>>()?;
        // G = -(J^T J)^-1 J^T (3 x 2K): A_g = G dr/dtheta_g.
        let ni = &t.normal_inverse;
        let g: Vec<[[f64; 2]; 3]> = jacobians
            .iter()
            .map(|j| {
                std::array::from_fn(|a| std::array::from_fn(|row| -(0..3).map(|b| ni[a][b] * j[row][b]).sum::<f64>()))
            })
            .collect();
        if let Some(joint) = self.joint_covariance() {
            return Ok((self.joint_part(&g, used, x, joint)?, CalibrationCovariance::Joint));
        }
        Ok((self.independent_part(&g, used, x)?, CalibrationCovariance::Independent))
    }

    /// A Sigma_joint A^T (module docs): every camera's numbers, camera 0's always (its
    /// pose to the world moves every extrinsic), the poses between cameras from theirs.
    fn joint_part(&self, g: &[[[f64; 2]; 3]], used: &[usize], x: [f64; 3], joint: &JointCovariance) -> Result<Mat3> {
        let total = joint.matrix.len();
        let mut d = vec![vec![0.0; total]; 2 * used.len()];
        let mut offset = 0;
        for c in 0..self.len() {
            let n = self.calibration(c).ok_or_else(|| Error::invalid("pixels", "camera out of range"))?.layout()?.len();
            if c == 0 || used.contains(&c) {
                let sd: Vec<f64> = (0..n).map(|i| joint.matrix[offset + i][offset + i].max(0.0).sqrt()).collect();
                let dc = self.model_derivatives(c, used, x, &sd, Poses::FromCalibrations)?;
                for (row, drow) in d.iter_mut().zip(&dc) {
                    row[offset..offset + n].copy_from_slice(drow);
                }
            }
            offset += n;
        }
        let mut cov = [[0.0; 3]; 3];
        add_group(&mut cov, g, &d, |i, j| joint.matrix[i][j], total);
        Ok(cov)
    }

    /// The sum over independent groups (module docs).
    fn independent_part(&self, g: &[[[f64; 2]; 3]], used: &[usize], x: [f64; 3]) -> Result<Mat3> {
        let mut cov = [[0.0; 3]; 3];
        let moving_0 = self.cameras()[0].model().centre.is_some();
        for c in (0..self.len()).filter(|&c| used.contains(&c) || (c == 0 && moving_0)) {
            let cal = self.calibration(c).ok_or_else(|| Error::invalid("pixels", "camera out of range"))?;
            let name = self.name(c);
            let cc = cal.require_covariance().map_err(|e| {
                e.within(format!("camera {c} ({name}): pass pixel-only to leave the calibration's part out"), None)
            })?;
            let n = cal.layout()?.len();
            let sd: Vec<f64> = (0..n).map(|i| cc[i][i].max(0.0).sqrt()).collect();
            let d = self.model_derivatives(c, used, x, &sd, Poses::FromFile)?;
            add_group(&mut cov, g, &d, |i, j| cc[i][j], n);
        }
        for (v, &k) in used.iter().enumerate().filter(|(_, k)| **k > 0) {
            let e = self.extrinsics_file(k).ok_or_else(|| Error::invalid("pixels", "camera has no pose"))?;
            let Some(ce) = e.covariance else {
                return Err(Error::invalid(
                    "covariance",
                    format!(
                        "camera {k} ({}): its pose in the rig file has no covariance: add one, or pass pixel-only to leave the calibration's part out",
                        self.name(k)
                    ),
                ));
            };
            let d = self.pose_derivatives(v, k, used.len(), x, e.rotation_rodrigues)?;
            add_group(&mut cov, g, &d, |i, j| ce[i][j], 6);
        }
        Ok(cov)
    }

    /// d r / d theta (2K x n, rows view by view) for camera `c`'s model numbers at fixed
    /// X, by central differences (module docs), number i stepped by 1e-3 `sd[i]` (skipped
    /// when 0), the poses between cameras as `poses` says.
    fn model_derivatives(
        &self,
        c: usize,
        used: &[usize],
        x: [f64; 3],
        sd: &[f64],
        poses: Poses,
    ) -> Result<Vec<Vec<f64>>> {
        let base = *self.cameras()[c].model();
        let layout = base.layout();
        let theta = to_params(&base);
        let mut d = vec![vec![0.0; sd.len()]; 2 * used.len()];
        for (i, &sd) in sd.iter().enumerate() {
            if sd == 0.0 {
                continue;
            }
            let h = 1e-3 * sd;
            let (mut plus, mut minus) = (theta, theta);
            plus[i] += h;
            minus[i] -= h;
            let (mp, mm) = (from_params(&layout, &plus), from_params(&layout, &minus));
            for (v, &k) in used.iter().enumerate() {
                if k != c && c != 0 {
                    continue;
                }
                let qp = self.project_with(k, (c, &mp), x, poses)?;
                let qm = self.project_with(k, (c, &mm), x, poses)?;
                for row in 0..2 {
                    d[2 * v + row][i] = (qp[row] - qm[row]) / (2.0 * h);
                }
            }
        }
        Ok(d)
    }

    /// Camera `k`'s pixel of X with camera `c`'s model replaced by `model` (its pose at the
    /// settings recomputed: Eq. R2 through both centres; with [`Poses::FromCalibrations`],
    /// (R_k, T_k) the relative pose of the models' poses to the world).
    fn project_with(&self, k: usize, (c, model): (usize, &CameraModel), x: [f64; 3], poses: Poses) -> Result<[f64; 2]> {
        let pick = |j: usize| if j == c { *model } else { *self.cameras()[j].model() };
        let (m0, mk) = (pick(0), pick(k));
        let ek = self.cameras()[k].setting_value();
        let pose = match self.extrinsics_file(k) {
            None => RigPose::IDENTITY,
            Some(e) => {
                let (om, t) = match poses {
                    Poses::FromFile => (e.rotation_rodrigues, e.translation_mm),
                    Poses::FromCalibrations => relative_pose(
                        (m0.rotation_rodrigues, m0.translation_mm),
                        (mk.rotation_rodrigues, mk.translation_mm),
                    ),
                };
                let p = RigPose::from_rodrigues(om, t);
                match e.reference_setting {
                    None => p,
                    Some([r0, rk]) => p.at_settings(
                        centre_shift_mm(&m0, self.cameras()[0].setting_value(), r0),
                        centre_shift_mm(&mk, ek, rk),
                    ),
                }
            }
        };
        Ok(project_camera_point(pose.apply(x), &mk.intrinsics(ek)?, &mk.distortion(ek)?)?)
    }

    /// d r / d (om_k, T_k) (2K x 6): only view `v` (camera `k`) depends on them.
    fn pose_derivatives(&self, v: usize, k: usize, views: usize, x: [f64; 3], om: [f64; 3]) -> Result<Vec<Vec<f64>>> {
        let (at, pose) = (&self.cameras()[k], &self.poses()[k]);
        let (_, dq) = project_camera_point_jacobian(pose.apply(x), at.intrinsics(), at.distortion())?;
        // T(E_0, E_k) = T + s_0 R e_z - s_k e_z: R acts on X + s_0 e_z.
        let s0 = match self.extrinsics_file(k).and_then(|e| e.reference_setting) {
            Some([r0, _]) => centre_shift_mm(self.cameras()[0].model(), self.cameras()[0].setting_value(), r0),
            None => 0.0,
        };
        let drot = rotate_point_jacobian(&pose.rotation, om, [x[0], x[1], x[2] + s0]);
        let mut d = vec![vec![0.0; 6]; 2 * views];
        for row in 0..2 {
            for j in 0..3 {
                d[2 * v + row][j] = (0..3).map(|m| dq[row][m] * drot[m][j]).sum();
                d[2 * v + row][3 + j] = dq[row][j];
            }
        }
        Ok(d)
    }
}

/// Where a projection's pose between cameras comes from.
#[derive(Debug, Clone, Copy)]
enum Poses {
    /// The rig file's extrinsics (the models' poses to their boards do not enter).
    FromFile,
    /// The relative pose of the models' poses to the shared world (the joint covariance's
    /// meaning).
    FromCalibrations,
}

/// cov += A C A^T with A = G D (3 x n): `g` per view (3 x 2), `d` the 2K x n derivatives,
/// `c(i, j)` the group's covariance.
fn add_group(cov: &mut Mat3, g: &[[[f64; 2]; 3]], d: &[Vec<f64>], c: impl Fn(usize, usize) -> f64, n: usize) {
    let a: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            std::array::from_fn(|p| {
                g.iter().enumerate().map(|(v, gv)| gv[p][0] * d[2 * v][i] + gv[p][1] * d[2 * v + 1][i]).sum()
            })
        })
        .collect();
    for i in 0..n {
        for j in 0..n {
            let cij = c(i, j);
            if cij == 0.0 {
                continue;
            }
            for p in 0..3 {
                for q in 0..3 {
                    cov[p][q] += a[i][p] * cij * a[j][q];
                }
            }
        }
    }
}
