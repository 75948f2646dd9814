//! The linear initialisation chain: RAC -> focal polynomial -> distortion.

use super::distortion_init::distortion_a;
use super::focal_poly::{focal_poly_with, Kf0};
use super::observations::View;
use super::params::Layout;
use super::rac::rac;
use crate::error::{all_finite, Result};
use crate::model::{CameraModel, DistortionA, MovingCentre, OpenCvFlags};

/// The lens-off intrinsics A0 (section 4.2): focal lengths at E = 0 and principal point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct A0 {
    /// fx at E = 0, px.
    pub kf0x: f64,
    /// fy at E = 0, px.
    pub kf0y: f64,
    /// Principal point u0, px.
    pub u0: f64,
    /// Principal point v0, px.
    pub v0: f64,
}

/// The paper's initial camera model from the views and A0: RAC (R, tx, ty), the cubic
/// focal polynomial (kf1..3, tz), then the distortion coefficients a1..a9.
///
/// Errors: those of [`rac`], [`super::focal_poly::focal_poly`] and [`distortion_a`] (each
/// names its unmet precondition).
pub fn initialise(views: &[View<'_>], a0: &A0) -> Result<CameraModel> {
    initialise_model(views, a0, Layout::PAPER, OpenCvFlags::NONE)
}

/// The initial camera model of `layout` (distortion family, focal degree) from the views
/// and A0: RAC (R, tx, ty), the focal polynomial of the layout's degree (kf1..kf_d, tz),
/// then the family's a_i, those held by OpenCV's `flags` at zero (hold them in the bundle
/// adjustment with [`Layout::opencv_mask`]).
///
/// Errors: those of [`rac`], [`super::focal_poly::focal_poly_of_degree`] and [`distortion_a`]; flags with
/// the paper family.
pub fn initialise_model(views: &[View<'_>], a0: &A0, layout: Layout, flags: OpenCvFlags) -> Result<CameraModel> {
    initialise_model_with(views, a0, Kf0::Known([a0.kf0x, a0.kf0y]), layout, flags)
}

/// As [`initialise_model`], with kf0 from A0 or solved with the focal polynomial
/// ([`Kf0`]): a focal-power calibration solves it, because 0 dpt is not the lens off. A0's
/// principal point is used either way (the ETL at any power leaves it where the lens-off
/// calibration found it, to the precision of the start).
pub fn initialise_model_with(
    views: &[View<'_>],
    a0: &A0,
    kf0: Kf0,
    layout: Layout,
    flags: OpenCvFlags,
) -> Result<CameraModel> {
    match kf0 {
        Kf0::Known(_) => all_finite(&[a0.kf0x, a0.kf0y, a0.u0, a0.v0], "A0 (kf0x, kf0y, u0, v0)")?,
        Kf0::Solved => all_finite(&[a0.u0, a0.v0], "A0 (u0, v0)")?,
    }
    flags.check(layout.model())?;
    let pp = [a0.u0, a0.v0];
    let r = rac(views, pp)?;
    let f = focal_poly_with(views, &r, kf0, pp, layout.focal_degree())?;
    let mut model = CameraModel {
        rotation_rodrigues: r.rotation_rodrigues,
        translation_mm: [r.tx_mm, r.ty_mm, f.tz_mm],
        kf_x: f.kf_x,
        kf_y: f.kf_y,
        principal_point: pp,
        distortion_a: DistortionA::zero(layout.model()),
        // The linear steps assume a fixed centre; a moving one starts from it (zero move),
        // and the bundle adjustment finds the move.
        centre: layout.moving_centre().then_some(MovingCentre::ZERO),
    };
    model.distortion_a = distortion_a(&model, views, flags)?;
    Ok(model)
}
