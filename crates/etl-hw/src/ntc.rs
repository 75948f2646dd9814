//! An external NTC thermistor read through an ADC (facts sheet section 8): the beta and
//! Steinhart-Hart equations and the voltage-divider formula. Not the lens's own sensor
//! (that one is digital, read with `TCA`): this is for a thermistor glued to the lens
//! or its mount.

use etl_core::error::finite;
use etl_core::Error;

/// 0 degC in kelvin.
pub const ZERO_C_IN_K: f64 = 273.15;

/// How resistance maps to temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NtcModel {
    /// R(T) = R0 exp[B (1/T - 1/T0)] (T in kelvin).
    Beta {
        /// Resistance at `t0_c`, ohm.
        r0_ohm: f64,
        /// Reference temperature, degC (usually 25).
        t0_c: f64,
        /// B, kelvin.
        beta_k: f64,
    },
    /// 1/T = A + B ln R + C (ln R)^3 (T in kelvin, R in ohm).
    SteinhartHart {
        /// A.
        a: f64,
        /// B.
        b: f64,
        /// C.
        c: f64,
    },
}

impl NtcModel {
    /// A common 10 kOhm, B = 3950 K part.
    pub const TEN_K_3950: NtcModel = NtcModel::Beta { r0_ohm: 10_000.0, t0_c: 25.0, beta_k: 3950.0 };

    /// The Steinhart-Hart coefficients through three (degC, ohm) calibration points.
    ///
    /// Errors: non-finite or non-positive resistances, temperatures at or below absolute
    /// zero, or points that do not determine the coefficients (repeated resistances):
    /// [`Error::NotFinite`] / [`Error::InvalidArgument`] / [`Error::Degenerate`].
    pub fn steinhart_hart_from_points(points: [(f64, f64); 3]) -> Result<NtcModel, Error> {
        let mut l = [0.0; 3];
        let mut y = [0.0; 3];
        for (i, &(t_c, r)) in points.iter().enumerate() {
            finite(t_c, "calibration temperature")?;
            finite(r, "calibration resistance")?;
            if r <= 0.0 || t_c <= -ZERO_C_IN_K {
                return Err(Error::InvalidArgument { what: "calibration points need R > 0 and T > -273.15 degC" });
            }
            l[i] = r.ln();
            y[i] = 1.0 / (t_c + ZERO_C_IN_K);
        }
        // KLIPPER's closed form (thermistor.py setup_coefficients).
        let (d12, d13) = (l[0] - l[1], l[0] - l[2]);
        if d12 == 0.0 || d13 == 0.0 || l[1] == l[2] {
            return Err(Error::Degenerate { what: "Steinhart-Hart needs three distinct resistances" });
        }
        let g2 = (y[1] - y[0]) / (l[1] - l[0]);
        let g3 = (y[2] - y[0]) / (l[2] - l[0]);
        let c = (g3 - g2) / (l[2] - l[1]) / (l[0] + l[1] + l[2]);
        let b = g2 - c * (l[0] * l[0] + l[0] * l[1] + l[1] * l[1]);
        let a = y[0] - (b + l[0] * l[0] * c) * l[0];
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            return Err(Error::Degenerate { what: "Steinhart-Hart points give non-finite coefficients" });
        }
        Ok(NtcModel::SteinhartHart { a, b, c })
    }

    /// Temperature, degC, at resistance `r_ohm` (> 0).
    pub fn temperature_c(&self, r_ohm: f64) -> Result<f64, Error> {
        finite(r_ohm, "thermistor resistance")?;
        positive_ohm(r_ohm, "thermistor resistance (ohm)")?;
        let inv_t = match *self {
            NtcModel::Beta { r0_ohm, t0_c, beta_k } => 1.0 / (t0_c + ZERO_C_IN_K) + (r_ohm / r0_ohm).ln() / beta_k,
            NtcModel::SteinhartHart { a, b, c } => {
                let l = r_ohm.ln();
                a + b * l + c * l * l * l
            }
        };
        if !(inv_t > 0.0) {
            return Err(Error::Degenerate { what: "thermistor coefficients give a temperature at or below 0 K" });
        }
        finite(1.0 / inv_t - ZERO_C_IN_K, "thermistor temperature")
    }

    /// Resistance, ohm, at temperature `t_c` (the inverse; for tests and simulation).
    pub fn resistance_ohm(&self, t_c: f64) -> Result<f64, Error> {
        finite(t_c, "temperature")?;
        let inv_t = 1.0 / (t_c + ZERO_C_IN_K);
        let r = match *self {
            NtcModel::Beta { r0_ohm, t0_c, beta_k } => r0_ohm * (beta_k * (inv_t - 1.0 / (t0_c + ZERO_C_IN_K))).exp(),
            NtcModel::SteinhartHart { a, b, c } => {
                // c L^3 + b L + (a - 1/T) = 0 (Cardano; one real root for b, c > 0).
                if c == 0.0 {
                    ((inv_t - a) / b).exp()
                } else {
                    let p = b / c;
                    let q = (a - inv_t) / c;
                    let disc = (q * q / 4.0 + p * p * p / 27.0).sqrt();
                    ((-q / 2.0 + disc).cbrt() + (-q / 2.0 - disc).cbrt()).exp()
                }
            }
        };
        finite(r, "thermistor resistance")
    }
}

