//! The plane-to-image homography by the normalised DLT (Hartley), used by PnP and by
//! Zhang's method.

use crate::error::{all_finite, Error, Result};
use crate::fit::GivensQr;

/// H (row-major, h33 = 1) with (x, y, 1) ~ H (X, Y, 1) for board points (X, Y) and image
/// points (x, y), by least squares on the DLT equations with the board normalised to
/// [-1, 1] (h33 = 1 presumes the board origin does not map to infinity, true for a board
/// in front of a camera).
///
/// Preconditions: at least 4 pairs of equal count; finite input; not all board points on
/// one line ([`Error::Degenerate`]).
pub fn homography(board: &[[f64; 2]], image: &[[f64; 2]]) -> Result<[[f64; 3]; 3]> {
    if board.len() != image.len() {
        return Err(Error::InvalidArgument { what: "board and image points differ in number" });
    }
    if board.len() < 4 {
        return Err(Error::TooFew { what: "points for a homography", needed: 4, got: board.len() });
    }
    let mut centre = [0.0; 2];
    for (b, p) in board.iter().zip(image) {
        all_finite(b, "board point")?;
        all_finite(p, "image point")?;
        centre[0] += b[0];
        centre[1] += b[1];
    }
    let n = board.len() as f64;
    centre = [centre[0] / n, centre[1] / n];
    let scale = board.iter().fold(0.0f64, |s, b| s.max((b[0] - centre[0]).abs()).max((b[1] - centre[1]).abs()));
    if !(scale > 0.0) {
        return Err(Error::Degenerate { what: "all board points coincide" });
    }
    let mut qr = GivensQr::<8>::full();
    for (b, p) in board.iter().zip(image) {
        let (bx, by) = ((b[0] - centre[0]) / scale, (b[1] - centre[1]) / scale);
        let (x, y) = (p[0], p[1]);
        qr.add_row(&[bx, by, 1.0, 0.0, 0.0, 0.0, -x * bx, -x * by], x, 1.0)?;
        qr.add_row(&[0.0, 0.0, 0.0, bx, by, 1.0, -y * bx, -y * by], y, 1.0)?;
    }
    let h = qr
        .solve()
        .map_err(|_| Error::Degenerate { what: "board points are collinear (the homography is undetermined)" })?;
    // Undo the normalisation X' = (X - c) / s: H = H' N with N = [[1/s, 0, -cx/s], [0, 1/s, -cy/s], [0, 0, 1]].
    let (cx, cy, s) = (centre[0], centre[1], scale);
    let row = |a: f64, b: f64, c: f64| [a / s, b / s, c - a * cx / s - b * cy / s];
    Ok([row(h[0], h[1], h[2]), row(h[3], h[4], h[5]), row(h[6], h[7], 1.0)])
}
/// The two rows Zhang's method (2000, Sec. 3.1 and Appendix B) takes from one view's
/// homography `h`: v_12 and v_11 - v_22, with v_ij . b = h_i^T B h_j for the columns h_i of
/// H and b = (B11, B12, B22, B13, B23, B33) of the image of the absolute conic (so that
/// v_12 . b = 0 and (v_11 - v_22) . b = 0). Shared by the calibration and its benchmark.
pub fn zhang_constraints(h: &[[f64; 3]; 3]) -> [[f64; 6]; 2] {
    let column = |i: usize| [h[0][i], h[1][i], h[2][i]];
    let v = |a: [f64; 3], b: [f64; 3]| {
        [
            a[0] * b[0],
            a[0] * b[1] + a[1] * b[0],
            a[1] * b[1],
            a[2] * b[0] + a[0] * b[2],
            a[2] * b[1] + a[1] * b[2],
            a[2] * b[2],
        ]
    };
    let (h1, h2) = (column(0), column(1));
    let (v11, v22) = (v(h1, h1), v(h2, h2));
    [v(h1, h2), core::array::from_fn(|i| v11[i] - v22[i])]
}
