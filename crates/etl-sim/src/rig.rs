//! The paper rig's facts (NOTES.md): its 15 views' stage positions and currents, its board
//! and temperature, and the focus law they imply. Shared by the synthetic camera
//! ([`crate::render`]) and the simulation ([`crate::simulate`]), which import this module
//! and not each other.

use etl_core::model::CameraModel;

/// Stage positions of the paper's 15 views, mm.
pub const PAPER_Z_W_MM: [f64; 15] =
    [75.0, 60.0, 48.0, 43.0, 35.0, 31.0, 28.0, 22.0, 19.0, 16.0, 13.0, 10.0, 8.0, 4.0, 2.0];
/// Compensated currents of the paper's 15 views, mA.
pub const PAPER_E_COM_MA: [f64; 15] =
    [80.0, 90.0, 100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0, 180.0, 190.0, 200.0, 210.0, 225.0];
/// Inner corners of the paper's board (columns, rows) and its square, mm.
pub const PAPER_BOARD: ([usize; 2], f64) = ([14, 12], 1.5);
/// Lens temperature of the simulated views, degC.
pub const PAPER_TEMPERATURE_C: f64 = 27.0;

/// The stage position (mm) at which the paper rig is in focus at current `e_ma`
/// (piecewise-linear through the paper's 15 views, clamped at the ends).
pub fn focused_z_mm(e_ma: f64) -> f64 {
    let (e, z) = (&PAPER_E_COM_MA, &PAPER_Z_W_MM);
    if e_ma <= e[0] {
        return z[0];
    }
    for k in 1..e.len() {
        if e_ma <= e[k] {
            let t = (e_ma - e[k - 1]) / (e[k] - e[k - 1]);
            return z[k - 1] + t * (z[k] - z[k - 1]);
        }
    }
    z[z.len() - 1]
}

/// Depth of the plane in focus at current `e_ma`, mm (the paper rig's stage position for
/// that current, seen from the camera at the board's centre).
pub fn focus_depth_mm(truth: &CameraModel, e_ma: f64) -> f64 {
    let ([cols, rows], sq) = PAPER_BOARD;
    let c = [sq * (cols - 1) as f64 / 2.0, sq * (rows - 1) as f64 / 2.0, focused_z_mm(e_ma)];
    truth.world_to_camera(c)[2]
}
