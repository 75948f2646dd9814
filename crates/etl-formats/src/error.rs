//! The error type of etlcal's std library crates (formats, images, calibration,
//! simulation, reports, studies): one line that tells the user what went wrong and what to
//! do, and an [`ErrorKind`] per cause so that front ends (the CLI's exit status, Python's
//! exception classes) act on it without reading the message.
//!
//! It lives here, in the bottom std crate, so that every crate above shares it and a
//! failure keeps its kind on the way up (a lens timeout in the temperature procedure is
//! still [`ErrorKind::DeviceTimeout`] when it reaches Python).
//!
//! Bad input is [`Error::InvalidInput`] with fields: `what` the user must change (a flag
//! `"--trials"`, a key path `"views[3].points"`, an argument `"image"`), the offending
//! `value` when there is one, and the one-line `message`. Build it with the constructors,
//! not `format!` alone:
//!
//! - [`Error::invalid`]`(what, message)`: no single offending value (a missing key, flags
//!   that exclude each other, too few views);
//! - [`Error::invalid_value`]`(what, value, message)`: `value` is kept as text the way
//!   messages print it ([`InputValue`]: numbers through [`crate::compact`]);
//! - [`crate::check_range`]`(what, value, range, unit)`: a number outside a range;
//! - [`Error::within`]`(context, what_prefix)`: an error as bad input of a larger whole
//!   (the file being written, the board of a view), its `what` kept under the prefix.
//!
//! ```
//! use etl_formats::Error;
//! let n = 0_u32;
//! let e = Error::invalid_value("--trials", n, format!("--trials {n} must lie in 1..=100000"));
//! assert_eq!(e.to_string(), "invalid input: --trials 0 must lie in 1..=100000");
//! assert_eq!((e.input_what(), e.input_value().as_deref()), (Some("--trials"), Some("0")));
//! ```

use std::path::PathBuf;

use etl_core::lens::{LensError, LensErrorKind};

use crate::InputValue;

/// Result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Why an etl-calib operation failed. Messages are one line, suitable for the CLI.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading a file (or a directory) failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// Writing an output failed (its directory is missing, the disk is full, ...); earlier
    /// output at `path` is left whole.
    #[error("{path}: {source}")]
    Output {
        /// The output file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// A JSON/CSV file could not be parsed or has the wrong shape.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the place (line/column) where known.
        message: String,
    },
    /// A file declares a format or version this build does not read.
    #[error("{path}: format \"{found}\" is not supported (expected \"{expected}\")")]
    Format {
        /// The file.
        path: PathBuf,
        /// The `"format"` field found (or "missing").
        found: String,
        /// The format this reader accepts.
        expected: String,
    },
    /// An image could not be read or decoded.
    #[error("{path}: cannot read image: {message}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A checkerboard was not found (or only in part) in an image.
    #[error("board not found: {0}")]
    BoardNotFound(String),
    /// An input the user gave is invalid (e.g. a negative square size). Build it with
    /// [`Error::invalid`] (no single offending value) or [`Error::invalid_value`] (with
    /// the value); [`crate::check_range`] fills it for a number outside a range.
    #[error("invalid input: {message}")]
    InvalidInput {
        /// What the user must change: a command-line flag (`"--trials"`), a file's key
        /// as a path into the document (`"square_mm"`, `"views[3].points"`,
        /// `"setting_rig.e_com_ma"`), a function's argument (`"image"`). Where no input of
        /// the user's is at fault (a plot that could not be drawn), the thing that failed.
        what: String,
        /// The offending value as given, printed compactly ([`crate::compact`] for
        /// numbers, see [`InputValue`]); `None` when the fault is no single value (a
        /// missing key, two flags that exclude each other, too few views).
        value: Option<String>,
        /// The one-line message after `invalid input: `, which names `what` (and the value)
        /// in words; users and tests match on it, so it does not change with the fields.
        message: String,
    },
    /// The core refused the problem (its message names the unmet precondition).
    #[error("{0}")]
    Core(#[from] etl_core::Error),
    /// The lens driver or the virtual lens failed ([`Error::lens`]).
    #[error("lens: {message}")]
    Lens {
        /// What kind of failure.
        kind: LensErrorKind,
        /// The driver's message.
        message: String,
    },
}

