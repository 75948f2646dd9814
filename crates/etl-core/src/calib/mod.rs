//! The calibration of an ETL camera (paper section 4.3-4.6) over borrowed observations.
//!
//! [`initialise`] chains the linear initialisers, [`bundle_adjust()`] refines every number:
//!
//! 1. [`rac`]: R, tx, ty from the radial alignment constraint over all views (Eq. 19-20);
//! 2. [`focal_poly`]: kf1..kf_d for x and y and tz (Eq. 21-22), given A0;
//! 3. [`distortion_init`]: the distortion coefficients per view (Eq. 23), then their a_i
//!    (Eq. 18);
//! 4. [`bundle_adjust()`]: Eq. 24 by Levenberg-Marquardt, optionally errors-in-variables.
//!
//! Each step works for either distortion family and any focal degree 1..=5: the layout of
//! the numbers is a value ([`params::Layout`]), chosen with [`initialise_model`].

pub mod basis;
pub mod bundle_adjust;
pub mod crlb;
mod dispatch;
pub mod distortion_init;
pub mod focal_poly;
mod initialise;
pub mod jacobian;
pub mod observations;
/// The parameter vector's layout: the model's ([`crate::model::params`]), named here too
/// because every solver speaks in it.
pub use crate::model::params;
pub mod rac;
pub mod uncertainty;

pub use bundle_adjust::{
    bundle_adjust, bundle_adjust_free_views, bundle_adjust_free_views_scratch, bundle_adjust_scratch,
    BundleAdjustOptions, BundleAdjustReport, Estimator, FreeView, InputNoise, JointScratch, RobustLoss, ViewCorrection,
    ViewScratch, MIN_FREE_VIEW_POINTS,
};
pub use focal_poly::Kf0;
pub use initialise::{initialise, initialise_model, initialise_model_with, A0};
pub use observations::{Point, View};
pub use params::{Layout, ParamMask};
pub use uncertainty::{projection_uncertainty, PixelUncertainty};
