//! The Python module `etlcal` (built by maturin as `etlcal._etlcal`).
//!
//! A file per noun: [`errors`] (the exception hierarchy), [`calibration`], [`thermal`],
//! [`physics`], [`observations`], [`board`], [`dataset`], [`pipeline`] (calibrate), [`zhang`],
//! [`images`] (detect_corners, sharpness, render), [`focus`] (autofocus), [`lens`] (Lens,
//! VirtualLens), [`thermal_calibration`], [`studies`]; [`arrays`] converts numpy arrays.
//! The Python package (`python/etlcal/`) re-exports these and adds the submodules and type
//! stubs.
use pyo3::prelude::*;

pub mod arrays;
pub mod board;
pub mod calibration;
pub mod camera;
pub mod dataset;
pub mod diff;
pub mod errors;
pub mod focus;
pub mod images;
pub mod lens;
pub mod observations;
pub mod physics;
pub mod pipeline;
pub mod pool;
pub mod pose;
pub mod results;
pub mod rig;
pub mod rig_calibration;
pub mod rig_runtime;
pub mod simulate;
pub mod stereo;
pub mod studies;
pub mod thermal;
pub mod thermal_calibration;
pub mod undistort;
pub mod zhang;

#[pymodule]
fn _etlcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    pool::prepare();
    arrays::prepare(m.py());
    // The planes of a first checkerboard detection in a 640 x 480 image (the fixtures'
    // webcam; 1280 x 960 and 2560 x 1920 images start at the same 320 x 240 level):
    // touched here, ~0.15 ms of the import, instead of page-faulted by that first call.
    etl_image::checkerboard::prepare(640, 480);
    errors::register(m)?;
    // A test hook, private: set as an attribute so that it stays out of `__all__`.
    m.setattr("_raise_rust_error", wrap_pyfunction!(errors::_raise_rust_error, m)?)?;
    m.setattr("_panic", wrap_pyfunction!(errors::_panic, m)?)?;
    m.setattr("_PanicProbe", m.py().get_type::<errors::_PanicProbe>())?;
    m.add_class::<calibration::Calibration>()?;
    m.add_class::<camera::CameraAt>()?;
    m.add_class::<thermal::ThermalSurface>()?;
    m.add_class::<thermal::ThermalCalibration>()?;
    m.add_class::<physics::LensPhysics>()?;
    m.add_class::<observations::Observations>()?;
    m.add_class::<dataset::Dataset>()?;
    m.add_class::<board::Board>()?;
    m.add_class::<observations::A0>()?;
    m.add_class::<pose::BoardPose>()?;
    m.add_class::<simulate::Simulation>()?;
    m.add_function(wrap_pyfunction!(simulate::simulate_paper_rig, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate_strong_rig, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(rig_calibration::calibrate_rig, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::cramer_rao_std, m)?)?;
    m.add_function(wrap_pyfunction!(images::detect_corners, m)?)?;
    m.add_function(wrap_pyfunction!(images::sharpness, m)?)?;
    m.add_function(wrap_pyfunction!(images::render, m)?)?;
    m.add_function(wrap_pyfunction!(focus::autofocus, m)?)?;
    m.add_function(wrap_pyfunction!(zhang::zhang, m)?)?;
    m.add_function(wrap_pyfunction!(stereo::stereo, m)?)?;
    // Private (not in __all__): reached through ZhangResult.projection_std only.
    m.setattr("_ZhangProjection", m.py().get_type::<zhang::ZhangProjection>())?;
    m.add_function(wrap_pyfunction!(diff::diff, m)?)?;
    m.add_function(wrap_pyfunction!(studies::study, m)?)?;
    m.add_class::<lens::Lens>()?;
    m.add_class::<lens::VirtualLens>()?;
    m.add_function(wrap_pyfunction!(thermal_calibration::thermal_calibration, m)?)?;
    m.add_class::<rig::RigCamera>()?;
    m.add_class::<rig_runtime::Rig>()?;
    m.add_class::<rig_runtime::RigAt>()?;
    m.add_function(wrap_pyfunction!(rig::rig_capture_views, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_capture_offstate, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_capture_thermal, m)?)?;
    Ok(())
}
