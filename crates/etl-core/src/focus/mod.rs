//! Sharpness measures and autofocus, without allocation, over a borrowed grayscale view.
//!
//! The measures ([`tenengrad`], [`laplacian_variance`], [`brenner`],
//! [`normalised_variance`]) take an [`ImageView`] of 8- or 16-bit pixels with any row
//! stride (a region of interest of a camera frame is measured in place) and return a
//! number that is larger when the image is sharper, in the image's own grey-level scale.
//! [`autofocus`] finds the lens current that maximises any such measure with a small,
//! fixed number of frames. CPBD, the perceptual measure the paper's temperature procedure
//! maximises, needs buffers and lives in `etl-calib` (`sharpness::cpbd`).
//!
//! Which measure to focus with (measured on the synthetic camera, see
//! docs/BENCHMARKS.md, "Sharpness and autofocus"): CPBD falls to 0 beyond about 1 px of
//! blur on a checkerboard, so it cannot drive a coarse search. The gradient measures
//! (Tenengrad, Brenner, variance of the Laplacian) fall steadily with blur over several
//! pixels and are the ones to use; normalised variance has the widest capture range but
//! the flattest peak.
//!
//! ```
//! use etl_core::focus::{autofocus, tenengrad, AutofocusOptions, ImageView};
//! // A toy "camera": a vertical edge whose width grows with the distance from 150 mA.
//! let mut frame = [0u8; 32 * 8];
//! let mut grab = |e_ma: f64| {
//!     let width = 1.0 + (e_ma - 150.0).abs() / 10.0;
//!     for (i, p) in frame.iter_mut().enumerate() {
//!         let x = (i % 32) as f64 - 15.5;
//!         *p = (127.5 + 127.5 * (x / width).tanh()) as u8;
//!     }
//!     tenengrad(&ImageView::packed(&frame, 32, 8)?)
//! };
//! let r = autofocus(&mut grab, &AutofocusOptions::default()).unwrap();
//! assert!((r.best_ma - 150.0).abs() < 1.0 && r.evaluations <= 15);
//! ```

pub mod autofocus;
pub mod brenner;
pub mod image;
pub mod laplacian;
pub mod normvar;
pub mod tenengrad;

pub use autofocus::{autofocus, AutofocusOptions, AutofocusResult};
pub use brenner::brenner;
pub use image::{ImageView, Pixel, MAX_SIDE_PX};
pub use laplacian::laplacian_variance;
pub use normvar::normalised_variance;
pub use tenengrad::tenengrad;

#[cfg(test)]
mod tests;
