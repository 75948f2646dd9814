//! etl-rig: the rig of an ETL camera, and the procedures that capture a dataset with it.
//!
//! - Devices: [`camera::Camera`] (backends [`camera::files`], [`camera::sim`]; aravis
//!   behind the cargo feature `aravis`), [`stage::Stage`] ([`stage::sim`],
//!   [`stage::manual`], [`stage::zaber`]) and the lens through etl-core's `Lens` trait
//!   ([`lens::RigLens`]: the Lens Driver 4 client or the virtual lens), each opened from a
//!   spec string ([`spec`]) and failing with an error that names the device
//!   ([`error::Error::kind`]).
//! - Procedures: [`capture::capture_views`], [`capture::capture_offstate`]: an
//!   `etlcal.plan/1` in, `dataset.json` and its images out, always whole on disk and
//!   resumable; [`capture::capture_thermal`]: the temperature procedure (section 4.1),
//!   its table and fitted surface out, resumable too.
//!
//! The command line (`etlcal capture`, `camera`, `stage`) and Python call these; this crate
//! imports neither.

#![warn(missing_docs)]

pub mod camera;
pub mod capture;
pub mod error;
pub mod lens;
pub mod rig;
pub mod sim;
pub mod spec;
pub mod stage;

pub use error::{Error, ErrorKind, Result};
