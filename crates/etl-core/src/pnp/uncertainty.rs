//! The uncertainty of a PnP pose and of the displacement between two poses, from the pixel
//! noise of the images and the covariance of the calibration together.
//!
//! The pose p = (om, t) minimises sum_i |r_i(p, x)|^2 with r_i the reprojection error of
//! corner i and x the calibrated numbers (25 for the paper's model). With N = J_p^T J_p (Gauss-Newton normal
//! matrix of the pose, J_p = dr / dp) and J_x = dr / dx:
//!
//! - pixel noise of standard deviation sigma on every coordinate gives
//!   Cov_pix(p) = sigma^2 N^-1;
//! - a change dx of the calibration moves the optimum by dp = S dx,
//!   S = -N^-1 J_p^T J_x (the stationarity condition J_p^T r = 0 differentiated, with the
//!   second-order terms sum r_i d^2 r_i dropped: the residuals are pixel noise, ~0.2 px,
//!   against Jacobian entries of thousands of px per unit); the calibration's own R, T
//!   do not enter the PnP, so their columns of S are zero;
//! - the two are independent (the measured images are not the calibration's), so
//!   Cov(p) = sigma^2 N^-1 + S C S^T.
//!
//! The displacement d = t_b - t_a of two poses measured with the same calibration has
//! Cov(d) = Cov_pix(t_a) + Cov_pix(t_b) + (S_b,t - S_a,t) C (S_b,t - S_a,t)^T: the
//! calibration's error moves both poses alike and largely cancels in the difference,
//! which is why the sensitivity S is kept rather than each pose's covariance alone.
//!
//! sigma is the caller's, or estimated from the PnP's own residual,
//! sigma^2 = sum |r_i|^2 / (2 n - 6) (n corners, 6 pose unknowns): the corner detector's
//! noise is what the residual shows, and a wrong guess would give wrong intervals.
//! Not included: an error of the current E_com itself (the thermal compensation's), which
//! would move fx(E) for both poses alike.

use super::planar::BoardPose;
use crate::calib::jacobian::Projector;
use crate::calib::params::MAX_PARAMS;
use crate::calib::uncertainty::{check_covariance, sandwich};
use crate::error::{all_finite, Error, Result};
use crate::linalg::spd_inverse;
use crate::model::CameraModel;

/// Pose unknowns (om1..om3, t1..t3).
const POSE: usize = 6;

/// The pixel noise assumed by [`pose_uncertainty`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PixelNoise {
    /// A known standard deviation per pixel coordinate, px.
    Known(f64),
    /// Estimated from the PnP residual: sigma^2 = sum |r_i|^2 / (2 n - 6).
    FromResidual,
}

/// The first-order uncertainty of a [`BoardPose`] (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseUncertainty {
    /// The pixel noise standard deviation used, px.
    pub sigma_px: f64,
    /// Covariance of (om1..om3 rad, t1..t3 mm) from the pixel noise: sigma^2 N^-1.
    pub pixel_covariance: [[f64; POSE]; POSE],
    /// S = d(om, t) / d(calibrated numbers) (zero columns for the calibration's R, T).
    pub d_pose_d_params: [[f64; MAX_PARAMS]; POSE],
}

impl PoseUncertainty {
    /// Cov(om, t) = sigma^2 N^-1 + S C S^T with C the calibration's covariance (`None`:
    /// the pixel noise alone).
    ///
    /// Errors: a NaN or infinite covariance entry.
    pub fn covariance(
        &self,
        calibration_covariance: Option<&[[f64; MAX_PARAMS]; MAX_PARAMS]>,
    ) -> Result<[[f64; POSE]; POSE]> {
        let mut out = self.pixel_covariance;
        if let Some(c) = calibration_covariance {
            check_covariance(c)?;
            add(&mut out, &sandwich(&self.d_pose_d_params, c));
        }
        Ok(out)
    }
}

fn add<const R: usize>(a: &mut [[f64; R]; R], b: &[[f64; R]; R]) {
    for (ai, bi) in a.iter_mut().zip(b.iter()) {
        for (x, y) in ai.iter_mut().zip(bi.iter()) {
            *x += y;
        }
    }
}

