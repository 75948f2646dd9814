//! Links etl-core into a `#![no_std]` artefact without a global allocator (see Cargo.toml).
//! Each exported function calls one part of the core so the linker keeps it.
#![no_std]

use etl_core::model::CameraModel;

// The panic handler calls a function that exists nowhere. If any panic path in etl-core is
// reachable from the exported functions after optimisation, the final link (a cdylib
// linked with --no-undefined, see build.rs) fails naming `etl_core_can_panic`.
extern "C" {
    fn etl_core_can_panic() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never executed: the symbol is undefined, so a build in which this handler is
    // reachable does not link.
    unsafe { etl_core_can_panic() }
}

/// Projects a world point of the paper rig; returns u + v, or NaN on error.
#[no_mangle]
pub extern "C" fn etl_gate_project(x: f64, y: f64, z: f64, e_ma: f64) -> f64 {
    match CameraModel::paper_rig().project([x, y, z], e_ma) {
        Ok([u, v]) => u + v,
        Err(_) => f64::NAN,
    }
}

/// Undistorts a pixel of the paper rig; returns u + v, or NaN on error.
#[no_mangle]
pub extern "C" fn etl_gate_undistort(u: f64, v: f64, e_ma: f64) -> f64 {
    match CameraModel::paper_rig().undistort([u, v], e_ma) {
        Ok([a, b]) => a + b,
        Err(_) => f64::NAN,
    }
}
