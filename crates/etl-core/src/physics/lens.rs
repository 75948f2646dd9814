//! [`LensPhysics`]: the parameters of Eq. 1-10.

use serde::{Deserialize, Serialize};

use crate::error::{all_finite, Error, Result};

/// Parameters of the physical lens model (Eq. 1-10), units in the names.
///
/// ```
/// use etl_core::physics::LensPhysics;
/// let lens = LensPhysics::paper();
/// assert!((lens.f_liq_mm(0.0).unwrap() - 120.5).abs() < 0.1);
/// assert!((lens.f_liq_mm(250.0).unwrap() - 50.5).abs() < 0.1);
/// let f = lens.f_com_mm(100.0).unwrap(); // ETL + 30 mm prime lens, 3 mm apart
/// assert!(f > 19.0 && f < 25.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LensPhysics {
    /// Young's modulus E of the membrane, Pa.
    pub young_modulus_pa: f64,
    /// Radius a of the membrane (half the aperture), mm.
    pub membrane_radius_mm: f64,
    /// Thickness h of the membrane, mm.
    pub membrane_thickness_mm: f64,
    /// Poisson's ratio v of the membrane (< 1).
    pub poisson_ratio: f64,
    /// Pre-strain eps_0 of the membrane (a fraction, > 0).
    pub prestrain: f64,
    /// Refractive index n_liq of the liquid (> n_0).
    pub n_liq: f64,
    /// Refractive index n_0 of the surroundings (1 in air).
    pub n_0: f64,
    /// Initial pressure p_0 in the lens, Pa.
    pub p0_pa: f64,
    /// k_E0 of Eq. 1, Pa.
    pub k_e0_pa: f64,
    /// k_E1 of Eq. 1, Pa / mA.
    pub k_e1_pa_per_ma: f64,
    /// k_E2 of Eq. 1, Pa / mA^2.
    pub k_e2_pa_per_ma2: f64,
    /// Focal length f_pri of the prime lens, mm (Eq. 10).
    pub f_pri_mm: f64,
    /// Distance d_lens between the optical centres of the prime lens and the ETL, mm.
    pub d_lens_mm: f64,
}

impl LensPhysics {
    /// The values of section 5.1.1: E = 3 MPa, a = 5 mm, h = 100 um, v = 0.48,
    /// n_liq = 1.4, n_0 = 1, eps_0 = 5 %, p_0 = 1200 Pa,
    /// p_a = -0.004 E^2 + 7.8 E + 2.061e-13 (Pa, E in mA), f_pri = 30 mm, d_lens = 3 mm.
    pub const fn paper() -> Self {
        LensPhysics {
            young_modulus_pa: 3.0e6,
            membrane_radius_mm: 5.0,
            membrane_thickness_mm: 0.1,
            poisson_ratio: 0.48,
            prestrain: 0.05,
            n_liq: 1.4,
            n_0: 1.0,
            p0_pa: 1200.0,
            k_e0_pa: 2.061e-13,
            k_e1_pa_per_ma: 7.8,
            k_e2_pa_per_ma2: -0.004,
            f_pri_mm: 30.0,
            d_lens_mm: 3.0,
        }
    }

    /// Checks the preconditions of the model: all numbers finite; E, a, h, eps_0 > 0;
    /// v < 1; n_liq > n_0 > 0; f_pri != 0.
    pub fn validate(&self) -> Result<()> {
        all_finite(
            &[
                self.young_modulus_pa,
                self.membrane_radius_mm,
                self.membrane_thickness_mm,
                self.poisson_ratio,
                self.prestrain,
                self.n_liq,
                self.n_0,
                self.p0_pa,
                self.k_e0_pa,
                self.k_e1_pa_per_ma,
                self.k_e2_pa_per_ma2,
                self.f_pri_mm,
                self.d_lens_mm,
            ],
            "lens physics parameters",
        )?;
        let bad = |what| Err(Error::InvalidArgument { what });
        if !(self.young_modulus_pa > 0.0) {
            return bad("young_modulus_pa must be positive");
        }
        if !(self.membrane_radius_mm > 0.0 && self.membrane_thickness_mm > 0.0) {
            return bad("membrane radius and thickness must be positive");
        }
        if !(self.prestrain > 0.0) {
            return bad("prestrain must be positive");
        }
        if !(self.poisson_ratio < 1.0) {
            return bad("poisson_ratio must be below 1");
        }
        if !(self.n_0 > 0.0 && self.n_liq > self.n_0) {
            return bad("refractive indices must satisfy n_liq > n_0 > 0");
        }
        if self.f_pri_mm == 0.0 {
            return bad("f_pri_mm must not be zero");
        }
        Ok(())
    }

    /// (1 - v) a^2 / (4 eps_0 h), mm: deflection per unit of p / E (Eq. 2).
    #[inline]
    pub(crate) fn deflection_length_mm(&self) -> f64 {
        (1.0 - self.poisson_ratio) * self.membrane_radius_mm * self.membrane_radius_mm
            / (4.0 * self.prestrain * self.membrane_thickness_mm)
    }

    /// n_0 / (n_liq - n_0): focal length per radius of curvature (Eq. 4).
    #[inline]
    pub(crate) fn lensmaker_factor(&self) -> f64 {
        self.n_0 / (self.n_liq - self.n_0)
    }
}
