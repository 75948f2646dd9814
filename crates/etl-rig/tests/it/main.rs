//! The integration tests of etl-rig, one binary: each module one subject.

#[cfg(feature = "aravis")]
mod aravis;
mod capture;
mod thermal;
mod zaber;
