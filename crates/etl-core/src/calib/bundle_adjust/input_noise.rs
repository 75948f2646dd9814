//! The paper estimator's covariance under the whole noise model: pixel noise, and the
//! errors of each view's recorded stage position and current that Eq. 24 takes as exact.
//!
//! The paper's estimate minimises |r(x)|^2 with the recorded Z_W and E of every view. If
//! the recorded values are off by d_j = (dZ_j, dE_j) (independent, Gaussian, spreads
//! sigma_z and sigma_e) and the corners by pixel noise eps (sigma_px), the residual at the
//! truth is eps + B d, B_j = d pixels / d (Z_W, E) of view j, so to first order
//!
//! ```text
//! dx = -H^-1 J^T (eps + B d),  H = J^T J
//! C  = sigma_px^2 H^-1 + H^-1 M H^-1,  M = sum_j W_j Q W_j^T,  W_j = J_j^T B_j,
//!                                       Q = diag(sigma_z^2, sigma_e^2)
//! ```
//!
//! This is the errors-in-variables noise model evaluated at the paper's estimate (not a
//! sandwich from the residuals: with 20-40 views and 25-39 numbers the per-view residual
//! structure cannot estimate the 25 x 25 middle term; the model's spreads are the same
//! priors the errors-in-variables estimator takes, docs/METHOD.md). The residuals then
//! hold both noises: E|r|^2 = sigma_px^2 (2n - p) + tr((I - P) B Q B^T), P the hat
//! matrix, so sigma_px^2 is estimated as (|r|^2 - sum_j tr(Q B_j^T B_j) + tr(H^-1 M)) /
//! (2n - p): the plain residual variance, which the input errors inflate, would count
//! them twice.
//!
//! H^-1 is the solver's (covariance / sigma2, hold rows included, so a held number keeps a
//! zero variance); with a robust loss every row carries its IRLS weight at the estimate.

use super::{BundleAdjustReport, RobustLoss};
use crate::calib::jacobian::Projector;
use crate::calib::observations::{point_count, View};
use crate::calib::params::MAX_PARAMS;
use crate::error::{Error, Result};

type Square = [[f64; MAX_PARAMS]; MAX_PARAMS];

/// The spread of what the paper's estimator takes as exact: each view's recorded stage
/// position and current (and, optionally, the pixel noise, estimated otherwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputNoise {
    /// Standard deviation of a view's recorded stage position, mm (paper: 0.010).
    pub sigma_z_mm: f64,
    /// Standard deviation of a view's recorded current, mA (paper: 0.4).
    pub sigma_e_ma: f64,
    /// Pixel noise standard deviation; `None`: estimated from the residuals with the
    /// input errors' share taken out (module docs).
    pub sigma_px: Option<f64>,
}

impl InputNoise {
    /// The paper's noise levels (section 5.1.2), the errors-in-variables priors' defaults.
    pub const PAPER: InputNoise = InputNoise { sigma_z_mm: 0.010, sigma_e_ma: 0.4, sigma_px: None };
}

/// What [`covariance_with_input_noise`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputNoiseCovariance {
    /// Covariance of the numbers (the report's layout; zero past it).
    pub covariance: Square,
    /// The pixel noise it assumes, px (given or estimated).
    pub sigma_px: f64,
}

/// Per view: W_j = J_j^T B_j (as its two columns) and the diagonal of B_j^T B_j (all the
/// input share needs), with the rows' weights.
struct ViewTerms {
    w: [[f64; MAX_PARAMS]; 2],
    btb_diagonal: [f64; 2],
}

/// Accumulates view `view`'s [`ViewTerms`] and its weighted squared residuals at `proj`
/// (the robust weight from the same projection: the estimate is the reference).
fn view_terms(proj: &Projector, view: &View<'_>, robust: Option<RobustLoss>, rss: &mut f64) -> Result<ViewTerms> {
    let mut t = ViewTerms { w: [[0.0; MAX_PARAMS]; 2], btb_diagonal: [0.0; 2] };
    for p in view.points {
        let pr = proj.project(p.world_mm, view.e_com_ma, true)?;
        let (du, dv) = (pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]);
        let f = robust.map_or(1.0, |loss| libm::sqrt(loss.weight(du * du + dv * dv)));
        let rows = pr.d_params.iter().zip(pr.d_z_w.iter().zip(pr.d_e.iter())).zip([du, dv]);
        for ((j_row, (&dz, &de)), d) in rows {
            let e = f * d;
            *rss += e * e;
            let b = [f * dz, f * de];
            for ((wk, btbk), &bk) in t.w.iter_mut().zip(t.btb_diagonal.iter_mut()).zip(b.iter()) {
                for (w, &j) in wk.iter_mut().zip(j_row.iter()) {
                    *w += f * j * bk;
                }
                *btbk += bk * bk;
            }
        }
    }
    Ok(t)
}

