//! etl-image: what etlcal reads from images. Checkerboard detection (sub-pixel corners
//! in a stable order, [`checkerboard`]), ChArUco detection (markers identified, corners with
//! their ids, partial views, [`charuco`]), the grey images and sub-pixel refinement both
//! share ([`grey`], `subpixel`) and sharpness (CPBD bit-exact against the reference
//! package, and the gradient measures of etl-core over images, [`sharpness`]); and
//! whole-image undistortion at any focus, parallel over bands of rows ([`undistort`]).

pub mod board;
pub mod charuco;
pub mod checkerboard;
pub mod grey;
mod read;
pub mod sharpness;
mod subpixel;
pub mod undistort;

pub use read::{read_image, MAX_JPEG_PIXELS_PER_BYTE, MAX_PNG_PIXELS_PER_BYTE, MAX_TIFF_PIXELS_PER_BYTE};

pub use etl_formats::{Error, Result};

// The path before issue 26 (`detect` held the checkerboard detector): kept so that code
// written against it still compiles, hidden from the documentation.
#[doc(hidden)]
pub use checkerboard as detect;
