//! The effect of gravity: the focal-length error of a vertical lens (Eq. 6) and the
//! gravity coefficient of a horizontal one (Eq. 9).

use super::lens::LensPhysics;
use crate::error::{finite, Error, Result};

/// Standard gravity, m / s^2.
pub const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

impl LensPhysics {
    /// error_gravity = f_liq(p_a + dp) - f_liq(p_a) (Eq. 6), mm, at current `e_ma` for the
    /// pressure change `dp_gravity_pa` (Pa) that the liquid's weight adds with the optical
    /// axis vertical.
    ///
    /// Evaluated in the closed form
    /// n_0 / (n_liq - n_0) dp [(1 - v) a^2 / (8 E eps_0 h) - 2 E eps_0 h / ((1 - v) p (p + dp))]
    /// with p = p_0 + p_a, free of the cancellation of the difference. The paper's print
    /// of Eq. 6 lacks the 1 / (1 - v) of the second term (its Eq. 5 has it); this is the
    /// difference of Eq. 5, which the paper defines Eq. 6 as.
    ///
    /// Errors: as [`Self::f_liq_mm`], for both p and p + dp.
    pub fn gravity_error_mm(&self, e_ma: f64, dp_gravity_pa: f64) -> Result<f64> {
        finite(dp_gravity_pa, "dp_gravity_pa")?;
        let p = self.membrane_pressure_pa(e_ma)?;
        // Both pressures must be inside the model's range.
        self.peak_deflection_at_pressure_mm(p)?;
        self.peak_deflection_at_pressure_mm(p + dp_gravity_pa)?;
        let e = self.young_modulus_pa;
        let eh = self.prestrain * self.membrane_thickness_mm;
        let nu1 = 1.0 - self.poisson_ratio;
        let a2 = self.membrane_radius_mm * self.membrane_radius_mm;
        let bracket = nu1 * a2 / (8.0 * e * eh) - 2.0 * e * eh / (nu1 * p * (p + dp_gravity_pa));
        finite(self.lensmaker_factor() * dp_gravity_pa * bracket, "gravity error")
    }

    /// k_gravity = (p_0 + p_a) / (2 (rho_liq - rho_sur) g a) (Eq. 9), dimensionless, at
    /// current `e_ma` for liquid and surrounding densities in kg / m^3 (a taken in m).
    /// Above ~30 gravity moves the optical axis by under 0.02 % (section 2.2.2 ii).
    ///
    /// Errors: non-finite input; equal densities ([`Error::Degenerate`]: no buoyancy
    /// difference, the coefficient is infinite); errors of [`Self::membrane_pressure_pa`].
    pub fn gravity_coefficient(&self, e_ma: f64, rho_liq_kg_m3: f64, rho_sur_kg_m3: f64) -> Result<f64> {
        finite(rho_liq_kg_m3, "rho_liq_kg_m3")?;
        finite(rho_sur_kg_m3, "rho_sur_kg_m3")?;
        let p = self.membrane_pressure_pa(e_ma)?;
        let denom = 2.0 * (rho_liq_kg_m3 - rho_sur_kg_m3) * STANDARD_GRAVITY_M_S2 * self.membrane_radius_mm * 1e-3;
        if denom == 0.0 {
            return Err(Error::Degenerate { what: "liquid and surrounding densities are equal" });
        }
        finite(p / denom, "gravity coefficient")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_equals_the_difference_of_eq_5() {
        let lens = LensPhysics::paper();
        for &(e, dp) in &[(0.0, 20.0), (100.0, 50.0), (250.0, -30.0)] {
            let p = lens.membrane_pressure_pa(e).unwrap();
            let diff = lens.f_liq_at_pressure_mm(p + dp).unwrap() - lens.f_liq_at_pressure_mm(p).unwrap();
            let g = lens.gravity_error_mm(e, dp).unwrap();
            assert!((g - diff).abs() < 1e-9 * diff.abs().max(1e-9), "{e} {dp}: {g} vs {diff}");
        }
    }

    /// Section 2.2.1 ii: the relative error is largest at p_a = 0. A 5 mm column of oil
    /// (~900 kg/m^3) gives dp ~ 44 Pa, a few percent of p_0; the error shrinks with current.
    #[test]
    fn gravity_error_shrinks_with_current() {
        let lens = LensPhysics::paper();
        let dp = 900.0 * STANDARD_GRAVITY_M_S2 * 5e-3;
        let rel0 = (lens.gravity_error_mm(0.0, dp).unwrap() / lens.f_liq_mm(0.0).unwrap()).abs();
        let rel200 = (lens.gravity_error_mm(200.0, dp).unwrap() / lens.f_liq_mm(200.0).unwrap()).abs();
        assert!(rel200 < rel0 && rel0 > 0.0, "{rel0} {rel200}");
        assert!(matches!(lens.gravity_error_mm(0.0, f64::NAN), Err(Error::NotFinite { .. })));
        assert!(matches!(lens.gravity_error_mm(0.0, -5000.0), Err(Error::OutOfRange { .. })));
    }

    #[test]
    fn gravity_coefficient_by_hand() {
        let lens = LensPhysics::paper();
        // At 0 mA: 1200 / (2 * (1000 - 1.2) * 9.80665 * 0.005).
        let k = lens.gravity_coefficient(0.0, 1000.0, 1.2).unwrap();
        assert!((k - 1200.0 / (2.0 * 998.8 * STANDARD_GRAVITY_M_S2 * 0.005)).abs() < 1e-9);
        assert!(matches!(lens.gravity_coefficient(0.0, 1.0, 1.0), Err(Error::Degenerate { .. })));
        assert!(matches!(lens.gravity_coefficient(0.0, f64::INFINITY, 1.0), Err(Error::NotFinite { .. })));
    }
}
