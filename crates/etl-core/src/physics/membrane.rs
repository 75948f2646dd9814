//! The membrane and the liquid lens: Eq. 1-5 and 8.
//!
//! Current -> actuator pressure p_a (Eq. 1) -> peak deflection of the pre-strained
//! membrane under p_0 + p_a (Eq. 2) -> radius of curvature of the spherical cap (Eq. 3) ->
//! focal length of the plano-convex liquid lens (Eq. 4). Eq. 5 and 8 are the composition
//! (with E_in, resp. the compensated E_com, as the current).

use super::lens::LensPhysics;
use crate::error::{finite, Error, Result};

impl LensPhysics {
    /// p_a = k_E2 E^2 + k_E1 E + k_E0 (Eq. 1), Pa, at current `e_ma` (mA).
    ///
    /// Errors: invalid parameters ([`Self::validate`]); a non-finite current or result.
    pub fn applied_pressure_pa(&self, e_ma: f64) -> Result<f64> {
        self.validate()?;
        finite(e_ma, "e_ma")?;
        finite((self.k_e2_pa_per_ma2 * e_ma + self.k_e1_pa_per_ma) * e_ma + self.k_e0_pa, "applied pressure")
    }

    /// Total pressure on the membrane p_0 + p_a, Pa, at current `e_ma`.
    pub fn membrane_pressure_pa(&self, e_ma: f64) -> Result<f64> {
        finite(self.p0_pa + self.applied_pressure_pa(e_ma)?, "membrane pressure")
    }

    /// The total pressure at which the membrane becomes a hemisphere (deflection = a),
    /// 4 E eps_0 h / ((1 - v) a), Pa: the minimum focal length (text after Eq. 8). The model
    /// holds for total pressures in (0, this].
    pub fn hemisphere_pressure_pa(&self) -> Result<f64> {
        self.validate()?;
        finite(self.young_modulus_pa * self.membrane_radius_mm / self.deflection_length_mm(), "hemisphere pressure")
    }

    /// Peak deflection delta_max = (p_0 + p_a) / E * (1 - v) a^2 / (4 eps_0 h) (Eq. 2), mm,
    /// for the total pressure `membrane_pressure_pa` = p_0 + p_a.
    ///
    /// Errors: invalid parameters; a total pressure outside (0, [`Self::hemisphere_pressure_pa`]]
    /// ([`Error::OutOfRange`]): a flat or inverted membrane, or one pushed past a hemisphere,
    /// is outside the model.
    pub fn peak_deflection_at_pressure_mm(&self, membrane_pressure_pa: f64) -> Result<f64> {
        finite(membrane_pressure_pa, "membrane pressure")?;
        let p_max = self.hemisphere_pressure_pa()?;
        if !(membrane_pressure_pa > 0.0 && membrane_pressure_pa <= p_max) {
            return Err(Error::OutOfRange {
                what: "membrane pressure p_0 + p_a (Pa) at this current",
                value: membrane_pressure_pa,
                min: 0.0,
                max: p_max,
            });
        }
        finite(membrane_pressure_pa / self.young_modulus_pa * self.deflection_length_mm(), "deflection")
    }

    /// Peak deflection at current `e_ma` (Eq. 1-2), mm. Errors as
    /// [`Self::peak_deflection_at_pressure_mm`].
    pub fn peak_deflection_mm(&self, e_ma: f64) -> Result<f64> {
        self.peak_deflection_at_pressure_mm(self.membrane_pressure_pa(e_ma)?)
    }

    /// Radius of curvature of the membrane R_mem = delta / 2 + a^2 / (2 delta) (Eq. 3), mm,
    /// at total pressure `membrane_pressure_pa`.
    pub fn radius_of_curvature_at_pressure_mm(&self, membrane_pressure_pa: f64) -> Result<f64> {
        let d = self.peak_deflection_at_pressure_mm(membrane_pressure_pa)?;
        let a = self.membrane_radius_mm;
        finite(0.5 * d + a * a / (2.0 * d), "membrane radius of curvature")
    }

    /// Radius of curvature of the membrane at current `e_ma` (Eq. 1-3), mm.
    pub fn radius_of_curvature_mm(&self, e_ma: f64) -> Result<f64> {
        self.radius_of_curvature_at_pressure_mm(self.membrane_pressure_pa(e_ma)?)
    }

    /// f_liq = R_mem n_0 / (n_liq - n_0) (Eq. 4), mm, at total pressure
    /// `membrane_pressure_pa`.
    pub fn f_liq_at_pressure_mm(&self, membrane_pressure_pa: f64) -> Result<f64> {
        let r = self.radius_of_curvature_at_pressure_mm(membrane_pressure_pa)?;
        finite(r * self.lensmaker_factor(), "f_liq")
    }

