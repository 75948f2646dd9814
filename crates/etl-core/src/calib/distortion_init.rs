//! Distortion initialisation (Eq. 23, then Eq. 18).
//!
//! Per view j, with the ideal centred pixel (u, v) of each point predicted by the
//! undistorted model and the observed centred (u_d, v_d), Eq. 17 is linear in
//! (k1, p1, p2):
//!
//! ```text
//! u_d - u = k1 u r^2 + p1 (3u^2 + v^2) + 2 p2 u v
//! v_d - v = k1 v r^2 + 2 p1 u v + p2 (u^2 + 3v^2)       (Weng's form; docs/METHOD.md)
//! ```
//!
//! Then each of k1, p1, p2 is fitted across views as a quadratic in w = 1 / f_mean(E_j)
//! (Eq. 18), with the streamed polynomial fit of [`crate::fit`] (centred and scaled w).

use super::observations::{validate, View};
use crate::error::{Error, Result};
use crate::fit::{GivensQr, PolyFit};
use crate::model::camera::project_camera_point;
use crate::model::{CameraModel, Distortion};

/// Pixel scale used inside the per-view solve (coefficients of size 1).
const R_SCALE_PX: f64 = 1000.0;

/// k1, p1, p2 of one view by Eq. 23, for the undistorted part of `model`.
///
/// Errors: fewer than 2 points ([`Error::TooFew`]); a point behind the camera; a
/// rank-deficient system (all points at the centre).
pub fn view_distortion(model: &CameraModel, view: &View<'_>) -> Result<Distortion> {
    if view.points.len() < 2 {
        return Err(Error::TooFew { what: "points in a view for Eq. 23", needed: 2, got: view.points.len() });
    }
    let k = model.intrinsics(view.e_com_ma)?;
    let none = Distortion::default();
    let mut qr = GivensQr::<3>::full();
    for p in view.points {
        let ideal = project_camera_point(model.world_to_camera(p.world_mm), &k, &none)?;
        let (u, v) = ((ideal[0] - k.u0) / R_SCALE_PX, (ideal[1] - k.v0) / R_SCALE_PX);
        let (ud, vd) = ((p.pixel[0] - k.u0) / R_SCALE_PX, (p.pixel[1] - k.v0) / R_SCALE_PX);
        let r2 = u * u + v * v;
        qr.add_row(&[u * r2, 3.0 * u * u + v * v, 2.0 * u * v], ud - u, 1.0)?;
        qr.add_row(&[v * r2, 2.0 * u * v, u * u + 3.0 * v * v], vd - v, 1.0)?;
    }
    let s = qr.solve().map_err(|_| Error::Degenerate { what: "Eq. 23 system is singular for a view" })?;
    // In scaled pixels k1 carries 1/R^2, p1 and p2 carry 1/R.
    Ok(Distortion { k1: s[0] / (R_SCALE_PX * R_SCALE_PX), p1: s[1] / R_SCALE_PX, p2: s[2] / R_SCALE_PX })
}

/// a1..a9 of Eq. 18 from the per-view coefficients of all views.
///
/// Preconditions: at least 3 views with distinct mean focal lengths ([`Error::TooFew`]).
pub fn distortion_a(model: &CameraModel, views: &[View<'_>]) -> Result<[f64; 9]> {
    validate(views)?;
    let (mut wmin, mut wmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in views {
        let k = model.intrinsics(v.e_com_ma)?;
        let w = 2.0 / (k.fx + k.fy);
        wmin = wmin.min(w);
        wmax = wmax.max(w);
    }
    if !(wmax > wmin * (1.0 + 1e-9)) {
        return Err(Error::TooFew { what: "views with distinct focal lengths (Eq. 18)", needed: 3, got: 1 });
    }
    let mut fits = [PolyFit::new(2, [wmin, wmax])?, PolyFit::new(2, [wmin, wmax])?, PolyFit::new(2, [wmin, wmax])?];
    for v in views {
        let k = model.intrinsics(v.e_com_ma)?;
        let w = 2.0 / (k.fx + k.fy);
        let d = view_distortion(model, v)?;
        for (fit, c) in fits.iter_mut().zip([d.k1, d.p1, d.p2]) {
            fit.add(w, c)?;
        }
    }
    let mut a = [0.0; 9];
    for (i, fit) in fits.iter().enumerate() {
        let (poly, _) = fit.solve().map_err(|e| match e {
            Error::TooFew { got, .. } => {
                Error::TooFew { what: "views with distinct focal lengths (Eq. 18)", needed: 3, got }
            }
            other => other,
        })?;
        let c = poly.monomial_coefficients()?;
        // Eq. 18 orders the coefficients w^2, w, 1.
        a[3 * i] = c.get(2).copied().unwrap_or(0.0);
        a[3 * i + 1] = c.get(1).copied().unwrap_or(0.0);
        a[3 * i + 2] = c.first().copied().unwrap_or(0.0);
    }
    Ok(a)
}
