//! The integration tests of etlcal, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

#[path = "../../../../fuzz/src/bodies.rs"]
mod bodies;
mod common;

mod architecture;
mod cli_board;
mod cli_calibrate;
mod cli_calibrate_rig;
mod cli_calibrate_rig_cameras;
mod cli_capture;
mod cli_capture_thermal;
mod cli_conventions;
mod cli_dataset;
mod cli_detect;
mod cli_diff;
mod cli_distortion;
mod cli_focal_power;
mod cli_focus;
mod cli_lens;
mod cli_measure;
mod cli_model;
mod cli_optics;
mod cli_outputs;
mod cli_render;
mod cli_report;
mod cli_rig;
mod cli_runtime;
mod cli_stereo;
mod cli_study;
mod cli_thermal;
mod cli_undistort;
mod cli_zhang;
mod docs_cli;
mod docs_links;
mod fuzz_corpus;
mod golden;
mod wheel_features;
