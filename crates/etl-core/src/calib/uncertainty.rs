//! What the calibration's covariance means downstream: the uncertainty of a projected
//! pixel due to the uncertainty of the calibrated numbers (any layout).
//!
//! The covariance C is that of the parameter vector of [`super::params`] (order of
//! [`super::params::Layout::names`], each number in its own unit), as the bundle adjustment
//! reports it ([`super::BundleAdjustReport::covariance`]). A quantity q(x) of the numbers
//! has, to first order, the covariance J_q C J_q^T with J_q = dq/dx at the estimate.

use super::jacobian::Projector;
use super::params::MAX_PARAMS;
use crate::error::{all_finite, Error, Result};
use crate::model::CameraModel;

/// The uncertainty of a projected pixel: its 2 x 2 covariance and the per-axis standard
/// deviations (square roots of the diagonal), px.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelUncertainty {
    /// Covariance of (u, v), px^2.
    pub covariance_px2: [[f64; 2]; 2],
    /// One standard deviation of u and of v, px.
    pub std_px: [f64; 2],
}

/// J C J^T for an R x p Jacobian `j` and a p x p covariance `c`, both at capacity (zero
/// past the layout's p numbers), exactly symmetric: the lower triangle is mirrored from
/// the upper.
pub fn sandwich<const R: usize>(j: &[[f64; MAX_PARAMS]; R], c: &[[f64; MAX_PARAMS]; MAX_PARAMS]) -> [[f64; R]; R] {
    // t = J C (R x p), then out = t J^T.
    let mut t = [[0.0; MAX_PARAMS]; R];
    for (ti, ji) in t.iter_mut().zip(j.iter()) {
        for (&jik, ck) in ji.iter().zip(c.iter()) {
            if jik != 0.0 {
                for (tij, &ckj) in ti.iter_mut().zip(ck.iter()) {
                    *tij += jik * ckj;
                }
            }
        }
    }
    let mut out = [[0.0; R]; R];
    for (oa, ta) in out.iter_mut().zip(t.iter()) {
        for (oab, jb) in oa.iter_mut().zip(j.iter()) {
            *oab = ta.iter().zip(jb.iter()).map(|(x, y)| x * y).sum();
        }
    }
    // Mirror the upper triangle (the two products differ by rounding).
    for a in 0..R {
        for b in 0..a {
            let v = out.get(b).and_then(|r| r.get(a)).copied().unwrap_or(0.0);
            if let Some(x) = out.get_mut(a).and_then(|r| r.get_mut(b)) {
                *x = v;
            }
        }
    }
    out
}

/// Refuses a covariance with a NaN or infinite entry.
pub fn check_covariance(covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS]) -> Result<()> {
    covariance.iter().try_for_each(|row| all_finite(row, "calibration covariance"))
}

/// The uncertainty of the pixel `model` projects `world_mm` to at compensated current
/// `e_com_ma`, due to the uncertainty of the calibration (covariance `covariance` of the
/// numbers, at capacity): Sigma_p = J_p C J_p^T with J_p = d pixel / d(numbers) (Eq. 13-18
/// differentiated, [`Projector::project`]).
///
/// First order: exact for the parameters the pixel is linear in (u0, v0, a1..a9), a
/// linearisation for the others (the relative error is of the order of the relative
/// standard deviations, ~1e-3 for a calibrated camera).
///
/// Errors: a NaN or infinite covariance entry, point or current; the point at or behind
/// the camera; a non-positive focal length at `e_com_ma`.
pub fn projection_uncertainty(
    model: &CameraModel,
    covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS],
    world_mm: [f64; 3],
    e_com_ma: f64,
) -> Result<PixelUncertainty> {
    all_finite(&world_mm, "world point")?;
    if !e_com_ma.is_finite() {
        return Err(Error::NotFinite { what: "current" });
    }
    check_covariance(covariance)?;
    let p = Projector::new(model).project(world_mm, e_com_ma, true)?;
    let cov = sandwich(&p.d_params, covariance);
    let [[uu, _], [_, vv]] = cov;
    let std_px = [libm::sqrt(uu.max(0.0)), libm::sqrt(vv.max(0.0))];
    if !(std_px[0].is_finite() && std_px[1].is_finite()) {
        return Err(Error::NotFinite { what: "projection standard deviation" });
    }
    Ok(PixelUncertainty { covariance_px2: cov, std_px })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::params::Layout;

    /// The pixel is u0 + ..., v0 + ...: a covariance on (u0, v0) alone passes through as
    /// is; one on kf0x alone gives |d u / d kf0x| times its std, against central
    /// differences of the projection.
    #[test]
    #[allow(non_snake_case)]
    fn matches_the_principal_point_and_a_finite_difference() {
        let m = CameraModel::paper_rig();
        let l = Layout::PAPER;
        let (U0, V0, KF0X) = (l.u0(), l.v0(), l.kf0x());
        let mut c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        c[U0][U0] = 4.0;
        c[V0][V0] = 0.25;
        c[U0][V0] = 0.5;
        c[V0][U0] = 0.5;
        let w = [10.0, 8.0, 40.0];
        let p = projection_uncertainty(&m, &c, w, 150.0).unwrap();
        assert_eq!(p.std_px, [2.0, 0.5]);
        assert_eq!(p.covariance_px2[0][1], 0.5);
        let mut c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        let s = 3.0;
        c[KF0X][KF0X] = s * s;
        let p = projection_uncertainty(&m, &c, w, 150.0).unwrap();
        let (mut mp, mut mm) = (m, m);
        mp.kf_x.coefficients_mut()[0] += 1e-3;
        mm.kf_x.coefficients_mut()[0] -= 1e-3;
        let du = (mp.project(w, 150.0).unwrap()[0] - mm.project(w, 150.0).unwrap()[0]) / 2e-3;
        let dv = (mp.project(w, 150.0).unwrap()[1] - mm.project(w, 150.0).unwrap()[1]) / 2e-3;
        assert!((p.std_px[0] - du.abs() * s).abs() < 1e-6 * p.std_px[0], "{:?} {du}", p.std_px);
        assert!((p.std_px[1] - dv.abs() * s).abs() < 1e-6 * p.std_px[1].max(1e-9), "{:?} {dv}", p.std_px);
    }

    #[test]
    fn refuses_a_non_finite_covariance_or_point() {
        let m = CameraModel::paper_rig();
        let mut c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        c[3][4] = f64::NAN;
        let e = projection_uncertainty(&m, &c, [0.0, 0.0, 40.0], 150.0).unwrap_err();
        assert_eq!(e, Error::NotFinite { what: "calibration covariance" });
        let c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        let e = projection_uncertainty(&m, &c, [f64::NAN, 0.0, 40.0], 150.0).unwrap_err();
        assert_eq!(e, Error::NotFinite { what: "world point" });
    }
}
