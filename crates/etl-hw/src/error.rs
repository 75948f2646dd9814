//! The error type of etl-hw.

use std::path::PathBuf;
use std::time::Duration;

use crate::codec::Reply;

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
    /// After a timeout, the resynchronising probe `H` got no reply either, so `command`
    /// was not sent (a late reply could otherwise be taken for its answer).
    #[error("no reply to the resynchronising H before {command} within {timeout:?} (the driver has not answered since an earlier timeout)")]
    Desynchronised {
        /// The command that was not sent.
        command: &'static str,
        /// The timeout.
        timeout: Duration,
    },
    /// A current command was not applied: the current read back (`Ar`) is not the code sent.
    #[error("lens driver did not apply {command}: sent current code {sent_code}, read back {read_code}")]
    CurrentNotApplied {
        /// The command's header (`Aw` or `A`).
        command: &'static str,
        /// The code sent.
        sent_code: i16,
        /// The code read back.
        read_code: i16,
    },
    /// The driver answered with the bare NACK `N` (it saw a bad CRC).
    #[error("lens driver answered {command} with N (it received a corrupted command)")]
    Nack {
        /// The command's header.
        command: &'static str,
    },
    /// The driver answered a command with a frame of another shape than the command's
    /// reply ([`crate::codec::Command::reply_header`]).
    #[error("protocol error: {command} expects a reply starting {expected:?}, got {}", describe(got))]
    UnexpectedReply {
        /// The command's header.
        command: &'static str,
        /// The reply header the command should get.
        expected: &'static str,
        /// What came instead.
        got: Option<Reply>,
    },
    /// The driver reports a max-current calibration (`CrMA`) that is not positive, so no
    /// current can be scaled.
    #[error("protocol error: the driver reports a max current of {} mA (must be > 0)", f64::from(*centi_ma) / 100.0)]
    BadMaxCurrent {
        /// The value received, mA x 100.
        centi_ma: i16,
    },
    /// The driver's software limits (`CrLA`, `CrUA`) have lower > upper.
    #[error("protocol error: driver limits are inverted: lower {lower} > upper {upper}")]
    InvertedLimits {
        /// Lower limit, current code.
        lower: i16,
        /// Upper limit, current code.
        upper: i16,
    },
    /// `MwCA` answered with status bit 2 set: the driver has no temperature limits.
    #[error(
        "controlled mode refused: no temperature limits received (call set_temperature_limits_c first; status {status:#010b})"
    )]
    ControlledModeRefused {
        /// Status byte #1 of the reply.
        status: u8,
    },
    /// The lens has no temperature sensor (or it returned an impossible value).
    #[error("the lens reports no temperature sensor (raw value {raw})")]
    NoSensor {
        /// The raw value received (4095 = no sensor).
        raw: i16,
    },
    /// A caller's value was refused (NaN, out of range, ...).
    #[error(transparent)]
    Core(#[from] etl_core::Error),
    /// A step of creating or serving the virtual lens's pseudo-terminal failed (`openpty`,
    /// `tcgetattr`, `tcsetattr`, `ttyname`, the serving thread).
    #[error("virtual lens: {step}: {source}")]
    Pty {
        /// The step.
        step: &'static str,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The virtual lens's port path (its directory or symlink) could not be made.
    #[error("virtual lens: {}: {source}", path.display())]
    PortPath {
        /// The path.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
}

impl etl_core::lens::LensError for HwError {
    fn kind(&self) -> etl_core::lens::LensErrorKind {
        use etl_core::lens::LensErrorKind as K;
        match self {
            HwError::Open { .. } | HwError::Io { .. } => K::LinkLost,
            HwError::Timeout { .. } | HwError::Desynchronised { .. } => K::Timeout,
            HwError::Crc { .. }
            | HwError::Nack { .. }
            | HwError::UnexpectedReply { .. }
            | HwError::BadMaxCurrent { .. }
            | HwError::InvertedLimits { .. } => K::Protocol,
            HwError::Device { .. }
            | HwError::CurrentNotApplied { .. }
            | HwError::NoSensor { .. }
            | HwError::ControlledModeRefused { .. } => K::Refused,
            HwError::Core(_) => K::InvalidInput,
            HwError::Pty { .. } | HwError::PortPath { .. } => K::Other,
        }
    }
}

/// A reply for a message: its frame header and fields, or that none came.
fn describe(reply: &Option<Reply>) -> String {
    match reply {
        Some(r) => format!("{} frame {r:?}", String::from_utf8_lossy(r.header())),
        None => "no reply".to_owned(),
    }
}
