//! The paper rig's facts (docs/METHOD.md): its 15 views' stage positions and currents, its board
//! and temperature, and the focus law they imply: piecewise linear through the stage
//! positions ([`focused_z_mm`], where the stage stands at a current) and the smooth physical
//! law of the simulated lens ([`PAPER_FOCUS_LAW_MA`], what is sharp at a current). Shared by the synthetic camera
//! ([`crate::render`]) and the simulation ([`crate::simulate`]), which import this module
//! and not each other.

use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_core::model::CameraModel;
use etl_formats::board::Board;

/// Stage positions of the paper's 15 views, mm.
pub const PAPER_Z_W_MM: [f64; 15] =
    [75.0, 60.0, 48.0, 43.0, 35.0, 31.0, 28.0, 22.0, 19.0, 16.0, 13.0, 10.0, 8.0, 4.0, 2.0];
/// Compensated currents of the paper's 15 views, mA.
pub const PAPER_E_COM_MA: [f64; 15] =
    [80.0, 90.0, 100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0, 180.0, 190.0, 200.0, 210.0, 225.0];
/// Inner corners of the paper's board (columns, rows) and its square, mm.
pub const PAPER_BOARD: ([usize; 2], f64) = ([14, 12], 1.5);

/// A ChArUco board by its `etlcal.board/1` fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharucoSpec {
    /// Squares [cols, rows].
    pub squares: [u32; 2],
    /// Side of a square, mm.
    pub square_mm: f64,
    /// Side of a marker, mm.
    pub marker_mm: f64,
    /// OpenCV's name of the dictionary.
    pub dictionary: &'static str,
}

impl CharucoSpec {
    /// The board (checked by [`Board::charuco`]).
    pub fn board(&self) -> etl_formats::Result<Board> {
        Board::charuco(self.squares, self.square_mm, self.marker_mm, self.dictionary)
    }
}

/// The simulated paper rig's ChArUco board: the squares of the paper's board (15 x 13 of
/// 1.5 mm, so that its 14 x 12 inner corners are the ChArUco corners) with markers of
/// 1.1 mm (cells of 0.16 mm, 10 to 19 px over the rig's views) from DICT_5X5_100 (97 of
/// its 100 markers), where the paper's board is: as the paper's board, it overflows the
/// frame at the near views. Its frame (OpenCV's) starts one square before the paper
/// board's first inner corner ([`charuco_frame`]).
pub const PAPER_CHARUCO: CharucoSpec =
    CharucoSpec { squares: [15, 13], square_mm: 1.5, marker_mm: 1.1, dictionary: "DICT_5X5_100" };

/// The lens-off views' ChArUco board: the squares of the lens-off checkerboard
/// ([`crate::simulate::LENS_OFF_BOARD`], 11 x 8 inner corners of 4 mm: 12 x 9 squares)
/// with 3 mm markers from DICT_5X5_100 (54 of them).
pub const LENS_OFF_CHARUCO: CharucoSpec =
    CharucoSpec { squares: [12, 9], square_mm: 4.0, marker_mm: 3.0, dictionary: "DICT_5X5_100" };

/// `cam` (whose world frame has a checkerboard's first inner corner at the origin) with
/// its world frame moved to the ChArUco frame of the same squares, which starts one
/// square of `square_mm` earlier on both axes: ChArUco point (x, y) is the old
/// (x - s, y - s).
pub fn charuco_frame(cam: &CameraModel, square_mm: f64) -> CameraModel {
    shifted_mm(cam, [-square_mm, -square_mm])
}

/// `cam` with its world frame's origin moved to the old point (dx, dy, 0): new point
/// (x, y, z) is the old (x + dx, y + dy, z) (t' = t + R (dx, dy, 0)).
pub fn shifted_mm(cam: &CameraModel, [dx, dy]: [f64; 2]) -> CameraModel {
    let r = rodrigues_to_matrix(cam.rotation_rodrigues);
    let o = mat_vec(&r, [dx, dy, 0.0]);
    let t = cam.translation_mm;
    CameraModel { translation_mm: [t[0] + o[0], t[1] + o[1], t[2] + o[2]], ..*cam }
}
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The ChArUco rig boards are valid and their corners are the paper boards' inner
    /// corners, seen at the same pixels through `charuco_frame`.
    #[test]
    fn the_charuco_boards_sit_where_the_checkerboards_do() {
        let truth = CameraModel::paper_rig();
        for (spec, (inner, sq)) in [(PAPER_CHARUCO, PAPER_BOARD), (LENS_OFF_CHARUCO, crate::simulate::LENS_OFF_BOARD)] {
            let b = spec.board().unwrap();
            assert_eq!(b.corner_grid(), inner);
            let cam = charuco_frame(&truth, sq);
            for id in [0u32, 7, (inner[0] * inner[1] - 1) as u32] {
                let [x, y] = b.corner_mm(id).unwrap();
                let (i, j) = ((id as usize % inner[0]) as f64, (id as usize / inner[0]) as f64);
                let a = cam.project([x, y, 20.0], 150.0).unwrap();
                let c = truth.project([i * sq, j * sq, 20.0], 150.0).unwrap();
                assert!((a[0] - c[0]).abs() < 1e-9 && (a[1] - c[1]).abs() < 1e-9, "{id}");
            }
        }
    }
}
