//! Distortion initialisation (Eq. 23, then Eq. 18), for either family.
//!
//! Per view j, with the ideal point of each observation predicted by the undistorted
//! model and the observed one, the distortion is linear in its coefficients. The paper's
//! family, in centred pixels (Eq. 23):
//!
//! ```text
//! u_d - u = k1 u r^2 + p1 (3u^2 + v^2) + 2 p2 u v
//! v_d - v = k1 v r^2 + 2 p1 u v + p2 (u^2 + 3v^2)       (Weng's form; docs/METHOD.md)
//! ```
//!
//! OpenCV's, in normalised coordinates x = X_C / Z_C and the observed x_d = (u_d - u0) / fx,
//! each row multiplied by its focal length so that the residual is in pixels as the bundle
//! adjustment's:
//!
//! ```text
//! fx (x_d - x) = fx [x r^2, x r^4, 2 x y, r^2 + 2 x^2, x r^6] . (k1, k2, p1, p2, k3)
//! fy (y_d - y) = fy [y r^2, y r^4, r^2 + 2 y^2, 2 x y, y r^6] . (k1, k2, p1, p2, k3)
//! ```
//!
//! (coefficients held by OpenCV's flags are left out of the solve, at zero). Then each
//! coefficient is fitted across views as a quadratic in w = 1 / f_mean(E_j) (Eq. 18), with
//! the streamed polynomial fit of [`crate::fit`] (centred and scaled w).

use super::observations::{validate, View};
use crate::error::{Error, Result};
use crate::fit::{GivensQr, PolyFit};
use crate::model::distortion::opencv_rows;
use crate::model::projection::project_camera_point;
use crate::model::{CameraModel, Distortion, DistortionA, DistortionModel, OpenCvFlags, MAX_COEFFICIENTS};

/// Pixel scale used inside the paper family's per-view solve (coefficients of size 1).
const R_SCALE_PX: f64 = 1000.0;

/// The distortion coefficients of one view by Eq. 23, for the undistorted part of `model`
/// (its family; every coefficient free).
///
/// Errors: fewer than 2 points ([`Error::TooFew`]); a point behind the camera; a
/// rank-deficient system (all points at the centre).
pub fn view_distortion(model: &CameraModel, view: &View<'_>) -> Result<Distortion> {
    view_distortion_with(model, view, OpenCvFlags::NONE)
}

/// As [`view_distortion`], with the coefficients OpenCV's `flags` hold left at zero.
/// Errors: as [`view_distortion`]; a flag with the paper family ([`OpenCvFlags::check`]).
pub fn view_distortion_with(model: &CameraModel, view: &View<'_>, flags: OpenCvFlags) -> Result<Distortion> {
    if view.points.len() < 2 {
        return Err(Error::TooFew { what: "points in a view for Eq. 23", needed: 2, got: view.points.len() });
    }
    let family = model.distortion_model();
    flags.check(family)?;
    match family {
        DistortionModel::Paper => paper_view(model, view),
        DistortionModel::OpenCv => opencv_view(model, view, flags),
    }
}

fn paper_view(model: &CameraModel, view: &View<'_>) -> Result<Distortion> {
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
    Ok(Distortion::paper(s[0] / (R_SCALE_PX * R_SCALE_PX), s[1] / R_SCALE_PX, s[2] / R_SCALE_PX))
}

fn opencv_view(model: &CameraModel, view: &View<'_>, flags: OpenCvFlags) -> Result<Distortion> {
    let k = model.intrinsics(view.e_com_ma)?;
    let family = DistortionModel::OpenCv;
    // The free coefficients, in order: their column in the compressed system.
    let mut free = [0usize; MAX_COEFFICIENTS];
    let mut n = 0;
    for c in 0..family.coefficient_count() {
        if !flags.holds(family, c) {
            if let Some(slot) = free.get_mut(n) {
                *slot = c;
            }
            n += 1;
        }
    }
    let mut qr = GivensQr::<MAX_COEFFICIENTS>::new(n)?;
    for p in view.points {
        let pc = model.world_to_camera(p.world_mm);
        if !(pc[2] > 0.0) {
            return Err(Error::BehindCamera);
        }
        let (x, y) = (pc[0] / pc[2], pc[1] / pc[2]);
        let (xd, yd) = ((p.pixel[0] - k.u0) / k.fx, (p.pixel[1] - k.v0) / k.fy);
        let rows = opencv_rows(x, y);
        for (row, (f, target)) in rows.iter().zip([(k.fx, xd - x), (k.fy, yd - y)]) {
            let mut compressed = [0.0; MAX_COEFFICIENTS];
            for (slot, &c) in compressed.iter_mut().zip(free.iter().take(n)) {
                *slot = f * row.get(c).copied().unwrap_or(0.0);
            }
            qr.add_row(&compressed, f * target, 1.0)?;
        }
    }
    let s = qr.solve().map_err(|_| Error::Degenerate { what: "Eq. 23 system is singular for a view" })?;
    let mut dist = [0.0; MAX_COEFFICIENTS];
    for (&c, &v) in free.iter().take(n).zip(s.iter()) {
        if let Some(slot) = dist.get_mut(c) {
            *slot = v;
        }
    }
    Ok(Distortion::opencv(dist, k.fx, k.fy))
}

/// The a_i of `model`'s distortion family (Eq. 18: each coefficient a quadratic in
/// w = 1 / f_mean) from the per-view coefficients of all views, those held by `flags`
/// at zero.
///
/// Preconditions: at least 3 views with distinct mean focal lengths ([`Error::TooFew`]);
/// flags that belong to the family ([`OpenCvFlags::check`]).
pub fn distortion_a(model: &CameraModel, views: &[View<'_>], flags: OpenCvFlags) -> Result<DistortionA> {
    validate(views)?;
    let family = model.distortion_model();
    flags.check(family)?;
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
    let fit = PolyFit::new(2, [wmin, wmax])?;
    let mut fits = [fit; MAX_COEFFICIENTS];
    let n = family.coefficient_count();
    for v in views {
        let k = model.intrinsics(v.e_com_ma)?;
        let w = 2.0 / (k.fx + k.fy);
        let d = view_distortion_with(model, v, flags)?;
        for (fit, &c) in fits.iter_mut().zip(d.coefficients()).take(n) {
            fit.add(w, c)?;
        }
    }
    let mut a = DistortionA::zero(family);
    let slots = a.as_mut_slice();
    for (i, fit) in fits.iter().enumerate().take(n) {
        if flags.holds(family, i) {
            continue;
        }
        let (poly, _) = fit.solve().map_err(|e| match e {
            Error::TooFew { got, .. } => {
                Error::TooFew { what: "views with distinct focal lengths (Eq. 18)", needed: 3, got }
            }
            other => other,
        })?;
        let c = poly.monomial_coefficients()?;
        // Eq. 18 orders the coefficients w^2, w, 1.
        for (k, deg) in [2, 1, 0].into_iter().enumerate() {
            if let Some(slot) = slots.get_mut(3 * i + k) {
                *slot = c.get(deg).copied().unwrap_or(0.0);
            }
        }
    }
    Ok(a)
}