    /// Focal length of the liquid lens f_liq at (compensated) current `e_ma` (Eq. 5, 8), mm.
    ///
    /// Errors: invalid parameters ([`Self::validate`]); a non-finite current
    /// ([`Error::NotFinite`]); a current whose total pressure leaves the model's range
    /// ([`Error::OutOfRange`], see [`Self::peak_deflection_at_pressure_mm`]).
    pub fn f_liq_mm(&self, e_ma: f64) -> Result<f64> {
        self.f_liq_at_pressure_mm(self.membrane_pressure_pa(e_ma)?)
    }

    /// Focal power of the liquid lens at (compensated) current `e_ma`, 1000 / f_liq, dpt
    /// (NaN outside the model's range, [`Self::f_liq_mm`]).
    pub fn power_dpt(&self, e_ma: f64) -> f64 {
        self.f_liq_mm(e_ma).map_or(f64::NAN, |f| 1000.0 / f)
    }

    /// The (compensated) current in `[lo_ma, hi_ma]` at which the liquid lens has power
    /// `dpt`, by bisection (the power rises with the current there); None when `dpt` is
    /// not reached in the interval. 60 halvings take any interval of the driver's range
    /// below the resolution of an f64.
    pub fn current_for_power_ma(&self, dpt: f64, [lo_ma, hi_ma]: [f64; 2]) -> Option<f64> {
        let (mut lo, mut hi) = (lo_ma, hi_ma);
        if !(self.power_dpt(lo) <= dpt && dpt <= self.power_dpt(hi)) {
            return None;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.power_dpt(mid) < dpt {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Section 5.1.1 / docs/METHOD.md: f_liq from 120.5 mm (0 mA) to 50.5 mm (250 mA).
    #[test]
    fn paper_values_at_0_and_250_ma() {
        let lens = LensPhysics::paper();
        let f0 = lens.f_liq_mm(0.0).unwrap();
        let f250 = lens.f_liq_mm(250.0).unwrap();
        assert!((f0 - 120.5).abs() < 0.1, "{f0}");
        assert!((f250 - 50.5).abs() < 0.1, "{f250}");
    }

    /// Each step by hand at 250 mA.
    #[test]
    fn steps_by_hand_at_250_ma() {
        let lens = LensPhysics::paper();
        // p_a = -0.004 * 62500 + 7.8 * 250 = 1700 Pa; total 2900 Pa.
        assert!((lens.applied_pressure_pa(250.0).unwrap() - 1700.0).abs() < 1e-9);
        // (1 - 0.48) 25 / (4 0.05 0.1) = 650 mm; delta = 2900 / 3e6 * 650 = 0.628333 mm.
        let d = lens.peak_deflection_mm(250.0).unwrap();
        assert!((d - 2900.0 / 3e6 * 650.0).abs() < 1e-12);
        // R = d / 2 + 25 / (2 d); f = R / 0.4.
        let r = lens.radius_of_curvature_mm(250.0).unwrap();
        assert!((r - (d / 2.0 + 12.5 / d)).abs() < 1e-12);
        assert!((lens.f_liq_mm(250.0).unwrap() - r / 0.4).abs() < 1e-12);
        // Hemisphere at 4 * 3e6 * 0.05 * 0.1 / (0.52 * 5) Pa.
        assert!((lens.hemisphere_pressure_pa().unwrap() - 60000.0 / 2.6).abs() < 1e-8);
    }

    /// Section 2.2.1: f_liq decreases monotonically with the current over the working range.
    #[test]
    fn f_liq_decreases_with_current() {
        let lens = LensPhysics::paper();
        let mut prev = f64::INFINITY;
        for i in 0..=300 {
            let f = lens.f_liq_mm(i as f64).unwrap();
            assert!(f < prev, "{i} mA");
            prev = f;
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let lens = LensPhysics::paper();
        assert_eq!(lens.f_liq_mm(f64::NAN), Err(Error::NotFinite { what: "e_ma" }));
        // p_0 + p_a <= 0 below about -151 mA; beyond the hemisphere above ~ 1e4 mA (p_a
        // peaks at 3.8 kPa, so never with the paper's Eq. 1: use a stiffer actuator).
        assert!(matches!(lens.f_liq_mm(-200.0), Err(Error::OutOfRange { .. })));
        let strong = LensPhysics { k_e1_pa_per_ma: 300.0, ..lens };
        assert!(matches!(strong.f_liq_mm(250.0), Err(Error::OutOfRange { .. })));
        let bad = LensPhysics { n_liq: 0.9, ..lens };
        assert!(matches!(bad.f_liq_mm(100.0), Err(Error::InvalidArgument { .. })));
        let nan = LensPhysics { poisson_ratio: f64::NAN, ..lens };
        assert!(matches!(nan.f_liq_mm(100.0), Err(Error::NotFinite { .. })));
    }
}
