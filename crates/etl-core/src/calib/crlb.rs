//! The Cramer-Rao bound of the model's numbers at the truth (the yardstick of
//! docs/METHOD.md), for any layout (family, focal degree).
//!
//! With pixel noise of standard deviation sigma on each coordinate, the Fisher information
//! of the parameters is J^T J / sigma^2 (J: the Jacobian of all projections at the true
//! parameters), and any unbiased estimator's covariance is at least its inverse. With the
//! errors-in-variables unknowns (dZ_j, dE_j with Gaussian priors), the bound of the
//! numbers is the inverse of the Schur complement of the per-view unknowns.

use super::dispatch::with_layout;
use super::jacobian::Projector;
use super::observations::{validate, View};
use super::params::MAX_PARAMS;
use crate::error::Result;
use crate::linalg::svd::sym_pinv;
use crate::model::CameraModel;

/// Relative singular-value threshold of the inversions (directions below it are
/// unidentified and get no bound).
const RANK_TOL: f64 = 1e-13;

/// The CRLB covariance of the truth's numbers (its layout's order, zero past its length)
/// for pixel noise `sigma_px`, the recorded stage positions and currents exact (the model
/// of the paper's Eq. 24).
pub fn crlb_covariance(
    views: &[View<'_>],
    truth: &CameraModel,
    sigma_px: f64,
) -> Result<[[f64; MAX_PARAMS]; MAX_PARAMS]> {
    crlb_covariance_eiv(views, truth, sigma_px, None)
}

/// The CRLB covariance of the truth's numbers with, per view, an unknown stage error and
/// current error of prior standard deviations `priors = Some((sigma_z_mm, sigma_e_ma))`
/// (None: both exact).
pub fn crlb_covariance_eiv(
    views: &[View<'_>],
    truth: &CameraModel,
    sigma_px: f64,
    priors: Option<(f64, f64)>,
) -> Result<[[f64; MAX_PARAMS]; MAX_PARAMS]> {
    validate(views)?;
    truth.validate()?;
    let layout = truth.layout();
    let mut out = [[0.0; MAX_PARAMS]; MAX_PARAMS];
    with_layout!(layout, N, _O, _P, {
        let cov = crlb_n::<N>(views, truth, sigma_px, priors)?;
        for (o, row) in out.iter_mut().zip(cov.iter()) {
            for (x, &v) in o.iter_mut().zip(row.iter()) {
                *x = v;
            }
        }
        Ok(())
    })?;
    Ok(out)
}

/// [`crlb_covariance_eiv`] for a layout of `N` numbers.
fn crlb_n<const N: usize>(
    views: &[View<'_>],
    truth: &CameraModel,
    sigma_px: f64,
    priors: Option<(f64, f64)>,
) -> Result<[[f64; N]; N]> {
    let proj = Projector::new(truth);
    let w = 1.0 / (sigma_px * sigma_px);
    let mut info = [[0.0; N]; N];
    for view in views {
        let mut cross = [[0.0; 2]; N]; // J_x^T J_y of the view
        let mut vv = [[0.0; 2]; 2]; // J_y^T J_y of the view
        for p in view.points {
            let pr = proj.project(p.world_mm, view.e_com_ma, true)?;
            for row in 0..2 {
                let jx: &[f64; N] = &core::array::from_fn(|k| pr.d_params[row].get(k).copied().unwrap_or(0.0));
                let jy = [pr.d_z_w[row], pr.d_e[row]];
                for i in 0..N {
                    for j in 0..N {
                        info[i][j] += w * jx[i] * jx[j];
                    }
                    for k in 0..2 {
                        cross[i][k] += w * jx[i] * jy[k];
                    }
                }
                for k in 0..2 {
                    for l in 0..2 {
                        vv[k][l] += w * jy[k] * jy[l];
                    }
                }
            }
        }
        if let Some((sz, se)) = priors {
            vv[0][0] += 1.0 / (sz * sz);
            vv[1][1] += 1.0 / (se * se);
            let (vinv, _) = sym_pinv(&vv, RANK_TOL);
            for i in 0..N {
                for j in 0..N {
                    let mut s = 0.0;
                    for k in 0..2 {
                        for l in 0..2 {
                            s += cross[i][k] * vinv[k][l] * cross[j][l];
                        }
                    }
                    info[i][j] -= s;
                }
            }
        }
    }
    Ok(sym_pinv(&info, RANK_TOL).0)
}
