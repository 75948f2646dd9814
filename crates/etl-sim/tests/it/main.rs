//! The integration tests of etl-sim, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod autofocus;
mod focal_power;
mod focus_law;
mod lens_dynamics;
mod multi_camera;
mod optics;
mod optics_multi_camera;
mod render;
mod rig_images;
mod simconfig_prop;
mod thermal_calibration;
