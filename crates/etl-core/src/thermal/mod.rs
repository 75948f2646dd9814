//! Temperature compensation (paper sections 2.2.1 iii, 4.1 and 5.2.2; Eq. 7-8).
//!
//! The lens's focal length drifts with its temperature; the paper compensates on the drive
//! current: E_com = E_in - E_T(T, E_in), with E_T a cubic surface in (T, E_in) fitted to
//! refocusing experiments. This module holds the surface ([`ThermalSurface`], with the
//! paper's coefficients as [`ThermalSurface::PAPER`]), its inverse (which E_in gives a
//! wanted E_com, [`ThermalSurface::e_in_for_e_com`]), the streamed least-squares fit of it
//! ([`ThermalFit`]) and the calibrated range with the extrapolation policy
//! ([`ThermalCalibration`]).
//!
//! Argument order: every function here (and in the rest of etlcal, Rust and Python) takes
//! the current before the temperature, `(e_in_ma, t_c)`; swapping two `f64` would be a
//! silent bug, so there is one order. The equations keep the paper's notation E_T(T, E_in).

pub mod fit;
pub mod inverse;
pub mod surface;

pub use fit::ThermalFit;
pub use inverse::{INVERSE_SEGMENTS, INVERSE_TOL_MA};
pub use surface::{Compensation, ThermalCalibration, ThermalSurface};

use crate::error::{finite, Error, Result};

/// Temperatures a thermal surface may be evaluated at, degC: the span of the lens's own
/// sensor and of common NTC thermistors. Beyond it the reading is not a lens temperature
/// (typically kelvin passed as degC) and a fitted cubic is meaningless.
pub const T_DOMAIN_C: [f64; 2] = [-40.0, 125.0];

/// Driver currents, mA: the output range of the Optotune Lens Driver 4 (+-292.84 mA,
/// 4096 steps each way). The inverse searches E_in within it.
pub const E_IN_DOMAIN_MA: [f64; 2] = [-292.84, 292.84];

/// Checks that (E_in, T) are finite and inside [`E_IN_DOMAIN_MA`] x [`T_DOMAIN_C`]; the
/// temperature is checked first, so a bad temperature is the error named when both are bad.
#[inline]
pub(crate) fn check_domain(e_in_ma: f64, t_c: f64) -> Result<()> {
    finite(t_c, "t_c")?;
    finite(e_in_ma, "e_in_ma")?;
    if !(T_DOMAIN_C[0]..=T_DOMAIN_C[1]).contains(&t_c) {
        return Err(Error::OutOfRange { what: "t_c", value: t_c, min: T_DOMAIN_C[0], max: T_DOMAIN_C[1] });
    }
    if !(E_IN_DOMAIN_MA[0]..=E_IN_DOMAIN_MA[1]).contains(&e_in_ma) {
        return Err(Error::OutOfRange {
            what: "e_in_ma",
            value: e_in_ma,
            min: E_IN_DOMAIN_MA[0],
            max: E_IN_DOMAIN_MA[1],
        });
    }
    Ok(())
}
