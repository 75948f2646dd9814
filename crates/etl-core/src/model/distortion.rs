//! Lens distortion in centred pixel coordinates (Eq. 17, 18).
//!
//! Eq. 17 as this project reads it (docs/METHOD.md): with u, v the ideal pixel offsets from the
//! principal point and r^2 = u^2 + v^2,
//!
//! ```text
//! u_d = u + k1 u r^2 + p1 (3u^2 + v^2) + 2 p2 u v
//! v_d = v + k1 v r^2 + 2 p1 u v + p2 (u^2 + 3v^2)
//! ```
//!
//! The paper prints `p2 (3u^2 + v^2)` in v_d; that is a typo for Weng et al.'s (1992)
//! decentering term `p2 (u^2 + 3v^2)`, used here. Note that the paper's p1, p2 are OpenCV's
//! p2, p1 (scaled by f): see `Distortion::to_opencv`.

use serde::{Deserialize, Serialize};

/// Distortion coefficients at one current: radial `k1` (1/px^2) and decentering `p1`, `p2`
/// (1/px), acting in centred pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Distortion {
    /// Radial coefficient, 1/px^2.
    pub k1: f64,
    /// Decentering coefficient paired with (3u^2 + v^2) in u_d, 1/px.
    pub p1: f64,
    /// Decentering coefficient paired with (u^2 + 3v^2) in v_d, 1/px.
    pub p2: f64,
}

impl Distortion {
    /// Eq. 18: the coefficients at mean focal length `f_mean_px` from the nine a_i.
    /// With w = 1 / f_mean: k1 = a1 w^2 + a2 w + a3, p1 = a4 w^2 + a5 w + a6,
    /// p2 = a7 w^2 + a8 w + a9.
    #[inline]
    pub fn from_a(a: &[f64; 9], f_mean_px: f64) -> Self {
        let w = 1.0 / f_mean_px;
        let w2 = w * w;
        Distortion { k1: a[0] * w2 + a[1] * w + a[2], p1: a[3] * w2 + a[4] * w + a[5], p2: a[6] * w2 + a[7] * w + a[8] }
    }

    /// Eq. 17: ideal centred (u, v) -> distorted centred (u_d, v_d).
    #[inline]
    pub fn distort(&self, u: f64, v: f64) -> [f64; 2] {
        let (uu, vv, uv) = (u * u, v * v, u * v);
        let r2 = uu + vv;
        [
            u + self.k1 * u * r2 + self.p1 * (3.0 * uu + vv) + 2.0 * self.p2 * uv,
            v + self.k1 * v * r2 + 2.0 * self.p1 * uv + self.p2 * (uu + 3.0 * vv),
        ]
    }

    /// Jacobian of [`Self::distort`] with respect to (u, v): `[[du_d/du, du_d/dv],
    /// [dv_d/du, dv_d/dv]]`.
    #[inline]
    pub fn distort_jacobian(&self, u: f64, v: f64) -> [[f64; 2]; 2] {
        let (uu, vv, uv) = (u * u, v * v, u * v);
        let r2 = uu + vv;
        let cross = 2.0 * self.k1 * uv + 2.0 * self.p1 * v + 2.0 * self.p2 * u;
        [
            [1.0 + self.k1 * (r2 + 2.0 * uu) + 6.0 * self.p1 * u + 2.0 * self.p2 * v, cross],
            [cross, 1.0 + self.k1 * (r2 + 2.0 * vv) + 2.0 * self.p1 * u + 6.0 * self.p2 * v],
        ]
    }

    /// OpenCV's (k1, k2, p1, p2, k3) for this distortion at focal length `f_px` (fx = fy).
    ///
    /// OpenCV works in normalised coordinates x = u / f: k1_cv = k1 f^2, p2_cv = p1 f,
    /// p1_cv = p2 f; k2 = k3 = 0. Exact when fx = fy; approximate otherwise.
    pub fn to_opencv(&self, f_px: f64) -> [f64; 5] {
        [self.k1 * f_px * f_px, 0.0, self.p2 * f_px, self.p1 * f_px, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_finite_differences() {
        let d = Distortion { k1: -2.2e-9, p1: 1.3e-6, p2: -4e-7 };
        for &(u, v) in &[(0.0, 0.0), (800.0, -600.0), (-900.0, 700.0), (123.0, 45.0)] {
            let j = d.distort_jacobian(u, v);
            let h = 1e-3;
            for (k, (du, dv)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
                let p = d.distort(u + du, v + dv);
                let m = d.distort(u - du, v - dv);
                for r in 0..2 {
                    let fd = (p[r] - m[r]) / (2.0 * h);
                    assert!((fd - j[r][k]).abs() < 1e-7, "{r}{k}: {fd} vs {}", j[r][k]);
                }
            }
        }
    }

    #[test]
    fn weng_decentering_term() {
        // A pure p2 distortion: v_d - v = p2 (u^2 + 3 v^2) (Weng), not p2 (3u^2 + v^2).
        let d = Distortion { k1: 0.0, p1: 0.0, p2: 1e-6 };
        let [ud, vd] = d.distort(100.0, 200.0);
        assert!((vd - 200.0 - 1e-6 * (100.0f64 * 100.0 + 3.0 * 200.0 * 200.0)).abs() < 1e-12);
        assert!((ud - 100.0 - 2.0 * 1e-6 * 100.0 * 200.0).abs() < 1e-12);
    }
}
