//! etl-image: what etlcal reads from images. Checkerboard detection (sub-pixel corners
//! in a stable order, [`detect`]), ChArUco detection (markers identified, corners with their
//! ids, partial views, [`charuco`]) and sharpness (CPBD bit-exact against the reference
//! package, and the gradient measures of etl-core over images, [`sharpness`]); and
//! whole-image undistortion at any focus, parallel over bands of rows ([`undistort`]).

pub mod board;
pub mod charuco;
pub mod detect;
mod read;
pub mod sharpness;
pub mod undistort;

pub use read::{read_image, MAX_JPEG_PIXELS_PER_BYTE, MAX_PNG_PIXELS_PER_BYTE};

pub use etl_formats::{Error, Result};
