//! Pixel -> board plane: the inverse of the model's projection (Eq. 13-17) for points on
//! the plane Z_W = board_z_mm.
//!
//! The plane's homography H = [r1 r2 r3 Z_b + T] maps board (X, Y, 1) to camera
//! coordinates; its inverse, composed with A(E)^-1, maps an undistorted centred pixel
//! (u, v, 1) to (X, Y, 1) / Z_c, so the third component is the reciprocal of the camera
//! depth Z_c of the board point (positive in front of the camera). Undistortion is Newton
//! on Eq. 17, continued along a row of pixel corners from its neighbour so that two
//! iterations usually reach 1e-10 px; the first point of a row (and any point where the
//! continuation does not converge) uses etl-core's safeguarded `Distortion::undistort`.

use etl_core::model::{CameraModel, Distortion};

use etl_formats::{Error, Result};

/// Tolerance of the continued Newton iteration, px.
const NEWTON_TOL_PX: f64 = 1e-10;
/// Newton steps of the continuation before falling back to the safeguarded solver.
const NEWTON_STEPS: usize = 6;

/// A board point seen through a pixel position: board (X, Y) in mm and the reciprocal of
/// its camera depth, 1/mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoardPoint {
    pub x_mm: f64,
    pub y_mm: f64,
    pub inv_depth: f64,
}

/// The pixel -> board-plane map of one scene.
#[derive(Debug, Clone)]
pub(crate) struct PixelToBoard {
    u0: f64,
    v0: f64,
    dist: Distortion,
    /// Maps undistorted centred (u, v, 1) to (X, Y, 1) / Z_c.
    m: [[f64; 3]; 3],
    /// Maps board (X, Y, 1) to camera (Xc, Yc, Zc).
    h: [[f64; 3]; 3],
}

fn inverse3(a: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1]
    };
    let det = a[0][0] * c(0, 0) + a[0][1] * c(0, 1) + a[0][2] * c(0, 2);
    let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    if !(det.abs() > 1e-12 * scale * scale * scale) || !det.is_finite() {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = c(j, i) / det;
        }
    }
    Some(inv)
}

impl PixelToBoard {
    /// The map for `model` at current `e_com_ma` and the plane Z_W = `board_z_mm`.
    ///
    /// Errors: the model's intrinsics or distortion are unusable at that current; the
    /// camera centre lies in the board plane (the board is seen edge-on).
    pub fn new(model: &CameraModel, e_com_ma: f64, board_z_mm: f64) -> Result<Self> {
        let k = model.intrinsics(e_com_ma)?;
        let dist = model.distortion(e_com_ma)?;
        let r = model.rotation_matrix();
        let t = model.translation_mm;
        let h = [
            [r[0][0], r[0][1], r[0][2] * board_z_mm + t[0]],
            [r[1][0], r[1][1], r[1][2] * board_z_mm + t[1]],
            [r[2][0], r[2][1], r[2][2] * board_z_mm + t[2]],
        ];
        let hinv = inverse3(&h).ok_or_else(|| {
            Error::invalid_value(
                "board_z_mm",
                board_z_mm,
                "the camera centre lies in the board plane (board seen edge-on)",
            )
        })?;
        let mut m = hinv;
        for row in m.iter_mut() {
            row[0] /= k.fx;
            row[1] /= k.fy;
        }
        Ok(PixelToBoard { u0: k.u0, v0: k.v0, dist, m, h })
    }

    /// Camera depth Z_c (mm) of board point (X, Y).
    pub fn depth_mm(&self, x_mm: f64, y_mm: f64) -> f64 {
        self.h[2][0] * x_mm + self.h[2][1] * y_mm + self.h[2][2]
    }

    /// The board point of an undistorted centred pixel (u, v); `None` when the ray meets
    /// the plane behind the camera (or at infinity).
    #[inline]
    pub fn board_of_undistorted(&self, u: f64, v: f64) -> Option<BoardPoint> {
        let m = &self.m;
        let w = m[2][0] * u + m[2][1] * v + m[2][2];
        if !(w > 0.0) {
            return None;
        }
        let x = (m[0][0] * u + m[0][1] * v + m[0][2]) / w;
        let y = (m[1][0] * u + m[1][1] * v + m[1][2]) / w;
        Some(BoardPoint { x_mm: x, y_mm: y, inv_depth: w })
    }

