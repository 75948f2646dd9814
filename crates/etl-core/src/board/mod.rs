//! Calibration targets as the camera sees them: OpenCV's ArUco/AprilTag dictionaries
//! ([`Dictionary`]) and the ChArUco board's geometry ([`CharucoBoard`]), in OpenCV's layout
//! and ids. Detection lives in etl-image, rendering in etl-sim, the `etlcal.board/1` file
//! in etl-formats; this module is the one place that knows where each square, marker and
//! corner is, without allocating.

pub mod charuco;
pub mod dictionary;

pub use charuco::CharucoBoard;
pub use dictionary::{Dictionary, Identified};