/// The divider: NTC to ground, pull-up `pullup_ohm` to the ADC reference, optional series
/// resistance in the NTC leg; R = Rp x / (1 - x) - R_series with x = adc / full scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Divider {
    /// Pull-up resistor, ohm.
    pub pullup_ohm: f64,
    /// Series (inline) resistance in the NTC leg, ohm.
    pub series_ohm: f64,
    /// ADC full-scale count (1023 or 1024 for 10 bits: the ADC's own convention).
    pub adc_full_scale: f64,
}

/// `Ok(r_ohm)` unless it is zero or negative ([`Error::OutOfRange`] naming `what`): a
/// thermistor's resistance, given or measured, is positive.
fn positive_ohm(r_ohm: f64, what: &'static str) -> Result<f64, Error> {
    if r_ohm <= 0.0 {
        return Err(Error::OutOfRange { what, value: r_ohm, min: 0.0, max: f64::INFINITY });
    }
    Ok(r_ohm)
}

impl Divider {
    /// The NTC resistance for an ADC reading; the normalised reading is clamped to
    /// [1e-5, 0.99999] as Klipper does, so rails give a finite (extreme) value.
    pub fn resistance_ohm(&self, adc: f64) -> Result<f64, Error> {
        finite(adc, "adc reading")?;
        if !(self.pullup_ohm > 0.0 && self.adc_full_scale > 0.0 && self.series_ohm >= 0.0) {
            return Err(Error::InvalidArgument { what: "divider needs pullup > 0, full scale > 0, series >= 0" });
        }
        let x = (adc / self.adc_full_scale).clamp(1e-5, 0.99999);
        let r = self.pullup_ohm * x / (1.0 - x) - self.series_ohm;
        positive_ohm(r, "thermistor resistance from the ADC (ohm)")
    }

    /// The ADC reading (unrounded) for an NTC resistance.
    pub fn adc(&self, r_ohm: f64) -> f64 {
        let r = r_ohm + self.series_ohm;
        self.adc_full_scale * r / (r + self.pullup_ohm)
    }
}

/// A thermistor on a divider.
///
/// ```
/// use etl_hw::ntc::{Divider, Ntc, NtcModel};
/// let ntc = Ntc { model: NtcModel::TEN_K_3950, divider: Divider { pullup_ohm: 10_000.0, series_ohm: 0.0, adc_full_scale: 1023.0 } };
/// assert!((ntc.temperature_c(511.5).unwrap() - 25.0).abs() < 1e-9); // R = pull-up
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ntc {
    /// The thermistor.
    pub model: NtcModel,
    /// The divider it sits in.
    pub divider: Divider,
}

