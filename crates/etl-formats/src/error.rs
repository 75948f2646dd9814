//! The error type of etlcal's std library crates (formats, images, calibration,
//! simulation, reports, studies): one line that tells the user what went wrong and what to
//! do, and an [`ErrorKind`] per cause so that front ends (the CLI's exit status, Python's
//! exception classes) act on it without reading the message.
//!
//! It lives here, in the bottom std crate, so that every crate above shares it and a
//! failure keeps its kind on the way up (a lens timeout in the temperature procedure is
//! still [`ErrorKind::DeviceTimeout`] when it reaches Python).

use std::path::PathBuf;

use etl_core::lens::{LensError, LensErrorKind};

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
    /// An input value is invalid (e.g. a negative square size).
    #[error("invalid input: {0}")]
    InvalidInput(String),
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
            Error::InvalidInput(_) => ErrorKind::InvalidInput,
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
