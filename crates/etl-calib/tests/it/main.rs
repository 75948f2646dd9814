//! The integration tests of etl-calib, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod common;

mod pipeline_baseline;
mod request;
mod rig;
mod rig_calibration;
mod rig_free_views;
mod rig_images;
mod rig_requests;
mod robust;
mod select;
mod setting_views;
mod stereo;
mod uncertainty;
mod zhang;
mod zhang_opencv;
