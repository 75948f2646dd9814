//! The inputs and options of [`super::stereo_calibrate`].

use crate::zhang::{PlanarView, ZhangOptions};

/// What the stereo refinement frees besides R, T and the pairs' poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StereoMode {
    /// Each camera's intrinsics held at its own Zhang calibration, from every view it saw
    /// (OpenCV's `CALIB_FIX_INTRINSIC` after `calibrateCamera` per camera).
    FixedIntrinsics,
    /// Both cameras' intrinsics free with R, T, from the pairs seen by both (OpenCV's
    /// `stereoCalibrate` with flags 0, started from each camera's Zhang calibration).
    Joint,
}

/// The options of [`super::stereo_calibrate`]: each camera's distortion family and OpenCV flags
/// (the same for both, as [`crate::zhang::zhang_with`] takes them) and the mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StereoOptions {
    /// The distortion family and flags of both cameras.
    pub zhang: ZhangOptions,
    /// Intrinsics held or free.
    pub mode: StereoMode,
}

/// One synchronised pair of views: each camera's board points and pixels, `None` where
/// that camera did not see the board.
#[derive(Debug, Clone, Default)]
pub struct StereoPair {
    /// The left camera's view.
    pub left: Option<PlanarView>,
    /// The right camera's view.
    pub right: Option<PlanarView>,
}

/// The fewest pairs seen by both cameras that [`StereoMode::Joint`] needs (the intrinsics
/// come from the pairs alone, Zhang's minimum); [`StereoMode::FixedIntrinsics`] needs one.
pub const MIN_JOINT_PAIRS: usize = 3;