/// `prefix.what`, or `prefix[i]...` when `what` starts with an index.
fn join_what(prefix: &str, what: &str) -> String {
    if what.starts_with('[') {
        format!("{prefix}{what}")
    } else {
        format!("{prefix}.{what}")
    }
}

/// The cause of an [`Error`], for callers that act on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// A value or argument the caller gave is invalid.
    InvalidInput,
    /// A file could not be read.
    Io,
    /// An output could not be written.
    Output,
    /// A file could not be parsed or has the wrong shape.
    Parse,
    /// A file declares another format or version.
    Format,
    /// An image could not be decoded.
    Image,
    /// The board was not found in an image.
    BoardNotFound,
    /// A solver's precondition is unmet or it failed (etl-core's error).
    Precondition,
    /// The lens driver did not answer in time.
    DeviceTimeout,
    /// The lens driver refused a command.
    DeviceRefused,
    /// The link to the lens is lost (port failure, unplugged).
    LinkLost,
    /// The lens driver's reply could not be understood.
    DeviceProtocol,
    /// Another failure of a (virtual) lens.
    Device,
}

impl Error {
    /// The cause of this error.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Io { .. } => ErrorKind::Io,
            Error::Output { .. } => ErrorKind::Output,
            Error::Parse { .. } => ErrorKind::Parse,
            Error::Format { .. } => ErrorKind::Format,
            Error::Image { .. } => ErrorKind::Image,
            Error::BoardNotFound(_) => ErrorKind::BoardNotFound,
            Error::InvalidInput { .. } => ErrorKind::InvalidInput,
            Error::Core(_) => ErrorKind::Precondition,
            Error::Lens { kind, .. } => match kind {
                LensErrorKind::Timeout => ErrorKind::DeviceTimeout,
                LensErrorKind::Refused => ErrorKind::DeviceRefused,
                LensErrorKind::LinkLost => ErrorKind::LinkLost,
                LensErrorKind::Protocol => ErrorKind::DeviceProtocol,
                LensErrorKind::InvalidInput => ErrorKind::InvalidInput,
                _ => ErrorKind::Device,
            },
        }
    }

    /// Bad input about `what` (a flag, a key path, an argument: see the fields of
    /// [`Error::InvalidInput`]) with no single offending value, e.g. a missing key or two flags that
    /// exclude each other: `Error::invalid("--port", "pass --port PATH or --virtual, not
    /// both")`. `message` is the whole line after `invalid input: `.
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidInput { what: what.into(), value: None, message: message.into() }
    }

    /// Bad input: `value` of `what` is refused; `value` is kept as text the way messages
    /// print it (numbers through [`crate::compact`], see [`InputValue`]):
    /// `Error::invalid_value("--trials", n, format!("--trials {n} must lie in 1..=100000"))`.
    pub fn invalid_value(what: impl Into<String>, value: impl InputValue, message: impl Into<String>) -> Self {
        Error::InvalidInput { what: what.into(), value: Some(value.to_input_value()), message: message.into() }
    }

    /// This error as bad input of a larger whole (a file being written, the board of a
    /// view): invalid input whose message is `"{context}: {self}"` (this error's whole
    /// line, its own `invalid input: ` included), whose value is this error's
    /// ([`Error::input_value`]) and whose `what` is this error's under `what_prefix`
    /// ([`Error::input_what`], joined as [`Error::under`] does; `None` keeps it), or
    /// `what_prefix` (else `"input"`) for an error that names no input.
    pub fn within(self, context: impl std::fmt::Display, what_prefix: Option<&str>) -> Self {
        let message = format!("{context}: {self}");
        let what = match (self.input_what(), what_prefix) {
            (Some(inner), Some(prefix)) => join_what(prefix, inner),
            (Some(inner), None) => inner.to_owned(),
            (None, prefix) => prefix.unwrap_or("input").to_owned(),
        };
        Error::InvalidInput { what, value: self.input_value(), message }
    }

    /// This error with the `what` of an [`Error::InvalidInput`] placed under `prefix`,
    /// its message and value unchanged: a board's `"square_mm"` becomes
    /// `"board.square_mm"`, a view's `"[3]"` `"views[3]"`. Other errors are returned as
    /// they are (their kind and message are contracts).
    pub fn under(self, prefix: &str) -> Self {
        self.map_what(|what| join_what(prefix, &what))
    }

    /// A library's option under the name a front end gives it: bad input about `from` (a
    /// field of an options struct, `"search_half_width_ma"`) becomes bad input about `to`
    /// (the flag `"--search-ma"`, the Python argument `"search_ma"`), in its `what` and in
    /// its message, which names `from` for this to work; any other error is returned as it
    /// is. So the library writes a message once and each front end names its own option.
    pub fn rename_input(self, from: &str, to: &str) -> Self {
        match self {
            Error::InvalidInput { what, value, message } if what == from => {
                Error::InvalidInput { what: to.to_owned(), value, message: message.replace(from, to) }
            }
            other => other,
        }
    }

    /// This error with the `what` of an [`Error::InvalidInput`] rewritten by `rename`
    /// (a solver's `"views[2].pixels"` as the caller's `"offstate_views[2].pixels"`), its
    /// message and value unchanged; other errors are returned as they are.
    pub fn map_what(self, rename: impl FnOnce(String) -> String) -> Self {
        match self {
            Error::InvalidInput { what, value, message } => Error::InvalidInput { what: rename(what), value, message },
            other => other,
        }
    }

    /// What the user must change, for bad input that names it: [`Error::InvalidInput`]'s
    /// `what`, or the input an etl-core range or finiteness check refused
    /// ([`Error::core_input`]).
    pub fn input_what(&self) -> Option<&str> {
        match self {
            Error::InvalidInput { what, .. } => Some(what),
            Error::Core(c) => Error::core_input(c).0,
            _ => None,
        }
    }

    /// The offending value of bad input, as text ([`Error::input_what`]'s value): an
    /// [`Error::InvalidInput`]'s `value`, or the value of an etl-core range check.
    pub fn input_value(&self) -> Option<String> {
        match self {
            Error::InvalidInput { value, .. } => value.clone(),
            Error::Core(c) => Error::core_input(c).1,
            _ => None,
        }
    }

    /// The input an etl-core range or finiteness check refused
    /// ([`etl_core::Error::OutOfRange`], [`etl_core::Error::NotFinite`]) and the value a
    /// range check saw (compact); `(None, None)` for the core's other errors, whose `what`
    /// names a condition or a count rather than an input.
    pub fn core_input(e: &etl_core::Error) -> (Option<&'static str>, Option<String>) {
        match *e {
            etl_core::Error::OutOfRange { what, value, .. } => (Some(what), Some(value.to_input_value())),
            etl_core::Error::NotFinite { what } => (Some(what), None),
            _ => (None, None),
        }
    }

    /// A lens failure, keeping its kind: `lens.set_current_ma(e).map_err(Error::lens)?`.
    pub fn lens<E: LensError>(e: E) -> Self {
        Error::Lens { kind: e.kind(), message: e.to_string() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lens error of a given kind, as a driver would return it.
    #[derive(Debug)]
    struct FakeLens(LensErrorKind);
    impl core::fmt::Display for FakeLens {
        fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            write!(f, "no reply to GetTemperature within 500ms")
        }
    }
    impl LensError for FakeLens {
        fn kind(&self) -> LensErrorKind {
            self.0
        }
    }

    #[test]
    fn a_lens_failure_keeps_its_kind_and_message() {
        let cases = [
            (LensErrorKind::Timeout, ErrorKind::DeviceTimeout),
            (LensErrorKind::Refused, ErrorKind::DeviceRefused),
            (LensErrorKind::LinkLost, ErrorKind::LinkLost),
            (LensErrorKind::Protocol, ErrorKind::DeviceProtocol),
            (LensErrorKind::InvalidInput, ErrorKind::InvalidInput),
            (LensErrorKind::Other, ErrorKind::Device),
        ];
        for (lens, kind) in cases {
            let e = Error::lens(FakeLens(lens));
            assert_eq!(e.kind(), kind);
            assert_eq!(e.to_string(), "lens: no reply to GetTemperature within 500ms");
        }
    }

    #[test]
    fn a_failed_write_is_an_output_error_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing-dir").join("c.json");
        let e = crate::write_atomic(&path, b"{}").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Output);
        assert!(!path.exists() && std::fs::read_dir(dir.path()).unwrap().count() == 0);
        let read = crate::read_json::<serde_json::Value>(&path, "x/1").unwrap_err();
        assert_eq!(read.kind(), ErrorKind::Io);
        assert_eq!(Error::Core(etl_core::Error::BehindCamera).kind(), ErrorKind::Precondition);
    }
}
