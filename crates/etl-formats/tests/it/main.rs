//! The integration tests of etl-formats, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod support {
    pub mod formats;
    pub mod mutate;
}

mod bad_input;
mod calibration;
mod focus_law;
mod lens_dynamics;
mod optics;
mod readers_mutations;
mod readers_prop;
