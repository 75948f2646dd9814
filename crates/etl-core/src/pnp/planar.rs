//! Planar PnP: closed-form start from the homography, then LM.

use super::homography::homography;
use crate::calib::jacobian::Projector;
use crate::error::{all_finite, Error, Result};
use crate::lm::{solve, Options, Problem, RowSink};
use crate::model::rotation::{matrix_to_rodrigues, rotation_from_two_columns, to_matrix3};
use crate::model::CameraModel;
use nalgebra::Vector3;

/// Most points [`solve_pnp`] takes (its normalised points live on the stack: 32 bytes each).
pub const MAX_PNP_POINTS: usize = 4096;

/// The pose of a board (board frame -> camera frame) found by [`solve_pnp`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardPose {
    /// Rotation board -> camera, Rodrigues vector.
    pub rotation_rodrigues: [f64; 3],
    /// Translation board -> camera, mm: the board origin in camera coordinates.
    pub translation_mm: [f64; 3],
    /// RMS reprojection error, px.
    pub rms_px: f64,
    /// LM iterations.
    pub iterations: usize,
}

/// The displacement of the board origin between two poses, in camera coordinates (mm);
/// its norm is the length of a stage move.
pub fn displacement_mm(a: &BoardPose, b: &BoardPose) -> [f64; 3] {
    [
        b.translation_mm[0] - a.translation_mm[0],
        b.translation_mm[1] - a.translation_mm[1],
        b.translation_mm[2] - a.translation_mm[2],
    ]
}

struct Reprojection<'a> {
    model: CameraModel,
    e_com_ma: f64,
    board_mm: &'a [[f64; 3]],
    pixels: &'a [[f64; 2]],
}

impl Problem<6> for Reprojection<'_> {
    fn eval(&mut self, x: &[f64; 6], jacobian: bool, sink: &mut dyn RowSink<6>) -> Result<()> {
        let mut m = self.model;
        m.rotation_rodrigues = [x[0], x[1], x[2]];
        m.translation_mm = [x[3], x[4], x[5]];
        let proj = Projector::new(&m);
        for (w, px) in self.board_mm.iter().zip(self.pixels) {
            let p = proj.project(*w, self.e_com_ma, jacobian)?;
            for row in 0..2 {
                let j: [f64; 6] = core::array::from_fn(|k| p.d_params[row][k]);
                sink.push(p.pixel[row] - px[row], &j);
            }
        }
        Ok(())
    }
}

/// The pose of a planar board (points with Z = 0 in the board frame, mm) seen at pixels
/// `pixels` at compensated current `e_com_ma` through `model` (whose own R, T are not
/// used).
///
/// Preconditions (typed errors): at least 4 points, as many pixels as points; finite
/// input; every board point with Z = 0; the points not all on one line
/// ([`Error::Degenerate`]); pixels the model can undistort.
///
/// ```
/// use etl_core::model::CameraModel;
/// use etl_core::pnp::solve_pnp;
/// let mut cam = CameraModel::paper_rig();
/// let board: Vec<[f64; 3]> = (0..20).map(|i| [1.5 * (i % 5) as f64, 1.5 * (i / 5) as f64, 0.0]).collect();
/// // Put the board at the paper rig's pose shifted to Z_W = 48 mm.
/// let px: Vec<[f64; 2]> = board.iter().map(|b| cam.project([b[0], b[1], 48.0], 100.0).unwrap()).collect();
/// let pose = solve_pnp(&cam, 100.0, &board, &px).unwrap();
/// let t = cam.world_to_camera([0.0, 0.0, 48.0]);
/// assert!((pose.translation_mm[2] - t[2]).abs() < 1e-8);
/// ```
pub fn solve_pnp(model: &CameraModel, e_com_ma: f64, board_mm: &[[f64; 3]], pixels: &[[f64; 2]]) -> Result<BoardPose> {
    if board_mm.len() != pixels.len() {
        return Err(Error::InvalidArgument { what: "board points and pixels differ in number" });
    }
    if board_mm.len() < 4 {
        return Err(Error::TooFew { what: "points for PnP", needed: 4, got: board_mm.len() });
    }
    let k = model.intrinsics(e_com_ma)?;
    for (w, p) in board_mm.iter().zip(pixels) {
        all_finite(w, "board point")?;
        all_finite(p, "pixel")?;
        if w[2] != 0.0 {
            return Err(Error::InvalidArgument { what: "board points must lie on Z = 0 of the board frame" });
        }
    }
    let n = board_mm.len() as f64;
    // The homography from board (X, Y) to normalised undistorted image coordinates.
    let mut img = [[0.0; 2]; MAX_PNP_POINTS];
    let mut brd = [[0.0; 2]; MAX_PNP_POINTS];
    let m = board_mm.len();
    let (Some(img), Some(brd)) = (img.get_mut(..m), brd.get_mut(..m)) else {
        return Err(Error::OutOfRange { what: "PnP points", value: m as f64, min: 4.0, max: MAX_PNP_POINTS as f64 });
    };
    for ((w, p), (bi, ii)) in board_mm.iter().zip(pixels).zip(brd.iter_mut().zip(img.iter_mut())) {
        let und = model.undistort(*p, e_com_ma)?;
        *ii = [(und[0] - k.u0) / k.fx, (und[1] - k.v0) / k.fy];
        *bi = [w[0], w[1]];
    }
    // The columns of H (nalgebra's array form of a matrix is its columns; owned vectors,
    // since arithmetic on column views keeps panicking bounds checks the gate rejects).
    let [c1, c2, c3]: [[f64; 3]; 3] = to_matrix3(&homography(brd, img)?).into();
    let (c1, c2, c3) = (Vector3::from(c1), Vector3::from(c2), Vector3::from(c3));
    let (n1, n2) = (c1.norm(), c2.norm());
    if !(n1 > 0.0 && n2 > 0.0) {
        return Err(Error::Degenerate { what: "PnP homography is singular" });
    }
    let mut lambda = 2.0 / (n1 + n2);
    if c3.z * lambda < 0.0 {
        lambda = -lambda; // the board is in front of the camera
    }
    let rot = rotation_from_two_columns((c1 * lambda).into(), (c2 * lambda).into());
    let t = c3 * lambda;
    let om = matrix_to_rodrigues(&rot);
    let mut problem = Reprojection { model: *model, e_com_ma, board_mm, pixels };
    let x0 = [om[0], om[1], om[2], t[0], t[1], t[2]];
    let opts = Options { max_iterations: 50, ftol: 1e-15, xtol: 1e-15, gtol: 1e-15, ..Options::default() };
    let r = solve(&mut problem, x0, &opts)?;
    Ok(BoardPose {
        rotation_rodrigues: [r.x[0], r.x[1], r.x[2]],
        translation_mm: [r.x[3], r.x[4], r.x[5]],
        rms_px: libm::sqrt(r.cost / n),
        iterations: r.iterations,
    })
}
