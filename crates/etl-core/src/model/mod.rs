//! The ETL camera model (paper section 3, Eq. 12-18).
//!
//! World point P_W (mm) -> camera P_C = R P_W + T (Eq. 13) -> ideal centred pixel
//! u = fx(E) X_C / Z_C, v = fy(E) Y_C / Z_C (Eq. 15-16) -> distorted centred pixel (Eq. 17,
//! with Weng's decentering term, or OpenCV's model: see [`family`] and [`distortion`]) ->
//! observed pixel (u_d + u0, v_d + v0).

pub mod centre;
pub mod distortion;
pub mod family;
pub mod focal;
pub mod opencv;
pub mod params;
pub mod projection;
pub mod ray;
pub mod rotation;

pub use centre::{MovingCentre, CENTRE_DZ_LEN, CENTRE_PP_LEN};
pub use distortion::Distortion;
pub use family::{DistortionA, DistortionModel, OpenCvFlags, MAX_COEFFICIENTS, MAX_DISTORTION_A};
pub use focal::{FocalPoly, MAX_FOCAL_DEGREE, PAPER_FOCAL_DEGREE};
pub use opencv::{fit_opencv5, OpenCvFit};
pub use projection::{CameraModel, Intrinsics};
pub use ray::Ray;

// The paths before issue 26 (`camera` held the model's projection, `undistort` the
// distortion's inverse): kept so that code written against them still compiles.
#[doc(hidden)]
pub use distortion as undistort;
#[doc(hidden)]
pub use projection as camera;
