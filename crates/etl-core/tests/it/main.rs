//! The integration tests of etl-core, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod common;

mod centre;
mod dynamics;
mod families;
mod input_noise;
mod lm;
mod nist;
mod no_panic;
mod setting_offset;
mod solvers;