/// The uncertainty of `pose`, found by [`super::solve_pnp`] from `board_mm` and `pixels`
/// at `e_com_ma` through `model`, under pixel noise `noise` (module docs).
///
/// Preconditions (typed errors): those of [`super::solve_pnp`] on the points (same
/// number, at least 4, finite); a known sigma finite and >= 0; a pose that the points
/// determine (N positive definite, [`Error::Degenerate`] otherwise); every point in front
/// of the camera at `pose`.
pub fn pose_uncertainty(
    model: &CameraModel,
    e_com_ma: f64,
    board_mm: &[[f64; 3]],
    pixels: &[[f64; 2]],
    pose: &BoardPose,
    noise: PixelNoise,
) -> Result<PoseUncertainty> {
    if board_mm.len() != pixels.len() {
        return Err(Error::InvalidArgument { what: "board points and pixels differ in number" });
    }
    if board_mm.len() < 4 {
        return Err(Error::TooFew { what: "points for PnP", needed: 4, got: board_mm.len() });
    }
    all_finite(&pose.rotation_rodrigues, "pose")?;
    all_finite(&pose.translation_mm, "pose")?;
    let mut m = *model;
    m.rotation_rodrigues = pose.rotation_rodrigues;
    m.translation_mm = pose.translation_mm;
    let proj = Projector::new(&m);
    // N = J_p^T J_p, B = J_p^T J_x (the pose is the first 6 of the model's numbers here).
    let mut n = [[0.0; POSE]; POSE];
    let mut b = [[0.0; MAX_PARAMS]; POSE];
    let mut cost = 0.0;
    for (w, px) in board_mm.iter().zip(pixels) {
        all_finite(w, "board point")?;
        all_finite(px, "pixel")?;
        let p = proj.project(*w, e_com_ma, true)?;
        for (d, (&u, &o)) in p.d_params.iter().zip(p.pixel.iter().zip(px.iter())) {
            cost += (u - o) * (u - o);
            for ((ni, bi), &ji) in n.iter_mut().zip(b.iter_mut()).zip(d.iter()) {
                for (nik, &dk) in ni.iter_mut().zip(d.iter()) {
                    *nik += ji * dk;
                }
                // Columns past the pose: the calibration's numbers the PnP holds.
                for (bik, &dk) in bi.iter_mut().zip(d.iter()).skip(POSE) {
                    *bik += ji * dk;
                }
            }
        }
    }
    let sigma_px = match noise {
        PixelNoise::Known(s) if s.is_finite() && s >= 0.0 => s,
        PixelNoise::Known(_) => {
            return Err(Error::InvalidArgument { what: "pixel noise sigma must be finite and >= 0" });
        }
        PixelNoise::FromResidual => libm::sqrt(cost / (2 * board_mm.len()).saturating_sub(POSE).max(1) as f64),
    };
    let ninv = spd_inverse(&n, 1e-14).ok_or(Error::Degenerate { what: "the points do not determine the PnP pose" })?;
    let mut pixel_covariance = ninv;
    pixel_covariance.iter_mut().flatten().for_each(|v| *v *= sigma_px * sigma_px);
    // S = -N^-1 B.
    let mut d_pose_d_params = [[0.0; MAX_PARAMS]; POSE];
    for (si, nii) in d_pose_d_params.iter_mut().zip(ninv.iter()) {
        for (&nik, bk) in nii.iter().zip(b.iter()) {
            for (sij, &bkj) in si.iter_mut().zip(bk.iter()) {
                *sij -= nik * bkj;
            }
        }
    }
    if !d_pose_d_params.iter().flatten().chain(pixel_covariance.iter().flatten()).all(|v| v.is_finite()) {
        return Err(Error::NotFinite { what: "pose uncertainty" });
    }
    Ok(PoseUncertainty { sigma_px, pixel_covariance, d_pose_d_params })
}

/// Covariance of [`super::displacement_mm`]`(a, b)` (mm^2) for poses with uncertainties
/// `ua`, `ub` measured in independent images with the same calibration (covariance
/// `calibration_covariance`; `None`: pixel noise alone): see the module docs.
///
/// Errors: a NaN or infinite covariance entry.
pub fn displacement_covariance_mm2(
    ua: &PoseUncertainty,
    ub: &PoseUncertainty,
    calibration_covariance: Option<&[[f64; MAX_PARAMS]; MAX_PARAMS]>,
) -> Result<[[f64; 3]; 3]> {
    let mut out = translation_block(&ua.pixel_covariance);
    add(&mut out, &translation_block(&ub.pixel_covariance));
    if let Some(c) = calibration_covariance {
        check_covariance(c)?;
        // The translation rows of S_b - S_a.
        let mut diff = [[0.0; MAX_PARAMS]; 3];
        let rows = ub.d_pose_d_params.iter().skip(3).zip(ua.d_pose_d_params.iter().skip(3));
        for (d, (rb, ra)) in diff.iter_mut().zip(rows) {
            for (x, (b, a)) in d.iter_mut().zip(rb.iter().zip(ra.iter())) {
                *x = b - a;
            }
        }
        add(&mut out, &sandwich(&diff, c));
    }
    Ok(out)
}