impl Ntc {
    /// Temperature, degC, for an ADC reading.
    pub fn temperature_c(&self, adc: f64) -> Result<f64, Error> {
        self.model.temperature_c(self.divider.resistance_ohm(adc)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEN_BIT: Divider = Divider { pullup_ohm: 10_000.0, series_ohm: 0.0, adc_full_scale: 1023.0 };

    /// Facts sheet section 8 worked numbers (10 kOhm, B = 3950).
    #[test]
    fn beta_matches_the_worked_table() {
        let m = NtcModel::TEN_K_3950;
        for (t, r) in [(0.0, 33_621.0), (25.0, 10_000.0), (37.0, 5_989.0), (50.0, 3_588.0)] {
            assert!((m.resistance_ohm(t).unwrap() - r).abs() < 1.0, "{t}");
            assert!((m.temperature_c(r).unwrap() - t).abs() < 0.01, "{r}");
        }
    }

    /// 10-bit ADC with a 10 kOhm pull-up reads 569 / 456 / 354 at 20 / 30 / 40 degC and
    /// the quantisation error is < 0.05 degC over 20..40 degC.
    #[test]
    fn divider_adc_readings() {
        let ntc = Ntc { model: NtcModel::TEN_K_3950, divider: TEN_BIT };
        for (t, adc) in [(20.0, 569.0), (30.0, 456.0), (40.0, 354.0)] {
            let r = NtcModel::TEN_K_3950.resistance_ohm(t).unwrap();
            assert_eq!(TEN_BIT.adc(r).round(), adc);
            assert!((ntc.temperature_c(adc).unwrap() - t).abs() < 0.05, "{t}");
        }
        // Series resistance is subtracted.
        let d = Divider { series_ohm: 100.0, ..TEN_BIT };
        let r = d.resistance_ohm(d.adc(5_000.0)).unwrap();
        assert!((r - 5_000.0).abs() < 1e-9);
    }

    /// The generic 10 kOhm Steinhart-Hart set gives 25 degC at 10 kOhm and disagrees with
    /// B = 3950 by ~0.6 degC at 0 degC (facts sheet: 0.3-0.6 degC).
    #[test]
    fn generic_steinhart_hart_set() {
        let sh = NtcModel::SteinhartHart { a: 1.129148e-3, b: 2.34125e-4, c: 8.76741e-8 };
        assert!((sh.temperature_c(10_000.0).unwrap() - 25.0).abs() < 0.01);
        assert!((sh.temperature_c(33_621.0).unwrap() + 0.573).abs() < 0.01);
        for t in [-10.0, 0.0, 25.0, 60.0] {
            let r = sh.resistance_ohm(t).unwrap();
            assert!((sh.temperature_c(r).unwrap() - t).abs() < 1e-9, "{t}");
        }
    }

    /// Steinhart-Hart through three points of the beta curve reproduces the points and
    /// stays within 0.05 degC of the curve between them.
    #[test]
    fn steinhart_hart_from_three_points() {
        let b = NtcModel::TEN_K_3950;
        let pts = [0.0, 25.0, 50.0].map(|t| (t, b.resistance_ohm(t).unwrap()));
        let sh = NtcModel::steinhart_hart_from_points(pts).unwrap();
        for (t, r) in pts {
            assert!((sh.temperature_c(r).unwrap() - t).abs() < 1e-9);
        }
        for t in [10.0, 37.0, 45.0] {
            assert!((sh.temperature_c(b.resistance_ohm(t).unwrap()).unwrap() - t).abs() < 0.05, "{t}");
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let m = NtcModel::TEN_K_3950;
        assert!(matches!(m.temperature_c(0.0), Err(Error::OutOfRange { .. })));
        assert!(matches!(m.temperature_c(-5.0), Err(Error::OutOfRange { .. })));
        assert!(matches!(m.temperature_c(f64::NAN), Err(Error::NotFinite { .. })));
        assert!(matches!(
            NtcModel::steinhart_hart_from_points([(0.0, 1e4), (10.0, 1e4), (20.0, 5e3)]),
            Err(Error::Degenerate { .. })
        ));
        assert!(matches!(
            NtcModel::steinhart_hart_from_points([(0.0, -1.0), (10.0, 1e4), (20.0, 5e3)]),
            Err(Error::InvalidArgument { .. })
        ));
        assert!(matches!(
            NtcModel::steinhart_hart_from_points([(f64::NAN, 1.0), (10.0, 1e4), (20.0, 5e3)]),
            Err(Error::NotFinite { .. })
        ));
        let bad = Divider { pullup_ohm: 0.0, ..TEN_BIT };
        assert!(matches!(bad.resistance_ohm(500.0), Err(Error::InvalidArgument { .. })));
        assert!(matches!(TEN_BIT.resistance_ohm(f64::NAN), Err(Error::NotFinite { .. })));
        // Rails are clamped to a finite extreme, not infinite.
        assert!(TEN_BIT.resistance_ohm(1023.0).unwrap().is_finite());
        let series = Divider { series_ohm: 1e6, ..TEN_BIT };
        assert!(matches!(series.resistance_ohm(1.0), Err(Error::OutOfRange { .. })));
        // Coefficients that give T <= 0 K.
        let absurd = NtcModel::SteinhartHart { a: -1.0, b: 0.0, c: 0.0 };
        assert!(matches!(absurd.temperature_c(1e4), Err(Error::Degenerate { .. })));
    }
}
