//! [`ThermalSurface`]: E_T(T, E_in), the current that compensates the temperature effect
//! (Eq. 7, section 5.2.2), and [`ThermalCalibration`]: a surface with the range it was
//! calibrated over.

use serde::{Deserialize, Serialize};

use super::check_domain;
use crate::error::{all_finite, finite, Error, Result};

/// The cubic surface E_T(T, E_in) = sum c_k m_k(T, E_in) of section 5.2.2, in mA, with T in
/// degC and E_in in mA; the monomials m_k in the paper's order
/// 1, T, E, T^2, T E, E^2, T^3, T^2 E, T E^2, E^3.
///
/// The compensated current is E_com = E_in - E_T(T, E_in) (Eq. 8).
///
/// Domain: every method refuses a temperature outside [`T_DOMAIN_C`](crate::thermal::T_DOMAIN_C) or a current outside
/// [`E_IN_DOMAIN_MA`](crate::thermal::E_IN_DOMAIN_MA) with [`Error::OutOfRange`]: those are not readings of a working lens
/// (a kelvin or an ampere passed by mistake), and a cubic evaluated there is meaningless.
/// Inside that domain the surface is evaluated as is, also outside the range it was fitted
/// over; [`ThermalCalibration`] knows that range and flags such results as extrapolated.
///
/// ```
/// use etl_core::thermal::ThermalSurface;
/// let s = ThermalSurface::PAPER;
/// // At the reference temperature of the paper's calibration E_T is about 0.
/// assert!(s.e_t_ma(120.0, 27.0).unwrap().abs() < 0.5);
/// let e_com = s.e_com_ma(120.0, 33.0).unwrap();
/// let e_in = s.e_in_for_e_com(e_com, 33.0).unwrap();
/// assert!((e_in - 120.0).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThermalSurface {
    /// c_0 .. c_9 for 1, T, E, T^2, T E, E^2, T^3, T^2 E, T E^2, E^3 (mA, degC).
    pub coefficients: [f64; 10],
}

impl ThermalSurface {
    /// The paper's fitted surface (section 5.2.2; fit RMSE 0.2106 mA).
    pub const PAPER: ThermalSurface = ThermalSurface {
        coefficients: [-348.1, 36.03, -0.414, -1.266, 0.02957, 1.176e-4, 0.01514, -5.276e-4, -4.632e-6, 2.761e-8],
    };

    /// The surface at (E_in = `e`, T = `t`) without domain checks (callers check).
    #[inline]
    pub(crate) fn eval_unchecked(&self, e: f64, t: f64) -> f64 {
        let c = &self.coefficients;
        c[0] + t * (c[1] + t * (c[3] + t * c[6]))
            + e * (c[2] + e * (c[5] + e * c[9]))
            + t * e * (c[4] + t * c[7] + e * c[8])
    }

    /// dE_T / dE_in at (E_in = `e`, T = `t`) without domain checks.
    #[inline]
    pub(crate) fn d_e_t_d_e_unchecked(&self, e: f64, t: f64) -> f64 {
        let c = &self.coefficients;
        c[2] + e * (2.0 * c[5] + 3.0 * c[9] * e) + t * (c[4] + t * c[7] + 2.0 * c[8] * e)
    }

    /// Checks that every coefficient is finite.
    pub fn validate(&self) -> Result<()> {
        all_finite(&self.coefficients, "thermal coefficients")
    }

    /// E_T(T, E_in) in mA (Eq. 7) at driver current `e_in_ma` (mA) and temperature `t_c`
    /// (degC).
    ///
    /// Errors: a non-finite input or result ([`Error::NotFinite`]); an input outside the
    /// domain [`T_DOMAIN_C`](crate::thermal::T_DOMAIN_C) x [`E_IN_DOMAIN_MA`](crate::thermal::E_IN_DOMAIN_MA) ([`Error::OutOfRange`]).
    #[inline]
    pub fn e_t_ma(&self, e_in_ma: f64, t_c: f64) -> Result<f64> {
        check_domain(e_in_ma, t_c)?;
        finite(self.eval_unchecked(e_in_ma, t_c), "E_T (check the thermal coefficients)")
    }

