//! A fixed-focus camera pair from paired views of a planar board: each camera's intrinsics
//! by Zhang's method ([`crate::zhang`]), then the relative pose (R, T) of the right camera
//! by Levenberg-Marquardt (etl-core's Schur-block solver), as `cv2.stereoCalibrate`.
//!
//! A board point X (mm, on Z = 0) seen in pair j lands in the left camera's frame at
//! X_l = R_j X + t_j (the view's board pose, a parameter) and in the right camera's at
//!
//! ```text
//! X_r = R X_l + T = R R_j X + (R t_j + T)
//! ```
//!
//! so R, T take a point from the left camera's frame to the right's (OpenCV's R, T). The
//! least-squares problem is OpenCV's: over every pair seen by both cameras,
//!
//! ```text
//! min  sum_j sum_i |q_l(X_l,ij) - u_l,ij|^2 + sum_j sum_i |q_r(X_r,ij) - u_r,ij|^2
//! ```
//!
//! with q_l, q_r the cameras' projections (the ETL model at E = 0 in the chosen distortion
//! family: with `opencv`, exactly `cv2.projectPoints`). Two modes ([`StereoMode`]):
//! [`StereoMode::FixedIntrinsics`] holds each camera's intrinsics at its own Zhang
//! calibration (every view that camera saw, paired or not) and fits R, T and the pairs'
//! poses (OpenCV's `CALIB_FIX_INTRINSIC` after `calibrateCamera`); [`StereoMode::Joint`]
//! also frees both cameras' intrinsics (OpenCV's flags = 0, its `CALIB_FIX_K3` and
//! `CALIB_ZERO_TANGENT_DIST` as [`crate::zhang::ZhangOptions`]), from the pairs alone.
//!
//! R, T start from the pairs' own relative poses, R_j' = R_r,j R_l,j^T and
//! T_j' = t_r,j - R_j' t_l,j (each camera's Zhang poses), as OpenCV: the median of each
//! component of the Rodrigues vectors and of T over the pairs. The Jacobians are analytic:
//! with q the projection of a camera-frame point (etl-core's [`Projector`] at the identity
//! pose, whose translation columns are dq/dX_c),
//!
//! ```text
//! dq_l/d(om_j, t_j) = dq_l/dX_l [d(R_j X)/d om_j | I]
//! dq_r/d(om, T)     = dq_r/dX_r [d(R X_l)/d om | I]
//! dq_r/d(om_j, t_j) = dq_r/dX_r R [d(R_j X)/d om_j | I]
//! ```
//!
//! with `d(R(om) p)/d om = -R [p]x J_r(om)` ([`etl_core::calib::jacobian::rotate_point_jacobian`]).
//! The covariance of the free numbers is OpenCV's scaling of (J^T J)^-1 marginalised over
//! the poses: sigma^2 = cost / (2 points - free numbers - 6 pairs), points of both cameras.
//! With the intrinsics held, that of R, T also carries the held intrinsics' own
//! uncertainty (each camera's Zhang covariance) through d(R, T)/d(intrinsics)
//! (`covariance.rs`): the intrinsics' errors dominate the relative pose's.
//!
//! [`rectify`] gives Bouguet's rectification of a pair in OpenCV's model, as
//! `cv2.stereoRectify`.
//!
//! Preconditions: each camera sees the board in at least 3 views (Zhang's); R, T need at
//! least one pair seen by both cameras, the joint mode at least 3.
//!
//! [`Projector`]: etl_core::calib::jacobian::Projector

mod calibrate;
mod covariance;
mod init;
mod options;
mod problem;
mod rectify;
mod result;
mod solve;

pub use calibrate::stereo_calibrate;
pub use init::relative_pose_median;
pub use options::{StereoMode, StereoOptions, StereoPair, MIN_JOINT_PAIRS};
pub use rectify::{rectify, rectify_cameras, undistort_opencv, Rectification, RectifyCamera};
pub use result::StereoResult;
