//! The projection uncertainty of a monofocal (Zhang) calibration, in mrcal's sense
//! (mrcal 2.x `projection_uncertainty`, "mean-frames"): the standard deviation of where the
//! point seen at a pixel, at a given distance (or in a direction: infinity), is projected
//! again by a calibration re-estimated from new noise on the same corners.
//!
//! The point is fixed in the boards' frames, not in the camera's: a new solve moves the
//! camera frame with the poses. So the pixel q is unprojected to p (the camera frame of
//! this solve), mapped into every view's board frame, p_i = R_i^T (p - t_i), and mapped back
//! through the perturbed poses and averaged, p' = (1/n) sum_i (R_i' p_i + t_i'), then
//! projected by the perturbed intrinsics. For a direction only the rotations act. To first
//! order, with x the free intrinsics and y_i the poses,
//!
//! ```text
//! Var(q) = sigma^2 (h S^-1 h^T + sum_i g_i V_i^-1 g_i^T),  h = g_x - sum_i g_i V_i^-1 W_i^T
//! ```
//!
//! g_x = dq/dx, g_i = dq/dy_i = dq/dp (1/n) [d(R_i p_i)/d om_i | I], and the blocks of
//! J^T J: V_i = J_yi^T J_yi, W_i = J_x^T J_yi, S = U - sum_i W_i V_i^-1 W_i^T (the Schur
//! complement; S^-1 the intrinsics' block of (J^T J)^-1). The formula is that block inverse
//! written out: the joint covariance of intrinsics and poses, never formed.
//!
//! sigma^2 is OpenCV's, cost / (2 points - free numbers - 6 views), the scaling of the
//! result's `std`. mrcal takes the standard deviation of the residuals instead (no degrees
//! of freedom removed), sqrt(2 points / dof) smaller: 4 % for 4 views of 54 corners, well
//! inside the 10 % that this module's test allows against mrcal on the same corners.

use etl_core::calib::jacobian::Projector;
use etl_core::calib::uncertainty::PixelUncertainty;
use etl_core::model::rotation::{mat_t_vec, mat_vec, rodrigues_to_matrix};
use etl_core::model::{CameraModel, DistortionModel};
use etl_formats::{Error, Result};
use nalgebra::{Matrix6, SMatrix};
use serde::{Deserialize, Serialize};

use super::{model_at, param_index, Shared, SHARED_MAX};

/// What the projection uncertainty of a Zhang solution needs (module docs): the camera,
/// the poses and the blocks of J^T J, over the shared numbers at capacity (rows of held
/// numbers zero). Serialisable, so that a result keeps it across a pickle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZhangUncertainty {
    /// The distortion family of the shared numbers.
    pub(super) model: DistortionModel,
    /// fx, fy, u0, v0, the coefficients.
    pub(super) shared: Shared,
    /// Each view's pose: Rodrigues, translation.
    pub(super) poses: Vec<[f64; 6]>,
    /// S^-1: (J^T J)^-1's block of the shared numbers, without sigma^2.
    pub(super) s_inv: [[f64; SHARED_MAX]; SHARED_MAX],
    /// Per view: W_i = J_x^T J_yi (shared x pose).
    pub(super) w: Vec<[[f64; 6]; SHARED_MAX]>,
    /// Per view: V_i^-1 = (J_yi^T J_yi)^-1.
    pub(super) v_inv: Vec<[[f64; 6]; 6]>,
    /// Pixel noise variance, px^2 (OpenCV's scaling).
    pub(super) sigma2_px: f64,
}

/// V^-1 of a view's pose block given by its upper triangle (as `etl_core::lm::BlockNormal`
/// accumulates it), or why it has none.
pub(super) fn invert_pose_block(v: &[[f64; 6]; 6]) -> Result<[[f64; 6]; 6]> {
    let m = Matrix6::from_fn(|i, j| v[i.min(j)][i.max(j)]);
    let inv = m
        .try_inverse()
        .ok_or(Error::Core(etl_core::Error::Degenerate { what: "a view's pose is not determined by its corners" }))?;
    Ok(core::array::from_fn(|i| core::array::from_fn(|j| inv[(i, j)])))
}

