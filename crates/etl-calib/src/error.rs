//! The error type of etl-calib: one line that tells the user what went wrong and what to do.

use std::path::PathBuf;

/// Result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Why an etl-calib operation failed. Messages are one line, suitable for the CLI.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
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
    /// The lens driver or the virtual lens failed (etl-hw).
    #[error("lens: {0}")]
    Lens(#[from] etl_hw::HwError),
}
