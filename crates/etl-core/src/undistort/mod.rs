//! Whole-image undistortion over caller buffers: undistortion maps in `cv2.remap`'s
//! convention ([`undistort_maps`]) and bilinear resampling ([`remap()`]), each over a band of
//! output rows so that std crates run the bands in parallel.
//!
//! Conventions (those of OpenCV's `initUndistortRectifyMap` + `remap`): an output pixel
//! (x, y), with (0, 0) the centre of the top-left pixel, takes the value of the distorted
//! (observed) image at the source pixel `(map_x[i], map_y[i])`, `i = y * width + x`, read
//! bilinearly. The maps are a forward evaluation of the model, so they are exact (no
//! iterative inversion): see [`undistort_maps`].
//!
//! ```
//! use etl_core::model::CameraModel;
//! use etl_core::undistort::{remap, undistort_maps, OutputCamera, SourceImage};
//! let cam = CameraModel::paper_rig();
//! let (k, d) = (cam.intrinsics(150.0)?, cam.distortion(150.0)?);
//! // The top-left 64 x 64 px of the image, all rows in one band.
//! let out = OutputCamera::of_intrinsics(&k, 64, 64)?;
//! let (mut map_x, mut map_y) = ([0.0f32; 64 * 64], [0.0f32; 64 * 64]);
//! undistort_maps(&k, &d, &out, 0..64, &mut map_x, &mut map_y)?;
//! // Distortion moves the corner of the image by about 10 px along x at 150 mA.
//! assert!((map_x[0] - 10.40).abs() < 0.01 && (map_y[0] - 4.75).abs() < 0.01);
//! let image = [100u8; 64 * 64];
//! let src = SourceImage::new(&image, 64, 64, 1)?;
//! let mut dst = [0u8; 64 * 64];
//! remap(&src, &map_x, &map_y, 0, &mut dst)?;
//! assert_eq!(dst[32 * 64 + 32], 100); // inside: the image's level
//! assert_eq!(dst[0], 100);
//! assert_eq!(dst[64 * 64 - 1], 0); // its source (~73, ~68) is outside: the border value
//! # Ok::<(), etl_core::Error>(())
//! ```

pub mod maps;
pub mod pinhole;
pub mod rectify;
pub mod remap;

pub use maps::undistort_maps;
pub use pinhole::{OutputCamera, MAX_PIXELS, MAX_SIDE_PX};
pub use rectify::rectify_maps;
pub use remap::{remap, Sample, SourceImage};

// The path before issue 26 (`camera` held the output image's pinhole camera): kept so that
// code written against it still compiles.
#[doc(hidden)]
pub use pinhole as camera;