/// d(R(om) p)/d om by central differences (3 x 3): smooth in om, step 1e-7 rad, error
/// ~1e-14 relative.
fn rotation_derivative(om: [f64; 3], p: [f64; 3]) -> [[f64; 3]; 3] {
    const H: f64 = 1e-7;
    let mut d = [[0.0; 3]; 3];
    for k in 0..3 {
        let (mut a, mut b) = (om, om);
        a[k] += H;
        b[k] -= H;
        let (pa, pb) = (mat_vec(&rodrigues_to_matrix(a), p), mat_vec(&rodrigues_to_matrix(b), p));
        for (row, (x, y)) in d.iter_mut().zip(pa.iter().zip(pb.iter())) {
            row[k] = (x - y) / (2.0 * H);
        }
    }
    d
}

impl super::ZhangResult {
    /// The uncertainty of the pixel at which the point seen at `pixel` is projected again
    /// by a calibration re-solved from new corner noise (module docs; mrcal's
    /// `projection_uncertainty`): at `distance_mm` along the viewing ray from the centre,
    /// or, for `None`, in that direction (a point at infinity).
    ///
    /// Errors: a result without [`Self::uncertainty`] (built by hand); those of
    /// [`ZhangUncertainty::projection_std`].
    pub fn projection_std(&self, pixel: [f64; 2], distance_mm: Option<f64>) -> Result<PixelUncertainty> {
        let u = self.uncertainty.as_ref().ok_or_else(|| {
            Error::invalid("uncertainty", "this Zhang result carries no covariance blocks (built by hand)")
        })?;
        u.projection_std(pixel, distance_mm)
    }
}

impl ZhangUncertainty {
    /// sigma^2 S^-1: the covariance of the shared numbers (fx, fy, u0, v0, the
    /// coefficients; the rows and columns of held ones zero), OpenCV's scaling, as the
    /// result's `std` squared on the diagonal.
    pub(crate) fn shared_covariance(&self) -> [[f64; SHARED_MAX]; SHARED_MAX] {
        self.s_inv.map(|row| row.map(|v| v * self.sigma2_px))
    }

    /// Its lengths agree (a pose, a W and a V^-1 per view, at least one view) and every
    /// number is finite: what [`Self::projection_std`] assumes of a deserialised value.
    pub fn validate(&self) -> Result<()> {
        let n = self.poses.len();
        if n == 0 || self.w.len() != n || self.v_inv.len() != n {
            return Err(Error::invalid(
                "uncertainty",
                "uncertainty: a pose, a W block and a V block per view, at least one view",
            ));
        }
        let numbers = self.shared.iter().chain(self.poses.iter().flatten()).chain(self.s_inv.iter().flatten());
        let blocks = self.w.iter().flatten().flatten().chain(self.v_inv.iter().flatten().flatten());
        if !numbers.chain(blocks).chain([&self.sigma2_px]).all(|v| v.is_finite()) {
            return Err(Error::invalid("uncertainty", "uncertainty: every number must be finite"));
        }
        Ok(())
    }

    /// The fitted camera at the identity pose ([`super::ZhangResult::camera`]).
    fn camera(&self) -> CameraModel {
        model_at(self.model, &self.shared, &[0.0; 6])
    }

