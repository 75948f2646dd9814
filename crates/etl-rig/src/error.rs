//! The rig's one error type: a device's failure names the device (`camera sim`, `stage
//! zaber:/dev/ttyUSB0`, `lens virtual`) and says what kind of failure it was
//! ([`Error::kind`], as etl-core's `LensError::kind` and embedded-hal's `Error::kind()` do),
//! so that a capture ends a view with one line saying which device failed and how.

use etl_core::lens::{LensError, LensErrorKind};

/// What kind of failure a rig call met.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The device did not answer in time.
    Timeout,
    /// The device refused the command (a limit, bad data, a busy axis).
    Refused,
    /// The link is gone: unplugged, closed, no more frames.
    LinkLost,
    /// The device's reply could not be understood.
    Protocol,
    /// The caller's value or the plan was refused before anything was sent.
    InvalidInput,
    /// A view was refused by the procedure (no board, temperature moved, not settled).
    ViewRefused,
    /// Files: the output could not be written or the dataset read.
    Io,
    /// The capture was stopped (Ctrl-C) between views.
    Stopped,
    /// Anything else.
    Other,
}

/// A failure of the rig or of a capture.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A device failed: `device` is e.g. `camera files:/data/run1`.
    #[error("{device}: {message}")]
    Device {
        /// The device, as `camera SPEC`, `stage SPEC` or `lens SPEC`.
        device: String,
        /// What kind of failure.
        kind: ErrorKind,
        /// What happened, one line.
        message: String,
    },
    /// A view was refused (named by its key, e.g. `views[3]`).
    #[error("{view}: {message}")]
    View {
        /// The view's key in the dataset, e.g. `views[3]` or `offstate_views[0]`.
        view: String,
        /// Why, one line.
        message: String,
    },
    /// A file or input error (the plan, the dataset, an image).
    #[error("{0}")]
    Formats(#[from] etl_formats::Error),
}

impl Error {
    /// A device's failure.
    pub fn device(device: impl Into<String>, kind: ErrorKind, message: impl Into<String>) -> Error {
        Error::Device { device: device.into(), kind, message: one_line(message.into()) }
    }

    /// A refused view.
    pub fn view(view: impl Into<String>, message: impl Into<String>) -> Error {
        Error::View { view: view.into(), message: one_line(message.into()) }
    }

    /// A lens failure of the device named `device` (its kind mapped from the lens's).
    pub fn lens<E: etl_core::lens::LensError>(device: &str, e: E) -> Error {
        let kind = match e.kind() {
            LensErrorKind::Timeout => ErrorKind::Timeout,
            LensErrorKind::Refused => ErrorKind::Refused,
            LensErrorKind::LinkLost => ErrorKind::LinkLost,
            LensErrorKind::Protocol => ErrorKind::Protocol,
            LensErrorKind::InvalidInput => ErrorKind::InvalidInput,
            _ => ErrorKind::Other,
        };
        Error::device(device, kind, e.to_string())
    }

    /// What kind of failure this is.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Device { kind, .. } => *kind,
            Error::View { .. } => ErrorKind::ViewRefused,
            Error::Formats(e) => match e.kind() {
                etl_formats::ErrorKind::InvalidInput => ErrorKind::InvalidInput,
                _ => ErrorKind::Io,
            },
        }
    }

    /// The device this error names, if it is a device's.
    pub fn device_name(&self) -> Option<&str> {
        match self {
            Error::Device { device, .. } => Some(device),
            _ => None,
        }
    }
}

/// The rig's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `message` on one line (line breaks of a device's text become spaces).
fn one_line(message: String) -> String {
    if message.contains(['\n', '\r']) {
        message.split(['\n', '\r']).filter(|s| !s.trim().is_empty()).collect::<Vec<_>>().join(" ")
    } else {
        message
    }
}

impl From<Error> for etl_formats::Error {
    /// For front ends whose error is etl-formats' (the command line): the same one line,
    /// led by the device or the view (as a file's error is led by its path); a device spec
    /// or value refused before anything was sent is invalid input naming the device.
    fn from(e: Error) -> Self {
        let other = |lead: String, message: String| etl_formats::Error::Io {
            path: lead.into(),
            source: std::io::Error::other(message),
        };
        match e {
            Error::Formats(e) => e,
            Error::Device { device, message, kind: ErrorKind::InvalidInput } => {
                let line = format!("{device}: {message}");
                etl_formats::Error::invalid(device, line)
            }
            Error::Device { device, message, .. } => other(device, message),
            Error::View { view, message } => other(view, message),
        }
    }
}

/// A rig error as a lens error (a rig lens, [`crate::lens::RigLens::from_driver`], under
/// etl-core's `Lens` trait): its kind mapped back.
impl LensError for Error {
    fn kind(&self) -> LensErrorKind {
        match Error::kind(self) {
            ErrorKind::Timeout => LensErrorKind::Timeout,
            ErrorKind::Refused => LensErrorKind::Refused,
            ErrorKind::LinkLost => LensErrorKind::LinkLost,
            ErrorKind::Protocol => LensErrorKind::Protocol,
            ErrorKind::InvalidInput => LensErrorKind::InvalidInput,
            _ => LensErrorKind::Other,
        }
    }
}
