//! etl-calib: calibration. Zhang's method for the lens-off (monofocal) intrinsics
//! ([`zhang`]), the pipeline from a dataset or observations to a calibration file
//! ([`pipeline`]), the per-setting baseline of the paper's section 5.2.3 ([`baseline`]) and
//! the temperature-calibration procedure ([`thermal_calibration`]); the one request per
//! verb that the CLI and Python parse their options into ([`request`]); a multi-camera
//! ETL rig calibrated jointly ([`rig_calibration`]).

pub mod baseline;
pub mod diff;
pub mod lens_dynamics;
pub mod pipeline;
pub mod request;
pub mod rig;
pub mod rig_calibration;
pub mod robust;
pub mod stereo;
pub mod thermal_calibration;
pub mod zhang;

pub use etl_formats::{Error, Result};
