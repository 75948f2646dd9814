//! # etl-core
//!
//! The allocation-free, panic-free core of etlcal: the camera model of a camera focused by
//! an electrically tunable lens (ETL), real-time temperature compensation, the lens physics
//! model, polynomial and surface fits, the linear initialisers of the calibration, a
//! hand-written Levenberg-Marquardt solver, bundle adjustment, plane-based PnP, and
//! whole-image undistortion maps and remapping over caller buffers.
//!
//! Equation numbers refer to the paper (*Calibration method for the electrically tunable lens
//! based on shape-changing polymer*, Optics Express 2020) as docs/METHOD.md reads it:
//! lengths in mm, currents in mA, temperatures in degC, pixels with (0, 0) at the centre
//! of the top-left pixel.
//!
//! Rules this crate keeps (and CI checks): `#![no_std]` without `alloc`; no `unsafe`; no
//! panics on any input (every fallible function returns [`Result`]); everything `f64`;
//! memory that grows with the problem size is provided by the caller (see the
//! `*_scratch` functions).
//!
//! ```
//! use etl_core::model::CameraModel;
//! let cam = CameraModel::paper_rig();
//! let px = cam.project([3.0, 4.5, 48.0], 100.0).unwrap();
//! let back = cam.undistort(px, 100.0).unwrap();
//! assert!(px[0] > 0.0 && px[0] < 1936.0 && back[1] > 0.0);
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod board;
pub mod calib;
pub mod error;
pub mod fit;
pub mod focus;
pub mod lens;
pub mod linalg;
pub mod lm;
pub mod model;
pub mod physics;
pub mod pnp;
pub mod progress;
pub mod runtime;
pub mod thermal;
pub mod undistort;

pub use error::{Compact, Error, Result};

// The paths before issue 26 named modules for what they held: kept so that code written
// against them still compiles, hidden from the documentation.
#[doc(hidden)]
pub use runtime as camera;