/// The translation's 3 x 3 block of a pose covariance (rows and columns 3..6).
fn translation_block(c: &[[f64; POSE]; POSE]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (o, row) in out.iter_mut().zip(c.iter().skip(3)) {
        for (x, &v) in o.iter_mut().zip(row.iter().skip(3)) {
            *x = v;
        }
    }
    out
}

/// One standard deviation of each component of the displacement, mm: the square roots of
/// the diagonal of [`displacement_covariance_mm2`].
pub fn displacement_std_mm(cov_mm2: &[[f64; 3]; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (k, (o, row)) in out.iter_mut().zip(cov_mm2.iter()).enumerate() {
        *o = libm::sqrt(row.get(k).copied().unwrap_or(0.0).max(0.0));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::solve_pnp;
    use super::*;

    fn board() -> [[f64; 3]; 20] {
        core::array::from_fn(|i| [1.5 * (i % 5) as f64, 1.5 * (i / 5) as f64, 0.0])
    }

    /// S against central differences: re-solving the PnP with one calibrated number
    /// moved moves the pose by S's column times the step.
    #[test]
    fn sensitivity_matches_resolving_with_a_moved_calibration() {
        let cam = CameraModel::paper_rig();
        let b = board();
        let px: [[f64; 2]; 20] = core::array::from_fn(|i| cam.project([b[i][0], b[i][1], 40.0], 120.0).unwrap());
        let pose = solve_pnp(&cam, 120.0, &b, &px).unwrap();
        let u = pose_uncertainty(&cam, 120.0, &b, &px, &pose, PixelNoise::Known(0.2)).unwrap();
        assert_eq!(u.sigma_px, 0.2);
        for (k, h) in [(6, 1.0), (14, 0.5), (15, 0.5), (16, 1e-3)] {
            use crate::calib::jacobian::{from_params, to_params};
            let mut x = to_params(&cam);
            let mut xm = x;
            x[k] += h;
            xm[k] -= h;
            let l = cam.layout();
            let (pp, pm) = (
                solve_pnp(&from_params(&l, &x), 120.0, &b, &px).unwrap(),
                solve_pnp(&from_params(&l, &xm), 120.0, &b, &px).unwrap(),
            );
            for i in 0..3 {
                let fd = (pp.translation_mm[i] - pm.translation_mm[i]) / (2.0 * h);
                let an = u.d_pose_d_params[3 + i][k];
                assert!((fd - an).abs() <= 1e-4 * an.abs().max(1e-6), "param {k} t{i}: fd {fd} an {an}");
            }
        }
        // The calibration's own R, T do not enter.
        assert!(u.d_pose_d_params.iter().all(|r| r[..6].iter().all(|&v| v == 0.0)));
    }

    /// Exact pixels: the residual estimate of sigma is ~0; a bad sigma or too few points
    /// are refused.
    #[test]
    fn residual_sigma_and_bad_inputs() {
        let cam = CameraModel::paper_rig();
        let b = board();
        let px: [[f64; 2]; 20] = core::array::from_fn(|i| cam.project([b[i][0], b[i][1], 40.0], 120.0).unwrap());
        let pose = solve_pnp(&cam, 120.0, &b, &px).unwrap();
        let u = pose_uncertainty(&cam, 120.0, &b, &px, &pose, PixelNoise::FromResidual).unwrap();
        assert!(u.sigma_px < 1e-6, "{}", u.sigma_px);
        let e = pose_uncertainty(&cam, 120.0, &b, &px, &pose, PixelNoise::Known(-1.0)).unwrap_err();
        assert_eq!(e, Error::InvalidArgument { what: "pixel noise sigma must be finite and >= 0" });
        let e = pose_uncertainty(&cam, 120.0, &b[..3], &px[..3], &pose, PixelNoise::FromResidual).unwrap_err();
        assert_eq!(e, Error::TooFew { what: "points for PnP", needed: 4, got: 3 });
        let mut c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        c[0][0] = f64::INFINITY;
        let e = displacement_covariance_mm2(&u, &u, Some(&c)).unwrap_err();
        assert_eq!(e, Error::NotFinite { what: "calibration covariance" });
    }
}
