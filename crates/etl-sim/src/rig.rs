//! The paper rig's facts (docs/METHOD.md): its 15 views' stage positions and currents, its board
//! and temperature, and the focus law they imply: piecewise linear through the stage
//! positions ([`focused_z_mm`], where the stage stands at a current) and the smooth physical
//! law of the simulated lens ([`PAPER_FOCUS_LAW_MA`], what is sharp at a current). Shared by the synthetic camera
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

/// The simulated lens's focus law: the camera depth Z_f (mm) of the plane in focus at
/// current E (mA) obeys E = c0 + c1 V + c2 V^2 with V = 1000 / Z_f (dioptres), the form of
/// [`etl_core::focus::FocusLaw`] (why this form: its docs and docs/METHOD.md).
///
/// Provenance: the least-squares fit of that form (`FocusLaw::fit`) to the paper's 15
/// views, each taken as in focus at its current and at the camera depth, under
/// [`CameraModel::paper_rig`], of the centroid of its visible corners (the samples
/// `etl_calib::pipeline::focus_law::focus_samples` makes of the noise-free rig;
/// `tests/focus_law.rs` refits them). Its RMS residual is 2.71 mA (4.75 mA at worst, at
/// 210 mA): the paper's stage positions are whole millimetres and no smooth law passes
/// through them, so the rig's views are slightly out of focus (at most about 1 px of blur
/// sigma at aperture 2.5 mm).
pub const PAPER_FOCUS_LAW_MA: [f64; 3] = [-2.0889218690457646e1, 1.1308537646717632e1, 4.255592823755981e-2];

/// Camera depth (mm) of the plane in focus at current `e_ma` under [`PAPER_FOCUS_LAW_MA`]:
/// the positive root V of c2 V^2 + c1 V + c0 - E = 0, then 1000 / V. Infinity for
/// currents at or below c0 (focus at or beyond infinity).
pub fn focus_law_depth_mm(e_ma: f64) -> f64 {
    let [c0, c1, c2] = PAPER_FOCUS_LAW_MA;
    // c1, c2 > 0: the larger root, written without cancellation.
    let c = c0 - e_ma;
    let v = -2.0 * c / (c1 + (c1 * c1 - 4.0 * c2 * c).sqrt());
    if v > 0.0 {
        1000.0 / v
    } else {
        f64::INFINITY
    }
}

/// Current (mA) at which the plane in focus lies at camera depth `depth_mm` under
/// [`PAPER_FOCUS_LAW_MA`] (the inverse of [`focus_law_depth_mm`]).
pub fn focus_law_current_ma(depth_mm: f64) -> f64 {
    let [c0, c1, c2] = PAPER_FOCUS_LAW_MA;
    let v = 1000.0 / depth_mm;
    c0 + v * (c1 + v * c2)
}
