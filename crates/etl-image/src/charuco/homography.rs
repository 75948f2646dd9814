//! A plane-to-image homography with its local derivative: the markers' cells, the board's
//! points near a marker, and the local scale of the board in the image.

/// `H` with (u, v, 1) ~ H (x, y, 1), row-major.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Homography(pub [[f64; 3]; 3]);

impl Homography {
    /// The homography taking the four plane points `from` to the image points `to`
    /// (etl-core's normalised DLT); `None` when degenerate.
    pub fn fit(from: &[[f64; 2]; 4], to: &[[f64; 2]; 4]) -> Option<Self> {
        etl_core::pnp::homography(from, to).ok().map(Self)
    }

    /// The image of plane point `p`.
    #[inline]
    pub fn map(&self, p: [f64; 2]) -> [f64; 2] {
        let h = &self.0;
        let w = h[2][0] * p[0] + h[2][1] * p[1] + h[2][2];
        [(h[0][0] * p[0] + h[0][1] * p[1] + h[0][2]) / w, (h[1][0] * p[0] + h[1][1] * p[1] + h[1][2]) / w]
    }

    /// The derivative at plane point `p`: `[[du/dx, du/dy], [dv/dx, dv/dy]]`.
    pub fn jacobian(&self, p: [f64; 2]) -> [[f64; 2]; 2] {
        let h = &self.0;
        let w = h[2][0] * p[0] + h[2][1] * p[1] + h[2][2];
        let [u, v] = self.map(p);
        [
            [(h[0][0] - u * h[2][0]) / w, (h[0][1] - u * h[2][1]) / w],
            [(h[1][0] - v * h[2][0]) / w, (h[1][1] - v * h[2][1]) / w],
        ]
    }
}

/// The inverse of a 2 x 2 matrix; `None` when singular.
pub(crate) fn inverse2(m: [[f64; 2]; 2]) -> Option<[[f64; 2]; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    (det.abs() > 1e-12).then(|| [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_the_four_points_and_differentiates() {
        let from = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let to = [[10.0, 20.0], [40.0, 22.0], [45.0, 55.0], [8.0, 50.0]];
        let h = Homography::fit(&from, &to).unwrap();
        for (f, t) in from.iter().zip(&to) {
            let m = h.map(*f);
            assert!((m[0] - t[0]).abs() < 1e-9 && (m[1] - t[1]).abs() < 1e-9);
        }
        let p = [0.3, 0.6];
        let j = h.jacobian(p);
        let e = 1e-6;
        for c in 0..2 {
            let mut q = p;
            q[c] += e;
            let (a, b) = (h.map(q), h.map(p));
            assert!(((a[0] - b[0]) / e - j[0][c]).abs() < 1e-4);
            assert!(((a[1] - b[1]) / e - j[1][c]).abs() < 1e-4);
        }
        let inv = inverse2(j).unwrap();
        let id = [j[0][0] * inv[0][0] + j[0][1] * inv[1][0], j[0][0] * inv[0][1] + j[0][1] * inv[1][1]];
        assert!((id[0] - 1.0).abs() < 1e-12 && id[1].abs() < 1e-12);
    }
}