/// a b for two squares (at capacity, or of a solver's `N`).
pub(super) fn product<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut out = [[0.0; N]; N];
    for (oi, ai) in out.iter_mut().zip(a.iter()) {
        for (&aik, bk) in ai.iter().zip(b.iter()) {
            if aik != 0.0 {
                for (o, &bkj) in oi.iter_mut().zip(bk.iter()) {
                    *o += aik * bkj;
                }
            }
        }
    }
    out
}

/// `c` made exactly symmetric, the mean of it and its transpose (products of the same
/// symmetric factors differ by rounding).
pub(super) fn symmetric<const N: usize>(c: [[f64; N]; N]) -> [[f64; N]; N] {
    let mut out = c;
    for (i, row) in out.iter_mut().enumerate() {
        for (o, c_col) in row.iter_mut().zip(c.iter()) {
            if let Some(&t) = c_col.get(i) {
                *o = 0.5 * (*o + t);
            }
        }
    }
    out
}

/// The covariance of the paper estimator's `report` over `views` (the views it solved,
/// with the robust loss it used) under the whole noise model `noise`: module docs.
///
/// Preconditions (typed errors): positive finite spreads; the views the report came
/// from (the projection errors of a point behind the camera otherwise). A report with a
/// zero residual variance (noise-free input) carries no H^-1 and is returned unchanged,
/// with a zero pixel noise.
pub fn covariance_with_input_noise(
    views: &[View<'_>],
    report: &BundleAdjustReport,
    robust: Option<RobustLoss>,
    noise: &InputNoise,
) -> Result<InputNoiseCovariance> {
    let spreads = [noise.sigma_z_mm, noise.sigma_e_ma];
    if !spreads.iter().chain(noise.sigma_px.as_ref()).all(|s| s.is_finite() && *s > 0.0) {
        return Err(Error::InvalidArgument { what: "input noise standard deviations must be positive and finite" });
    }
    let s2 = report.sigma_px * report.sigma_px;
    if !(s2 > 0.0 && s2.is_finite()) {
        return Ok(InputNoiseCovariance { covariance: report.covariance, sigma_px: 0.0 });
    }
    let h_inv: Square = report.covariance.map(|row| row.map(|c| c / s2));
    let proj = Projector::new(&report.model);
    let q = [spreads[0] * spreads[0], spreads[1] * spreads[1]];
    let (mut m, mut rss, mut input_share) = ([[0.0; MAX_PARAMS]; MAX_PARAMS], 0.0, 0.0);
    for view in views {
        let t = view_terms(&proj, view, robust, &mut rss)?;
        input_share += q[0] * t.btb_diagonal[0] + q[1] * t.btb_diagonal[1];
        for (wk, &qk) in t.w.iter().zip(q.iter()) {
            for (mi, &wi) in m.iter_mut().zip(wk.iter()) {
                if wi != 0.0 {
                    for (mij, &wj) in mi.iter_mut().zip(wk.iter()) {
                        *mij += qk * wi * wj;
                    }
                }
            }
        }
    }
    let hm = product(&h_inv, &m);
    let trace: f64 = hm.iter().enumerate().filter_map(|(i, row)| row.get(i)).sum();
    let explained = input_share - trace;
    let free = report.layout().len();
    let dof = (2 * point_count(views)).saturating_sub(free).max(1) as f64;
    let sigma2_px = match noise.sigma_px {
        Some(s) => s * s,
        None => ((rss - explained) / dof).max(0.0),
    };
    // (H^-1 M) H^-1, from the product the trace took: `uncertainty::sandwich` computes the
    // same with another order of sums, which moves the paper file's covariance by 1e-11.
    let mut covariance = product(&hm, &h_inv);
    for (c_row, h_row) in covariance.iter_mut().zip(h_inv.iter()) {
        for (c, &h) in c_row.iter_mut().zip(h_row.iter()) {
            *c += sigma2_px * h;
        }
    }
    Ok(InputNoiseCovariance { covariance: symmetric(covariance), sigma_px: libm::sqrt(sigma2_px) })
}
