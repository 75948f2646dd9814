//! The error type of etl-hw.

use std::time::Duration;

/// Result with [`HwError`].
pub type Result<T> = std::result::Result<T, HwError>;

/// Why a lens-driver operation failed. Messages are one line, for the CLI.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HwError {
    /// The serial port could not be opened or configured.
    #[error("cannot open serial port {path}: {message}")]
    Open {
        /// The port.
        path: String,
        /// Why.
        message: String,
    },
    /// Reading or writing the port failed (e.g. the device was unplugged).
    #[error("serial I/O on {path}: {source} (device unplugged? reconnect)")]
    Io {
        /// The port.
        path: String,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// No (complete) reply within the timeout.
    #[error("no reply to {command} within {timeout:?}")]
    Timeout {
        /// The command's header.
        command: &'static str,
        /// The timeout.
        timeout: Duration,
    },
    /// The reply failed its CRC check (the command may be retried).
    #[error("reply to {command} failed its CRC check")]
    Crc {
        /// The command's header.
        command: &'static str,
    },
    /// The driver answered with an error frame `E` + id.
    #[error("lens driver answered {command} with error {id}: {}", crate::codec::error_meaning(*id))]
    Device {
        /// The command's header.
        command: &'static str,
        /// Error id (1 CRC, 2 not in this firmware, 3 unknown command, 4 lens incompatible).
        id: u8,
    },
    /// The driver answered with the bare NACK `N` (it saw a bad CRC).
    #[error("lens driver answered {command} with N (it received a corrupted command)")]
    Nack {
        /// The command's header.
        command: &'static str,
    },
    /// The driver answered something the protocol does not allow here.
    #[error("protocol error: {0}")]
    Protocol(String),
    /// The lens has no temperature sensor (or it returned an impossible value).
    #[error("the lens reports no temperature sensor (raw value {raw})")]
    NoSensor {
        /// The raw value received (4095 = no sensor).
        raw: i16,
    },
    /// A caller's value was refused (NaN, out of range, ...).
    #[error(transparent)]
    Core(#[from] etl_core::Error),
    /// Creating or serving the virtual lens's pseudo-terminal failed.
    #[error("virtual lens: {0}")]
    Virtual(String),
}

impl etl_core::lens::LensError for HwError {
    fn kind(&self) -> etl_core::lens::LensErrorKind {
        use etl_core::lens::LensErrorKind as K;
        match self {
            HwError::Open { .. } | HwError::Io { .. } => K::LinkLost,
            HwError::Timeout { .. } => K::Timeout,
            HwError::Crc { .. } | HwError::Nack { .. } | HwError::Protocol(_) => K::Protocol,
            HwError::Device { .. } | HwError::NoSensor { .. } => K::Refused,
            HwError::Core(_) => K::InvalidInput,
            HwError::Virtual(_) => K::Other,
        }
    }
}
