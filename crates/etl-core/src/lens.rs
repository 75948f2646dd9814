//! The [`Lens`] trait: what the calibration and compensation code needs from a tunable
//! lens and its driver (section 2.2.1 iii, 4.1): command a current, read the lens
//! temperature, read back the current.
//!
//! Implemented by `etl_hw::client::LensClient` (a real Optotune Lens Driver 4) and by
//! `etl_hw::virtual_lens::VirtualLens` (the simulated device). The error type is
//! associated, so that a driver keeps its own rich errors (timeouts, CRC, unplugged port);
//! its [`LensError::kind`] tells generic code (the `hold` loop, the temperature procedure,
//! the Python mapping) what happened without downcasting, as embedded-hal's
//! `Error::kind()` does.

/// What kind of failure a lens call met.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum LensErrorKind {
    /// The driver did not answer within the timeout.
    Timeout,
    /// The driver answered with an error: it refused the command (or has no such sensor).
    Refused,
    /// The link is gone: the port cannot be opened or its I/O failed (unplugged device).
    LinkLost,
    /// The driver's reply could not be understood (CRC failure, NACK, malformed reply).
    Protocol,
    /// The caller's value was refused before anything was sent (e.g. a NaN current).
    InvalidInput,
    /// Any other failure (e.g. of a simulated device).
    Other,
}

/// The error of a [`Lens`]: displayable, and of a [`LensErrorKind`].
pub trait LensError: core::fmt::Debug + core::fmt::Display {
    /// What kind of failure this is.
    fn kind(&self) -> LensErrorKind;
}

/// The core's own errors reach a lens only as refused input (a NaN or out-of-range value).
impl LensError for crate::Error {
    fn kind(&self) -> LensErrorKind {
        LensErrorKind::InvalidInput
    }
}

/// A tunable lens with its driver.
///
/// Contract of implementations: no call commands a current outside the driver's limits,
/// whatever `e_in_ma` is (out-of-range values are clamped, NaN is refused), and the
/// returned value is the current actually commanded after clamping and the driver's
/// quantisation.
///
/// ```
/// use etl_core::lens::Lens;
/// /// A lens that only remembers its current (a test double).
/// struct Fixed { e_ma: f64 }
/// impl Lens for Fixed {
///     type Error = etl_core::Error;
///     fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64, Self::Error> {
///         self.e_ma = etl_core::error::finite(e_in_ma, "e_in_ma")?.clamp(-290.0, 290.0);
///         Ok(self.e_ma)
///     }
///     fn current_ma(&mut self) -> Result<f64, Self::Error> { Ok(self.e_ma) }
///     fn temperature_c(&mut self) -> Result<f64, Self::Error> { Ok(27.0) }
/// }
/// let mut lens = Fixed { e_ma: 0.0 };
/// assert_eq!(lens.set_current_ma(1e9).unwrap(), 290.0);
/// assert!(lens.set_current_ma(f64::NAN).is_err());
/// ```
pub trait Lens {
    /// The driver's error type.
    type Error: LensError;

    /// Commands the driver current E_in, mA; returns the current actually commanded
    /// (clamped to the driver's limits and quantised). Errors on NaN/infinite input and on
    /// communication failures.
    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64, Self::Error>;

    /// The driver current the lens is at, mA.
    fn current_ma(&mut self) -> Result<f64, Self::Error>;

    /// The lens temperature, degC.
    fn temperature_c(&mut self) -> Result<f64, Self::Error>;
}

impl<L: Lens + ?Sized> Lens for &mut L {
    type Error = L::Error;
    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64, Self::Error> {
        (**self).set_current_ma(e_in_ma)
    }
    fn current_ma(&mut self) -> Result<f64, Self::Error> {
        (**self).current_ma()
    }
    fn temperature_c(&mut self) -> Result<f64, Self::Error> {
        (**self).temperature_c()
    }
}
