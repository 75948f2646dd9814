//! Lens distortion at one current, in either family ([`DistortionModel`]), acting on
//! centred pixel coordinates (u, v) = (pixel - principal point).
//!
//! **paper** (Eq. 17 as this project reads it, docs/METHOD.md): with r^2 = u^2 + v^2,
//!
//! ```text
//! u_d = u + k1 u r^2 + p1 (3u^2 + v^2) + 2 p2 u v
//! v_d = v + k1 v r^2 + 2 p1 u v + p2 (u^2 + 3v^2)
//! ```
//!
//! The paper prints `p2 (3u^2 + v^2)` in v_d; that is a typo for Weng et al.'s (1992)
//! decentering term `p2 (u^2 + 3v^2)`, used here. Note that the paper's p1, p2 are OpenCV's
//! p2, p1 (scaled by f): see `Distortion::to_opencv`.
//!
//! **opencv** (`cv2.projectPoints`): in normalised coordinates x = u / fx, y = v / fy,
//! r^2 = x^2 + y^2,
//!
//! ```text
//! x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//! y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
//! u_d = fx x_d,  v_d = fy y_d
//! ```
//!
//! Its inverse, undistortion ([`Distortion::undistort`]), is here too: a Newton iteration
//! on these equations, so that the distortion and its inverse are read in one file.

use super::family::{DistortionA, DistortionModel, MAX_COEFFICIENTS};
use crate::error::{all_finite, Error, Result};

/// The distortion at one current: the family, its coefficients (paper: k1 1/px^2, p1, p2
/// 1/px; opencv: k1, k2, p1, p2, k3, dimensionless) and, for opencv, the focal lengths that
/// normalise centred pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    model: DistortionModel,
    c: [f64; MAX_COEFFICIENTS],
    focal_px: [f64; 2],
}

impl Default for Distortion {
    /// No distortion (the paper family with zero coefficients).
    fn default() -> Self {
        Distortion::paper(0.0, 0.0, 0.0)
    }
}

impl Distortion {
    /// The paper's family: radial `k1` (1/px^2) and decentering `p1` (paired with
    /// 3u^2 + v^2 in u_d), `p2` (paired with u^2 + 3v^2 in v_d), 1/px.
    #[inline(always)]
    pub const fn paper(k1: f64, p1: f64, p2: f64) -> Self {
        Distortion { model: DistortionModel::Paper, c: [k1, p1, p2, 0.0, 0.0], focal_px: [1.0, 1.0] }
    }

    /// OpenCV's family: `dist` = [k1, k2, p1, p2, k3] in OpenCV's order, with the focal
    /// lengths `fx_px`, `fy_px` that normalise centred pixels (x = u / fx).
    pub const fn opencv(dist: [f64; 5], fx_px: f64, fy_px: f64) -> Self {
        Distortion { model: DistortionModel::OpenCv, c: dist, focal_px: [fx_px, fy_px] }
    }

    /// No distortion in `model` (opencv with focal lengths `fx_px`, `fy_px`).
    pub const fn none(model: DistortionModel, fx_px: f64, fy_px: f64) -> Self {
        match model {
            DistortionModel::Paper => Self::paper(0.0, 0.0, 0.0),
            DistortionModel::OpenCv => Self::opencv([0.0; 5], fx_px, fy_px),
        }
    }

    /// A family's coefficients in its order ([`DistortionModel::coefficient_names`]);
    /// entries past its count are ignored. Focal lengths as in [`Self::opencv`] (unused
    /// by the paper family).
    pub fn from_coefficients(model: DistortionModel, c: &[f64; MAX_COEFFICIENTS], fx_px: f64, fy_px: f64) -> Self {
        match model {
            DistortionModel::Paper => Self::paper(c[0], c[1], c[2]),
            DistortionModel::OpenCv => Self::opencv(*c, fx_px, fy_px),
        }
    }

    /// Eq. 18 (generalised): the coefficients of `a` at focal lengths `fx_px`, `fy_px`,
    /// each a quadratic in w = 1 / f_mean, f_mean = (fx + fy) / 2.
    #[inline(always)]
    pub fn from_a(a: &DistortionA, fx_px: f64, fy_px: f64) -> Self {
        let c = a.coefficients_at(0.5 * (fx_px + fy_px));
        Self::from_coefficients(a.model(), &c, fx_px, fy_px)
    }

    /// The family.
    pub const fn model(&self) -> DistortionModel {
        self.model
    }

    /// The coefficients in the family's order ([`DistortionModel::coefficient_count`]).
    pub fn coefficients(&self) -> &[f64] {
        self.c.get(..self.model.coefficient_count()).unwrap_or(&self.c)
    }

    /// The coefficients at capacity (zeros past the family's count).
    pub const fn padded(&self) -> &[f64; MAX_COEFFICIENTS] {
        &self.c
    }

