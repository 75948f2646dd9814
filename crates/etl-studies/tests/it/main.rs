//! The integration tests of etl-studies, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod optics;
mod rig_efficiency;
mod rig_traced;
mod rig_triangulation;
mod study;