    /// E_com = E_in - E_T(T, E_in) in mA (Eq. 8) at driver current `e_in_ma` (mA) and
    /// temperature `t_c` (degC): the current the camera model is indexed by.
    ///
    /// Errors as [`Self::e_t_ma`].
    #[inline]
    pub fn e_com_ma(&self, e_in_ma: f64, t_c: f64) -> Result<f64> {
        let e_t = self.e_t_ma(e_in_ma, t_c)?;
        finite(e_in_ma - e_t, "E_com")
    }
}

/// The result of a compensation through a [`ThermalCalibration`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Compensation {
    /// Driver current, mA.
    pub e_in_ma: f64,
    /// E_T(T, E_in), mA.
    pub e_t_ma: f64,
    /// E_com = E_in - E_T, mA.
    pub e_com_ma: f64,
    /// The temperature or E_in lies outside the range the surface was fitted over: the
    /// value is the cubic's extrapolation, and only as good as that.
    pub extrapolated: bool,
}

/// A fitted [`ThermalSurface`] with the temperatures and currents it was fitted over (the
/// content of an `etlcal.thermal/1` file).
///
/// Out-of-range policy: outside the calibrated ranges but inside the lens's operating
/// domain ([`T_DOMAIN_C`](crate::thermal::T_DOMAIN_C), [`E_IN_DOMAIN_MA`](crate::thermal::E_IN_DOMAIN_MA)) a result is returned with
/// [`Compensation::extrapolated`] set, so a controller keeps running and can warn or log;
/// outside the operating domain the methods return [`Error::OutOfRange`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThermalCalibration {
    /// The surface.
    pub surface: ThermalSurface,
    /// [min, max] temperature of the fitted samples, degC.
    pub t_range_c: [f64; 2],
    /// [min, max] E_in of the fitted samples, mA.
    pub e_in_range_ma: [f64; 2],
}

impl ThermalCalibration {
    /// The paper's surface over the paper's procedure (section 4.1, Fig. 4): 27..37 degC,
    /// 40..240 mA.
    pub const PAPER: ThermalCalibration =
        ThermalCalibration { surface: ThermalSurface::PAPER, t_range_c: [27.0, 37.0], e_in_range_ma: [40.0, 240.0] };

    /// Checks the numbers: all finite, each range ordered (min <= max).
    pub fn validate(&self) -> Result<()> {
        self.surface.validate()?;
        all_finite(&self.t_range_c, "t_range_c")?;
        all_finite(&self.e_in_range_ma, "e_in_range_ma")?;
        if self.t_range_c[0] > self.t_range_c[1] {
            return Err(Error::InvalidArgument { what: "t_range_c must be [min, max] with min <= max" });
        }
        if self.e_in_range_ma[0] > self.e_in_range_ma[1] {
            return Err(Error::InvalidArgument { what: "e_in_range_ma must be [min, max] with min <= max" });
        }
        Ok(())
    }

    /// Whether (`e_in_ma`, `t_c`) lies inside the calibrated ranges (false for NaN).
    pub fn contains(&self, e_in_ma: f64, t_c: f64) -> bool {
        t_c >= self.t_range_c[0]
            && t_c <= self.t_range_c[1]
            && e_in_ma >= self.e_in_range_ma[0]
            && e_in_ma <= self.e_in_range_ma[1]
    }

    /// E_T and E_com at driver current `e_in_ma` (mA) and temperature `t_c` (degC), flagged
    /// when outside the calibrated ranges.
    ///
    /// Errors as [`ThermalSurface::e_t_ma`], and [`Self::validate`]'s.
    pub fn compensate(&self, e_in_ma: f64, t_c: f64) -> Result<Compensation> {
        self.validate()?;
        let e_t_ma = self.surface.e_t_ma(e_in_ma, t_c)?;
        let e_com_ma = finite(e_in_ma - e_t_ma, "E_com")?;
        Ok(Compensation { e_in_ma, e_t_ma, e_com_ma, extrapolated: !self.contains(e_in_ma, t_c) })
    }