    /// The focal lengths (fx, fy) that normalise centred pixels (opencv; [1, 1] for paper).
    pub const fn focal_px(&self) -> [f64; 2] {
        self.focal_px
    }

    /// Checks that the coefficients are finite and, for opencv, the focal lengths finite
    /// and positive. Errors name `what`.
    pub fn validate(&self, what: &'static str) -> Result<()> {
        all_finite(self.coefficients(), what)?;
        let [fx, fy] = self.focal_px;
        if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
            return Err(Error::InvalidArgument { what: "distortion focal lengths must be finite and > 0" });
        }
        Ok(())
    }

    /// Ideal centred (u, v) -> distorted centred (u_d, v_d) (module documentation).
    #[inline(always)]
    pub fn distort(&self, u: f64, v: f64) -> [f64; 2] {
        match self.model {
            DistortionModel::Paper => self.distort_paper(u, v),
            DistortionModel::OpenCv => {
                let [fx, fy] = self.focal_px;
                let [xd, yd] = self.distort_normalised(u / fx, v / fy);
                [fx * xd, fy * yd]
            }
        }
    }

    #[inline(always)]
    fn distort_paper(&self, u: f64, v: f64) -> [f64; 2] {
        let [k1, p1, p2, _, _] = self.c;
        let (uu, vv, uv) = (u * u, v * v, u * v);
        let r2 = uu + vv;
        [u + k1 * u * r2 + p1 * (3.0 * uu + vv) + 2.0 * p2 * uv, v + k1 * v * r2 + 2.0 * p1 * uv + p2 * (uu + 3.0 * vv)]
    }

    /// OpenCV's distortion of normalised (x, y), in `cv2.projectPoints`' order of terms
    /// (the same expressions as [`super::opencv::opencv_project`]). For the opencv family.
    #[inline(always)]
    pub fn distort_normalised(&self, x: f64, y: f64) -> [f64; 2] {
        let [k1, k2, p1, p2, k3] = self.c;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        [
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        ]
    }

    /// Jacobian of [`Self::distort`] with respect to (u, v): `[[du_d/du, du_d/dv],
    /// [dv_d/du, dv_d/dv]]`.
    #[inline(always)]
    pub fn distort_jacobian(&self, u: f64, v: f64) -> [[f64; 2]; 2] {
        match self.model {
            DistortionModel::Paper => {
                let [k1, p1, p2, _, _] = self.c;
                let (uu, vv, uv) = (u * u, v * v, u * v);
                let r2 = uu + vv;
                let cross = 2.0 * k1 * uv + 2.0 * p1 * v + 2.0 * p2 * u;
                [
                    [1.0 + k1 * (r2 + 2.0 * uu) + 6.0 * p1 * u + 2.0 * p2 * v, cross],
                    [cross, 1.0 + k1 * (r2 + 2.0 * vv) + 2.0 * p1 * u + 6.0 * p2 * v],
                ]
            }
            DistortionModel::OpenCv => {
                let [fx, fy] = self.focal_px;
                let j = self.normalised_jacobian(u / fx, v / fy);
                // u_d = fx x_d(u / fx, v / fy): the chain rule scales the off-diagonal terms.
                [[j[0][0], j[0][1] * fx / fy], [j[1][0] * fy / fx, j[1][1]]]
            }
        }
    }

    /// Jacobian of [`Self::distort_normalised`] with respect to (x, y).
    #[inline(always)]
    pub fn normalised_jacobian(&self, x: f64, y: f64) -> [[f64; 2]; 2] {
        let [k1, k2, p1, p2, k3] = self.c;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        // d radial / d(r^2), and d(r^2) = 2x dx + 2y dy.
        let dr = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        let (drx, dry) = (2.0 * x * dr, 2.0 * y * dr);
        [
            [radial + x * drx + 2.0 * p1 * y + 6.0 * p2 * x, x * dry + 2.0 * p1 * x + 2.0 * p2 * y],
            [y * drx + 2.0 * p1 * x + 2.0 * p2 * y, radial + y * dry + 6.0 * p1 * y + 2.0 * p2 * x],
        ]
    }

    /// d(u_d, v_d) / d(coefficients) at centred (u, v), in the family's order (columns past
    /// its count zero): the distortion is linear in its coefficients, so these are also
    /// the rows of the linear initialisation (Eq. 23).
    #[inline(always)]
    pub fn coefficient_jacobian(&self, u: f64, v: f64) -> [[f64; MAX_COEFFICIENTS]; 2] {
        match self.model {
            DistortionModel::Paper => paper_rows(u, v),
            DistortionModel::OpenCv => {
                let [fx, fy] = self.focal_px;
                let r = opencv_rows(u / fx, v / fy);
                [r[0].map(|c| fx * c), r[1].map(|c| fy * c)]
            }
        }
    }

    /// OpenCV's (k1, k2, p1, p2, k3) for this distortion.
    ///
    /// opencv family: its own coefficients, exact. paper family at focal length `f_px`
    /// (fx = fy): OpenCV works in normalised coordinates x = u / f, so k1_cv = k1 f^2,
    /// p2_cv = p1 f, p1_cv = p2 f; k2 = k3 = 0. Exact when fx = fy; approximate otherwise
    /// ([`super::fit_opencv5`] gives the least-squares coefficients and their error).
    pub fn to_opencv(&self, f_px: f64) -> [f64; 5] {
        match self.model {
            DistortionModel::Paper => {
                let [k1, p1, p2, _, _] = self.c;
                [k1 * f_px * f_px, 0.0, p2 * f_px, p1 * f_px, 0.0]
            }
            DistortionModel::OpenCv => self.c,
        }
    }
}