    /// [`super::ZhangResult::projection_std`].
    ///
    /// Errors: a pixel that does not unproject (outside the distortion's domain); a
    /// distance that is not a finite number > 0.
    pub fn projection_std(&self, pixel: [f64; 2], distance_mm: Option<f64>) -> Result<PixelUncertainty> {
        let u = self;
        if let Some(d) = distance_mm.filter(|d| !(d.is_finite() && *d > 0.0)) {
            let message = format!("distance_mm = {d} must be a finite number > 0 (None: a direction)");
            return Err(Error::invalid_value("distance_mm", d, message));
        }
        let camera = u.camera();
        let ray = camera.ray(pixel, 0.0).map_err(Error::Core)?;
        let p = distance_mm.map_or(ray.direction, |s| ray.at(s));
        let proj = Projector::new(&camera);
        let q = proj.project(p, 0.0, true).map_err(Error::Core)?;
        let layout = camera.layout();
        let count = 4 + u.model.coefficient_count();
        let column = |r: usize, i: usize| q.d_params.get(r).and_then(|row| row.get(i)).copied().unwrap_or(0.0);
        let g_x: [[f64; SHARED_MAX]; 2] = core::array::from_fn(|r| {
            core::array::from_fn(|k| if k < count { column(r, param_index(&layout, k)) } else { 0.0 })
        });
        // dq/dp at the identity pose is dq/dT.
        let t = layout.translation();
        let dq_dp: [[f64; 3]; 2] = core::array::from_fn(|r| core::array::from_fn(|c| column(r, t.at(c))));
        let n = u.poses.len() as f64;
        let mut h = g_x;
        let mut diag = [[0.0; 2]; 2];
        for ((pose, w), v_inv) in u.poses.iter().zip(&u.w).zip(&u.v_inv) {
            let g = pose_gradient(pose, p, distance_mm.is_some(), &dq_dp, n);
            let gv = mul_2x6_6x6(&g, v_inv);
            for r in 0..2 {
                for (hk, wk) in h[r].iter_mut().zip(w.iter()) {
                    *hk -= gv[r].iter().zip(wk.iter()).map(|(a, b)| a * b).sum::<f64>();
                }
                for c in 0..2 {
                    diag[r][c] += gv[r].iter().zip(g[c].iter()).map(|(a, b)| a * b).sum::<f64>();
                }
            }
        }
        let hs = SMatrix::<f64, 2, SHARED_MAX>::from_fn(|r, k| h[r][k]);
        let s = SMatrix::<f64, SHARED_MAX, SHARED_MAX>::from_fn(|i, j| u.s_inv[i][j]);
        let core = hs * s * hs.transpose();
        let cov: [[f64; 2]; 2] =
            core::array::from_fn(|r| core::array::from_fn(|c| u.sigma2_px * (core[(r, c)] + diag[r][c])));
        let sym = 0.5 * (cov[0][1] + cov[1][0]);
        let covariance_px2 = [[cov[0][0], sym], [sym, cov[1][1]]];
        Ok(PixelUncertainty { covariance_px2, std_px: [cov[0][0].max(0.0).sqrt(), cov[1][1].max(0.0).sqrt()] })
    }
}

/// g_i = dq/dy_i (2 x 6: om, t) for view `pose`: the point `p` of the camera frame held in
/// the view's board frame, mapped back through the pose and averaged over `n` views.
fn pose_gradient(pose: &[f64; 6], p: [f64; 3], finite: bool, dq_dp: &[[f64; 3]; 2], n: f64) -> [[f64; 6]; 2] {
    let (om, t) = ([pose[0], pose[1], pose[2]], [pose[3], pose[4], pose[5]]);
    let r_t = rodrigues_to_matrix(om);
    // p_i = R^T (p - t) for a point, R^T p for a direction.
    let rel = if finite { [p[0] - t[0], p[1] - t[1], p[2] - t[2]] } else { p };
    let p_i = mat_t_vec(&r_t, rel);
    let d_om = rotation_derivative(om, p_i);
    let mut g = [[0.0; 6]; 2];
    for (gr, dr) in g.iter_mut().zip(dq_dp.iter()) {
        for c in 0..3 {
            gr[c] = (0..3).map(|k| dr[k] * d_om[k][c]).sum::<f64>() / n;
            if finite {
                gr[3 + c] = dr[c] / n;
            }
        }
    }
    g
}

fn mul_2x6_6x6(a: &[[f64; 6]; 2], b: &[[f64; 6]; 6]) -> [[f64; 6]; 2] {
    core::array::from_fn(|r| core::array::from_fn(|c| (0..6).map(|k| a[r][k] * b[k][c]).sum()))
}
