//! Which settings a calibration can be trusted at, and what happens outside them.

use serde::{Deserialize, Serialize};

use super::setting::Extrapolated;
use crate::error::{all_finite, Error, Result};
use crate::thermal::{ThermalCalibration, ThermalSurface};

/// Temperature margin beyond the thermal calibration's range, degC. The lens's own sensor
/// reads to about +-0.5 degC and a cubic surface fitted over 10 degC bends little within a
/// degree of its end, so a reading just past the range is accepted as inside.
pub const T_MARGIN_C: f64 = 1.0;
/// Driver-current margin beyond the thermal calibration's E_in range, mA: a few driver
/// steps (0.07 mA each) and the focus search's last step.
pub const E_IN_MARGIN_MA: f64 = 5.0;
/// Compensated-current margin beyond the calibrated E_com range, mA: the cubic fx(E) of
/// the paper rig changes by about 0.05 % over 5 mA past its ends, well below its own
/// standard error there; `etlcal measure` has used this margin since its first version.
pub const E_COM_MARGIN_MA: f64 = 5.0;
/// Focal-power margin beyond a focal-power calibration's range, dpt: 5 mA of the paper's
/// lens (about 0.046 dpt/mA at mid-range) is 0.23 dpt; 0.25 dpt is also the Lens Driver's
/// stated focal-power repeatability band (+-0.1 dpt) with room for the last focus step.
pub const FOCAL_POWER_MARGIN_DPT: f64 = 0.25;

/// What to do with a setting outside the calibrated ranges (widened by their margins).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trust {
    /// Refuse it: [`Error::OutOfRange`] naming the quantity, its value and the range.
    Refuse,
    /// Return it, marked in [`super::CameraAt::flags`]. The lens's operating domain is
    /// still enforced ([`crate::thermal::T_DOMAIN_C`], [`crate::thermal::E_IN_DOMAIN_MA`]).
    Extrapolate,
}

/// A temperature compensation with the ranges it was calibrated over.
///
/// `t_range_c` and `e_in_range_ma` are `None` for a surface whose ranges are not known (a
/// calibration file written before the ranges were kept): then every temperature and
/// current is outside them, and only [`Trust::Extrapolate`] evaluates it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThermalTrust {
    /// E_T(T, E_in) (Eq. 8).
    pub surface: ThermalSurface,
    /// [min, max] temperature of the samples the surface was fitted to, degC.
    pub t_range_c: Option<[f64; 2]>,
    /// [min, max] E_in of those samples, mA.
    pub e_in_range_ma: Option<[f64; 2]>,
}

impl ThermalTrust {
    /// The surface and ranges of a thermal calibration.
    pub fn from_calibration(cal: &ThermalCalibration) -> Self {
        ThermalTrust { surface: cal.surface, t_range_c: Some(cal.t_range_c), e_in_range_ma: Some(cal.e_in_range_ma) }
    }

    /// The surface is valid and each known range is finite and ordered.
    pub fn validate(&self) -> Result<()> {
        self.surface.validate()?;
        let ranges = [
            (self.t_range_c, "t_range_c", "t_range_c must be [min, max] with min <= max"),
            (self.e_in_range_ma, "e_in_range_ma", "e_in_range_ma must be [min, max] with min <= max"),
        ];
        for (r, what, unordered) in ranges {
            if let Some(r) = r {
                all_finite(&r, what)?;
                if r[0] > r[1] {
                    return Err(Error::InvalidArgument { what: unordered });
                }
            }
        }
        Ok(())
    }

    /// Whether `temperature_c` is outside the calibrated temperature range (margin
    /// [`T_MARGIN_C`]); an error if it is and `trust` refuses. For callers that need the
    /// temperature judged before a current is known (the inverse E_com -> E_in).
    pub fn check_temperature(&self, temperature_c: f64, trust: Trust) -> Result<bool> {
        check_opt("temperature_c", temperature_c, self.t_range_c, T_MARGIN_C, trust)
    }

    /// E_T at (`e_in_ma`, `temperature_c`) and which ranges the setting is outside of
    /// (the temperature checked first). Errors: outside a range with [`Trust::Refuse`];
    /// outside the lens's operating domain; non-finite input.
    pub fn e_t_ma(&self, e_in_ma: f64, temperature_c: f64, trust: Trust) -> Result<(f64, Extrapolated)> {
        let temperature = check_opt("temperature_c", temperature_c, self.t_range_c, T_MARGIN_C, trust)?;
        let e_in = check_opt("e_in_ma", e_in_ma, self.e_in_range_ma, E_IN_MARGIN_MA, trust)?;
        let e_t = self.surface.e_t_ma(e_in_ma, temperature_c)?;
        Ok((e_t, Extrapolated { temperature, e_in, ..Extrapolated::NONE }))
    }
}

/// As [`check`], for a range that may be unknown (then every value is outside it).
fn check_opt(what: &'static str, value: f64, range: Option<[f64; 2]>, margin: f64, trust: Trust) -> Result<bool> {
    match range {
        Some(r) => check(what, value, r, margin, trust),
        None if trust == Trust::Extrapolate => Ok(true),
        None => Err(Error::InvalidArgument {
            what: "the calibration's thermal part has no calibrated ranges (an older file): re-run calibrate \
                   with --thermal, or extrapolate explicitly",
        }),
    }
}

/// Whether `value` lies outside `range` widened by `margin` (`Ok(true)` only under
/// [`Trust::Extrapolate`]). Errors: non-finite `value`; outside under [`Trust::Refuse`].
pub(super) fn check(what: &'static str, value: f64, range: [f64; 2], margin: f64, trust: Trust) -> Result<bool> {
    crate::error::finite(value, what)?;
    let (min, max) = (range[0] - margin, range[1] + margin);
    let outside = !(min..=max).contains(&value);
    if outside && trust == Trust::Refuse {
        return Err(Error::OutOfRange { what, value, min, max });
    }
    Ok(outside)
}