/// d(u_d - u, v_d - v) / d(k1, p1, p2) of the paper family at centred (u, v).
#[inline(always)]
pub fn paper_rows(u: f64, v: f64) -> [[f64; MAX_COEFFICIENTS]; 2] {
    let r2 = u * u + v * v;
    [[u * r2, 3.0 * u * u + v * v, 2.0 * u * v, 0.0, 0.0], [v * r2, 2.0 * u * v, u * u + 3.0 * v * v, 0.0, 0.0]]
}

/// d(x_d - x, y_d - y) / d(k1, k2, p1, p2, k3) of OpenCV's family at normalised (x, y).
#[inline(always)]
pub fn opencv_rows(x: f64, y: f64) -> [[f64; MAX_COEFFICIENTS]; 2] {
    let r2 = x * x + y * y;
    let r4 = r2 * r2;
    [
        [x * r2, x * r4, 2.0 * x * y, r2 + 2.0 * x * x, x * r4 * r2],
        [y * r2, y * r4, r2 + 2.0 * y * y, 2.0 * x * y, y * r4 * r2],
    ]
}

// Undistortion: the inverse of the distortion (Eq. 17 or OpenCV's), by a safeguarded
// Newton iteration.

/// Tolerance on |distort(u, v) - (u_d, v_d)|, px.
pub const UNDISTORT_TOL_PX: f64 = 1e-9;
/// Newton iterations allowed before giving up.
pub const UNDISTORT_MAX_ITER: usize = 50;

impl Distortion {
    /// Solves distort(u, v) = (u_d, v_d) for the ideal centred (u, v).
    ///
    /// Newton's method from (u_d, v_d) with the analytic 2 x 2 Jacobian, halving the step
    /// while it does not reduce the residual. Converges in 3-5 iterations over the whole
    /// image for the paper's model. Errors (never a silent wrong answer): the Jacobian is
    /// singular (the distortion folds the image there) or the residual stays above
    /// [`UNDISTORT_TOL_PX`] after [`UNDISTORT_MAX_ITER`] iterations.
    pub fn undistort(&self, ud: f64, vd: f64) -> Result<[f64; 2]> {
        all_finite(&[ud, vd], "undistort input")?;
        all_finite(self.coefficients(), "undistort input")?;
        let (mut u, mut v) = (ud, vd);
        let resid = |u: f64, v: f64| {
            let [a, b] = self.distort(u, v);
            [a - ud, b - vd]
        };
        let mut r = resid(u, v);
        let mut norm = libm::hypot(r[0], r[1]);
        for _ in 0..UNDISTORT_MAX_ITER {
            if norm <= UNDISTORT_TOL_PX {
                self.check_unfolded(u, v)?;
                return Ok([u, v]);
            }
            let j = self.distort_jacobian(u, v);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if !(det.abs() > 1e-12) || !det.is_finite() {
                return Err(Error::Degenerate {
                    what: "distortion Jacobian is singular (the model folds the image here)",
                });
            }
            let du = (j[1][1] * r[0] - j[0][1] * r[1]) / det;
            let dv = (-j[1][0] * r[0] + j[0][0] * r[1]) / det;
            let mut step = 1.0;
            loop {
                let (nu, nv) = (u - step * du, v - step * dv);
                let nr = resid(nu, nv);
                let nn = libm::hypot(nr[0], nr[1]);
                if nn < norm || step < 1e-6 {
                    u = nu;
                    v = nv;
                    r = nr;
                    norm = nn;
                    break;
                }
                step *= 0.5;
            }
            if !norm.is_finite() {
                break;
            }
        }
        if norm <= UNDISTORT_TOL_PX {
            self.check_unfolded(u, v)?;
            Ok([u, v])
        } else {
            Err(Error::NotConverged { what: "undistortion (inverse of Eq. 17)", iterations: UNDISTORT_MAX_ITER })
        }
    }