    /// Undistorted centred coordinates of pixel (x, y), exact (etl-core's safeguarded
    /// Newton); `None` where the distortion folds the image.
    pub fn undistort_exact(&self, x: f64, y: f64) -> Option<[f64; 2]> {
        self.dist.undistort(x - self.u0, y - self.v0).ok()
    }

    /// Undistorted centred coordinates of pixel (x, y) by Newton from `guess`, falling
    /// back to [`Self::undistort_exact`].
    #[inline]
    pub fn undistort_from(&self, x: f64, y: f64, guess: [f64; 2]) -> Option<[f64; 2]> {
        let (ud, vd) = (x - self.u0, y - self.v0);
        let [mut u, mut v] = guess;
        for _ in 0..NEWTON_STEPS {
            let [a, b] = self.dist.distort(u, v);
            let (ru, rv) = (a - ud, b - vd);
            if ru.abs() <= NEWTON_TOL_PX && rv.abs() <= NEWTON_TOL_PX {
                return Some([u, v]);
            }
            let j = self.dist.distort_jacobian(u, v);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if !(det > 1e-6) {
                break;
            }
            u -= (j[1][1] * ru - j[0][1] * rv) / det;
            v -= (j[0][0] * rv - j[1][0] * ru) / det;
        }
        self.undistort_exact(x, y)
    }

    /// Board points of the pixel positions (x0 + k, y), k = 0..out.len(), continuing the
    /// undistortion along the row.
    pub fn map_row(&self, x0: f64, y: f64, out: &mut [Option<BoardPoint>]) {
        self.map_positions(y, (0..out.len()).map(|k| x0 + k as f64), out);
    }

    /// Board points of the pixel positions (x, y) for the increasing `xs`, one per entry of
    /// `out`. Newton starts from the linear extrapolation of the two previous solutions (the
    /// undistortion is smooth along a row), which usually meets the tolerance after one
    /// step.
    pub fn map_positions(&self, y: f64, xs: impl Iterator<Item = f64>, out: &mut [Option<BoardPoint>]) {
        // (x, undistorted) of the last two solved positions.
        let mut prev: Option<(f64, [f64; 2])> = None;
        let mut prev2: Option<(f64, [f64; 2])> = None;
        for (x, o) in xs.zip(out.iter_mut()) {
            let und = match (prev, prev2) {
                (Some((xa, a)), Some((xb, b))) if xa > xb => {
                    let t = (x - xa) / (xa - xb);
                    self.undistort_from(x, y, [a[0] + t * (a[0] - b[0]), a[1] + t * (a[1] - b[1])])
                }
                (Some((xa, a)), _) => self.undistort_from(x, y, [a[0] + (x - xa), a[1]]),
                (None, _) => self.undistort_exact(x, y),
            };
            prev2 = prev;
            prev = und.map(|u| (x, u));
            if prev.is_none() {
                prev2 = None;
            }
            *o = und.and_then(|[u, v]| self.board_of_undistorted(u, v));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn board_points_project_back_to_their_pixel() {
        let cam = CameraModel::paper_rig();
        let (e, z) = (120.0, 35.0);
        let map = PixelToBoard::new(&cam, e, z).unwrap();
        let mut row = vec![None; 40];
        for &y in &[3.5, 700.0, 1450.5] {
            map.map_row(-20.5, y, &mut row);
            for (k, p) in row.iter().enumerate() {
                let p = p.unwrap();
                let px = cam.project([p.x_mm, p.y_mm, z], e).unwrap();
                assert!((px[0] - (-20.5 + k as f64)).abs() < 1e-8 && (px[1] - y).abs() < 1e-8, "{px:?}");
                let zc = cam.world_to_camera([p.x_mm, p.y_mm, z])[2];
                assert!((zc * p.inv_depth - 1.0).abs() < 1e-12);
                assert!((map.depth_mm(p.x_mm, p.y_mm) - zc).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn edge_on_board_is_an_error() {
        // Camera at the origin looking along Z; the plane Z = 0 contains the centre.
        let cam = CameraModel { rotation_rodrigues: [0.0; 3], translation_mm: [0.0; 3], ..CameraModel::paper_rig() };
        let e = PixelToBoard::new(&cam, 100.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("edge-on"), "{e}");
    }
}
