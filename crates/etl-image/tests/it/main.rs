//! The integration tests of etl-image, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod charuco;
mod detect;
mod read;
mod sharpness;
