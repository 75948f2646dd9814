//! Plane-based PnP: the pose of a planar board at a known current (paper section 5.2.3),
//! and the displacement between two poses (the measurement of a stage move).
//!
//! 1. Undistort the pixels with the model at the current and normalise them through
//!    A(E): x = (u - u0) / fx, y = (v - v0) / fy.
//! 2. The homography H from board (X, Y) to (x, y) by the normalised DLT (h33 = 1,
//!    streamed Givens least squares), decomposed as [r1 r2 t] = H / |H e1| (Zhang 2000)
//!    with r3 = r1 x r2, then the nearest rotation.
//! 3. Levenberg-Marquardt over (Rodrigues, t) on the reprojection error in pixels with
//!    the full model (distortion included), using the analytic Jacobian of
//!    [`crate::calib::jacobian`].
//! 4. The pose's uncertainty from the pixel noise and the calibration's covariance, and the
//!    displacement's ([`pose_uncertainty`], [`displacement_covariance_mm2`]).

mod homography;
mod planar;
mod uncertainty;

pub use homography::{homography, zhang_constraints};
pub use planar::{displacement_mm, solve_pnp, BoardPose, MAX_PNP_POINTS};
pub use uncertainty::{
    displacement_covariance_mm2, displacement_std_mm, pose_uncertainty, PixelNoise, PoseUncertainty,
};