    /// A root of Eq. 17 is the right one only if the distortion is one-to-one between the
    /// principal point and it: otherwise it lies on a folded branch (a real solution of
    /// the polynomial, but not the pixel the lens imaged). We check that det J stays
    /// positive along the segment from the centre, at 16 points and at the root.
    fn check_unfolded(&self, u: f64, v: f64) -> Result<()> {
        for i in 1..=16 {
            let s = i as f64 / 16.0;
            let j = self.distort_jacobian(s * u, s * v);
            if !(j[0][0] * j[1][1] - j[0][1] * j[1][0] > 0.0) {
                return Err(Error::Degenerate {
                    what: "pixel lies beyond the fold of the distortion model (no valid undistortion)",
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::opencv::opencv_project;
    use crate::model::Intrinsics;

    fn check_jacobians(d: &Distortion, points: &[(f64, f64)], h: f64, tol: f64) {
        for &(u, v) in points {
            let j = d.distort_jacobian(u, v);
            for (k, (du, dv)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
                let p = d.distort(u + du, v + dv);
                let m = d.distort(u - du, v - dv);
                for r in 0..2 {
                    let fd = (p[r] - m[r]) / (2.0 * h);
                    assert!((fd - j[r][k]).abs() < tol, "{r}{k}: {fd} vs {}", j[r][k]);
                }
            }
            // The coefficient Jacobian: the distortion is linear in the coefficients.
            let jc = d.coefficient_jacobian(u, v);
            let base = d.distort(u, v);
            let n = d.model().coefficient_count();
            for c in 0..n {
                let mut cc = *d.padded();
                cc[c] += 1e-3;
                let [fx, fy] = d.focal_px();
                let moved = Distortion::from_coefficients(d.model(), &cc, fx, fy).distort(u, v);
                for r in 0..2 {
                    let fd = (moved[r] - base[r]) / 1e-3;
                    assert!((fd - jc[r][c]).abs() <= 1e-6 * jc[r][c].abs().max(1.0), "c{c} r{r}: {fd} vs {}", jc[r][c]);
                }
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let d = Distortion::paper(-2.2e-9, 1.3e-6, -4e-7);
        check_jacobians(&d, &[(0.0, 0.0), (800.0, -600.0), (-900.0, 700.0), (123.0, 45.0)], 1e-3, 1e-7);
    }

    /// A strong wide-angle lens in OpenCV's family (k1 = -0.3, k2 = 0.15) with fx != fy.
    #[test]
    fn opencv_jacobians_match_finite_differences() {
        let d = Distortion::opencv([-0.3, 0.15, 1e-3, -2e-3, -0.02], 600.0, 610.0);
        check_jacobians(&d, &[(0.0, 0.0), (300.0, -250.0), (-310.0, 240.0), (12.0, 45.0)], 1e-3, 1e-7);
    }

    /// The opencv family is OpenCV's formula exactly (`cv2.projectPoints`' expressions).
    #[test]
    fn opencv_family_is_opencvs_formula() {
        let k = Intrinsics { fx: 600.0, fy: 610.0, u0: 320.0, v0: 240.0 };
        let dist = [-0.3, 0.15, 1e-3, -2e-3, -0.02];
        let d = Distortion::opencv(dist, k.fx, k.fy);
        for (x, y) in [(0.0, 0.0), (0.5, -0.4), (-0.52, 0.39), (0.01, 0.3)] {
            let want = opencv_project(&k, &dist, x, y);
            let [ud, vd] = d.distort(k.fx * x, k.fy * y);
            let got = [ud + k.u0, vd + k.v0];
            assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12, "{got:?} {want:?}");
        }
        assert_eq!(d.to_opencv(1.0), dist);
    }

    #[test]
    fn weng_decentering_term() {
        // A pure p2 distortion: v_d - v = p2 (u^2 + 3 v^2) (Weng), not p2 (3u^2 + v^2).
        let d = Distortion::paper(0.0, 0.0, 1e-6);
        let [ud, vd] = d.distort(100.0, 200.0);
        assert!((vd - 200.0 - 1e-6 * (100.0f64 * 100.0 + 3.0 * 200.0 * 200.0)).abs() < 1e-12);
        assert!((ud - 100.0 - 2.0 * 1e-6 * 100.0 * 200.0).abs() < 1e-12);
    }

    #[test]
    fn folding_distortion_is_an_error_not_a_wrong_answer() {
        // Strong barrel distortion folds the image beyond r = 1 / sqrt(3 |k1|).
        let d = Distortion::paper(-1e-6, 0.0, 0.0);
        let r = d.undistort(2000.0, 0.0);
        assert!(r.is_err(), "{r:?}");
    }
}
