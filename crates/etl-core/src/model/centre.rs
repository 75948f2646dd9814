//! [`MovingCentre`]: a projection centre and a principal point that move with the lens
//! setting (docs/METHOD.md, "The moving centre").
//!
//! The pinhole's centre is the entrance pupil. An ETL in front of a prime lens images the
//! prime's pupil, so when its power P changes the entrance pupil moves along the axis.
//! Paraxially, a thin ETL a distance d in front of the prime's own pupil puts the image of
//! that pupil at d / (1 + d P): a shift of -d^2 P + d^3 P^2 - ..., and P is close to linear
//! in the current over an EL-10-30's range, so a quadratic in E holds the shift to well
//! below a micrometre (d = 10 mm, P <= 0.01 / mm: the cubic term is 10 nm). A decentred ETL
//! is a thin prism of deviation (decentre x P), which moves the principal point linearly
//! in P: a line in E.
//!
//! ```text
//! dz(E)  = dz1 E + dz2 E^2                (mm, the centre along the camera's +Z)   (C1)
//! T(E)   = T - dz(E) e_z                                                            (C2)
//! u0(E)  = u0 + u1 E,   v0(E) = v0 + v1 E (px)                                      (C3)
//! ```
//!
//! dz has no constant term: a constant is the pose's own T_z, so the calibration's pose is
//! the centre's at E = 0 (in the setting's unit) and dz(E) is the move from there. A
//! lateral move of the centre is not modelled: over a board's depth range it is, to first
//! order, a principal-point move (fx dx / Z), which (C3) carries.

use crate::error::{all_finite, Result};

/// Coefficients of dz(E) (E^1, E^2: Eq. C1).
pub const CENTRE_DZ_LEN: usize = 2;
/// Coefficients of the principal point's move per axis (E^1: Eq. C3).
pub const CENTRE_PP_LEN: usize = 1;

/// The move of the projection centre and of the principal point with the setting E
/// (module documentation, Eq. C1-C3). A model without one has today's fixed centre.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MovingCentre {
    /// dz1, dz2 of dz(E) = dz1 E + dz2 E^2: mm / mA, mm / mA^2 (Eq. C1).
    pub dz_mm: [f64; CENTRE_DZ_LEN],
    /// u1, v1 of u0(E) = u0 + u1 E, v0(E) = v0 + v1 E: px / mA (Eq. C3).
    pub principal_point_slope_px: [f64; 2],
}

impl MovingCentre {
    /// A centre that does not move (every coefficient zero): a moving-centre model's start.
    pub const ZERO: MovingCentre = MovingCentre { dz_mm: [0.0; CENTRE_DZ_LEN], principal_point_slope_px: [0.0; 2] };

    /// dz(E) in mm (Eq. C1).
    #[inline]
    pub fn dz_mm_at(&self, e_ma: f64) -> f64 {
        let [a, b] = self.dz_mm;
        e_ma * (a + b * e_ma)
    }

    /// d dz / dE at `e_ma`, mm / mA.
    #[inline]
    pub fn dz_slope(&self, e_ma: f64) -> f64 {
        let [a, b] = self.dz_mm;
        a + 2.0 * b * e_ma
    }

    /// The principal point's move from (u0, v0) at `e_ma`, px (Eq. C3).
    #[inline]
    pub fn principal_point_shift_px(&self, e_ma: f64) -> [f64; 2] {
        let [u1, v1] = self.principal_point_slope_px;
        [u1 * e_ma, v1 * e_ma]
    }

    /// Checks that every number is finite.
    pub fn validate(&self) -> Result<()> {
        all_finite(&self.dz_mm, "centre.dz_mm")?;
        all_finite(&self.principal_point_slope_px, "centre.principal_point_px")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_polynomials_and_their_slope() {
        let c = MovingCentre { dz_mm: [-0.01, 2e-5], principal_point_slope_px: [0.02, -0.03] };
        assert_eq!(c.dz_mm_at(0.0), 0.0);
        assert!((c.dz_mm_at(150.0) - (-1.5 + 0.45)).abs() < 1e-12);
        let h = 1e-3;
        let fd = (c.dz_mm_at(150.0 + h) - c.dz_mm_at(150.0 - h)) / (2.0 * h);
        assert!((fd - c.dz_slope(150.0)).abs() < 1e-10);
        assert_eq!(c.principal_point_shift_px(100.0), [2.0, -3.0]);
        assert!(MovingCentre { dz_mm: [f64::NAN, 0.0], ..c }.validate().is_err());
        assert!(MovingCentre::ZERO.validate().is_ok());
    }
}
