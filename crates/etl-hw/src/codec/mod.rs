//! The Optotune Lens Driver 4 serial protocol (facts sheet
//! `docs/PROTOCOL.md`): CRC-16/ARC, commands, replies, units.
//!
//! ```
//! use etl_hw::codec::{Command, Reply};
//! assert_eq!(Command::Temperature.encode(), [0x54, 0x43, 0x41, 0xB0, 0xD0]);
//! let (reply, used) = Reply::decode(&[0x54, 0x43, 0x41, 0x01, 0xB2, 0xF5, 0xB9, 0x0D, 0x0A]).unwrap();
//! assert_eq!((reply, used), (Reply::Temperature { raw: 434 }, 9)); // 27.125 degC
//! ```

pub mod command;
pub mod crc;
pub mod reply;
pub mod scaling;

pub use command::{Command, Mode};
pub use crc::crc16_arc;
pub use reply::{error_meaning, Reply};

/// Why bytes did not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum DecodeError {
    /// The bytes are a proper prefix of a frame: read more.
    #[error("incomplete frame")]
    Incomplete,
    /// No frame starts with these bytes.
    #[error("unknown frame header")]
    Unknown,
    /// A complete frame of `len` bytes whose CRC-16/ARC does not match.
    #[error("CRC mismatch in a {len}-byte frame")]
    Crc {
        /// Frame length.
        len: usize,
    },
    /// A complete frame of `len` bytes with a bad field or terminator.
    #[error("malformed {len}-byte frame")]
    Malformed {
        /// Frame length.
        len: usize,
    },
}

/// What [`scan_reply`] found in a receive buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scan {
    /// A valid reply (with the expected header, or an error frame) ending at `end`; the
    /// `start` bytes before it were garbage.
    Found {
        /// The reply.
        reply: Reply,
        /// Bytes skipped before it.
        start: usize,
        /// One past its last byte.
        end: usize,
    },
    /// A complete frame with the expected header and terminator but a failing CRC,
    /// ending at `end`.
    Corrupted {
        /// One past its last byte.
        end: usize,
    },
    /// Nothing yet: read more.
    NeedMore,
}

/// Looks for the reply to a command whose reply starts with `expected` (or an error
/// frame `E`/`N`) anywhere in `buf`, so that stray bytes before it are skipped
/// (resynchronisation). The earliest valid frame wins; a corrupted frame with the expected
/// header is reported only when no valid one follows it.
pub fn scan_reply(buf: &[u8], expected: &[u8]) -> Scan {
    let mut corrupted = None;
    for start in 0..buf.len() {
        let rest = &buf[start..];
        let plausible = rest.starts_with(expected) || rest.starts_with(b"E") || rest.starts_with(b"N");
        if !plausible {
            continue;
        }
        match Reply::decode(rest) {
            Ok((reply, n)) if rest.starts_with(expected) || matches!(reply, Reply::Error(_) | Reply::Nack) => {
                return Scan::Found { reply, start, end: start + n };
            }
            Err(DecodeError::Crc { len }) if rest.starts_with(expected) && corrupted.is_none() => {
                corrupted = Some(start + len);
            }
            _ => {}
        }
    }
    match corrupted {
        Some(end) => Scan::Corrupted { end },
        None => Scan::NeedMore,
    }
}
