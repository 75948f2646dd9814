//! etl-calib: images, detection, Zhang's method, the calibration pipeline, studies,
//! reports and the `etlcal` command line.

pub mod baseline;
pub mod cli;
pub mod detect;
pub mod error;
pub mod formats;
pub mod pipeline;
pub mod progress;
pub mod render;
pub mod report;
pub mod sharpness;
pub mod simulate;
pub mod study;
pub mod thermal_calibration;
pub mod zhang;

pub use error::{Error, Result};