    /// The driver current that gives `e_com_ma` at `t_c` ([`ThermalSurface::e_in_for_e_com`]),
    /// flagged when that current or the temperature is outside the calibrated ranges.
    pub fn e_in_for_e_com(&self, e_com_ma: f64, t_c: f64) -> Result<Compensation> {
        self.validate()?;
        let e_in_ma = self.surface.e_in_for_e_com(e_com_ma, t_c)?;
        let e_t_ma = self.surface.e_t_ma(e_in_ma, t_c)?;
        Ok(Compensation { e_in_ma, e_t_ma, e_com_ma, extrapolated: !self.contains(e_in_ma, t_c) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Section 5.2.2: E_T is about 0 at 27 degC (the reference temperature) over the range.
    #[test]
    fn paper_surface_is_near_zero_at_27_c() {
        let s = ThermalSurface::PAPER;
        let mut worst = 0.0f64;
        for i in 0..=240 {
            let e = i as f64;
            worst = worst.max(s.e_t_ma(e, 27.0).unwrap().abs());
        }
        assert!(worst < 0.5, "max |E_T(27 C, E)| = {worst} mA");
        // And it grows with temperature: a few mA at 37 degC.
        let hot = s.e_t_ma(120.0, 37.0).unwrap();
        assert!(hot.abs() > 1.0, "{hot}");
    }

    #[test]
    fn e_t_matches_the_printed_formula() {
        let (t, e) = (31.5, 187.0);
        let expect =
            -348.1 + 36.03 * t - 0.414 * e - 1.266 * t * t + 0.02957 * t * e + 1.176e-4 * e * e + 0.01514 * t * t * t
                - 5.276e-4 * t * t * e
                - 4.632e-6 * t * e * e
                + 2.761e-8 * e * e * e;
        let s = ThermalSurface::PAPER;
        assert!((s.e_t_ma(e, t).unwrap() - expect).abs() < 1e-11);
        assert!((s.e_com_ma(e, t).unwrap() - (e - expect)).abs() < 1e-11);
        let h = 1e-4;
        let fd = (s.eval_unchecked(e + h, t) - s.eval_unchecked(e - h, t)) / (2.0 * h);
        assert!((fd - s.d_e_t_d_e_unchecked(e, t)).abs() < 1e-8);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let s = ThermalSurface::PAPER;
        assert_eq!(s.e_t_ma(100.0, f64::NAN), Err(Error::NotFinite { what: "t_c" }));
        assert_eq!(s.e_com_ma(f64::INFINITY, 30.0), Err(Error::NotFinite { what: "e_in_ma" }));
        // 300 K passed as degC, 0.1 A passed as 100 000 uA...
        assert!(matches!(s.e_t_ma(100.0, 300.0), Err(Error::OutOfRange { what: "t_c", .. })));
        assert!(matches!(s.e_t_ma(1e5, 30.0), Err(Error::OutOfRange { what: "e_in_ma", .. })));
        let bad = ThermalSurface { coefficients: [f64::NAN; 10] };
        assert!(matches!(bad.e_t_ma(100.0, 30.0), Err(Error::NotFinite { .. })));
    }

    /// The policy: outside the calibrated range, a flagged result; outside the domain, an
    /// error.
    #[test]
    fn extrapolation_is_flagged() {
        let cal = ThermalCalibration::PAPER;
        let inside = cal.compensate(100.0, 30.0).unwrap();
        assert!(!inside.extrapolated);
        assert!((inside.e_com_ma - ThermalSurface::PAPER.e_com_ma(100.0, 30.0).unwrap()).abs() == 0.0);
        assert!(cal.compensate(100.0, 45.0).unwrap().extrapolated);
        assert!(cal.compensate(260.0, 30.0).unwrap().extrapolated);
        assert!(cal.compensate(10.0, 30.0).unwrap().extrapolated);
        assert!(matches!(cal.compensate(400.0, 30.0), Err(Error::OutOfRange { .. })));
        let back = cal.e_in_for_e_com(inside.e_com_ma, 30.0).unwrap();
        assert!((back.e_in_ma - 100.0).abs() < 1e-9 && !back.extrapolated);
        let swapped = ThermalCalibration { t_range_c: [37.0, 27.0], ..cal };
        assert!(matches!(swapped.compensate(100.0, 30.0), Err(Error::InvalidArgument { .. })));
        assert!(!cal.contains(100.0, f64::NAN));
    }
}
