//! etl-image: what etlcal reads from images. Checkerboard detection (sub-pixel corners
//! in a stable order, [`detect`]) and sharpness (CPBD bit-exact against the reference
//! package, and the gradient measures of etl-core over images, [`sharpness`]).

pub mod detect;
pub mod sharpness;

pub use etl_formats::{Error, Result};
