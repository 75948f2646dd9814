//! The one error type of etl-core.
//!
//! Every variant names the unmet precondition, so that a caller (and the user reading the
//! message) knows what to change. `what` strings are static: etl-core never allocates.

use core::fmt;

/// Result with the core's [`Error`].
pub type Result<T> = core::result::Result<T, Error>;

/// Why an etl-core operation refused its input or could not finish.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// An input was NaN or infinite.
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// An input lies outside the range where it is meaningful or calibrated.
    OutOfRange {
        /// Which input.
        what: &'static str,
        /// The value given.
        value: f64,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
    /// Fewer samples, points, views or distinct values than the method needs.
    TooFew {
        /// What is counted (e.g. "distinct currents").
        what: &'static str,
        /// How many the method needs at least.
        needed: usize,
        /// How many were given.
        got: usize,
    },
    /// The data do not determine the unknowns (e.g. all points on one plane where the
    /// method needs depth, all samples at one temperature, a singular system).
    Degenerate {
        /// Which condition failed.
        what: &'static str,
    },
    /// A point lies at or behind the camera's centre of projection (Z_C <= 0).
    BehindCamera,
    /// An iterative method did not reach its tolerance.
    NotConverged {
        /// Which method.
        what: &'static str,
        /// Iterations spent.
        iterations: usize,
    },
    /// Caller-provided storage is smaller than the `*_scratch` function asked for.
    BufferTooSmall {
        /// Which buffer.
        what: &'static str,
        /// Length needed.
        needed: usize,
        /// Length given.
        got: usize,
    },
    /// An argument is invalid for a reason not covered above.
    InvalidArgument {
        /// What is wrong with it.
        what: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NotFinite { what } => write!(f, "{what} is NaN or infinite; pass finite numbers"),
            Error::OutOfRange { what, value, min, max } => {
                write!(f, "{what} = {} is outside [{}, {}]", Compact(value), Compact(min), Compact(max))
            }
            Error::TooFew { what, needed, got } => {
                write!(f, "too few {what}: the method needs at least {needed}, got {got}")
            }
            Error::Degenerate { what } => write!(f, "degenerate input: {what}"),
            Error::BehindCamera => {
                write!(f, "point is at or behind the camera (Z_C <= 0); check the pose and units (mm)")
            }
            Error::NotConverged { what, iterations } => {
                write!(f, "{what} did not converge in {iterations} iterations")
            }
            Error::BufferTooSmall { what, needed, got } => {
                write!(f, "buffer {what} too small: needs {needed} elements, got {got} (see its *_scratch function)")
            }
            Error::InvalidArgument { what } => write!(f, "invalid argument: {what}"),
        }
    }
}

impl core::error::Error for Error {}

/// A number as messages print it, for people: scientific notation outside [1e-4, 1e5)
/// (so that 1e308 prints as `1e308`, not 309 digits; `1e5`, not `100000`), else Rust's
/// shortest round-trip digits (at most 17 significant), so that -292.84 reads as typed.
/// Without allocation, for `write!` in `no_std` code.
///
/// ```
/// use etl_core::Compact;
/// assert_eq!(format!("{}", Compact(1e308)), "1e308");
/// assert_eq!(format!("{}", Compact(-292.84)), "-292.84");
/// assert_eq!(format!("{}", Compact(100000.0)), "1e5");
/// assert_eq!(format!("{}", Compact(1.8446744073709552e19)), "1.8446744073709552e19");
/// assert_eq!(format!("{}", Compact(f64::NAN)), "NaN");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compact(pub f64);

impl fmt::Display for Compact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x != 0.0 && x.is_finite() && !(1e-4..1e5).contains(&x.abs()) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

/// `Ok(x)` if `x` is finite, else [`Error::NotFinite`] naming it.
#[inline]
pub fn finite(x: f64, what: &'static str) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::NotFinite { what })
    }
}

/// `Ok(n)` if the count or degree `n` is in `min..=max`, else [`Error::OutOfRange`]
/// naming it: the one check of a size a caller chooses (a polynomial's degree, an image
/// side), so that every such refusal reads the same.
#[inline]
pub fn count_in_range(n: usize, min: usize, max: usize, what: &'static str) -> Result<usize> {
    if (min..=max).contains(&n) {
        Ok(n)
    } else {
        Err(Error::OutOfRange { what, value: n as f64, min: min as f64, max: max as f64 })
    }
}

/// Checks that every element of `xs` is finite.
#[inline]
pub fn all_finite(xs: &[f64], what: &'static str) -> Result<()> {
    if xs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::NotFinite { what })
    }
}
