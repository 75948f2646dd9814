//! The integration tests of etl-rig, one binary: each module one subject.

#[cfg(feature = "aravis")]
mod aravis;
mod capture;
mod thermal;
#[cfg(all(feature = "v4l2", target_os = "linux"))]
mod v4l2;
mod zaber;
