//! etl-image: what etlcal reads from images. Checkerboard detection (sub-pixel corners
//! in a stable order, [`detect`]) and sharpness (CPBD bit-exact against the reference
//! package, and the gradient measures of etl-core over images, [`sharpness`]).

pub mod detect;
mod read;
pub mod sharpness;

pub use read::read_image;

pub use etl_formats::{Error, Result};
