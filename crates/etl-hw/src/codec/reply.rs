//! Driver -> host replies (facts sheet sections 2, 4 and 4.10): every reply has a fixed
//! length given by its header and ends with CRC-16/ARC (low byte first) and `\r\n`;
//! `Ready\r\n` and the bare NACK `N\r\n` carry no CRC.
//!
//! Replies are never framed by looking for `\r\n`: payload and CRC bytes can contain 0x0A
//! and 0x0D (facts sheet section 1).

use super::command::Mode;
use super::crc::{append_crc, crc_ok};
use super::DecodeError;

/// A reply from the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reply {
    /// `Ready\r\n`, the answer to `Start`.
    Ready,
    /// `A` + current code (answer to `Ar`).
    Current {
        /// Current code.
        code: i16,
    },
    /// `CMA` + mA x 100 (answer to `CrMA`).
    MaxCurrent {
        /// Max-current calibration, mA x 100.
        centi_ma: i16,
    },
    /// `CUA` + current code (answer to `CrUA`).
    UpperLimit {
        /// Current code.
        code: i16,
    },
    /// `CLA` + current code (answer to `CrLA`).
    LowerLimit {
        /// Current code.
        code: i16,
    },
    /// `M?A`: mode switched (answer to `Mw?A` for every mode but controlled).
    Mode(Mode),
    /// `MCA` + status + max FP + min FP (answer to `MwCA`).
    ControlledMode {
        /// Status byte #1 (section 4.7).
        status: u8,
        /// Largest reachable focal-power code.
        max_fp: i16,
        /// Smallest reachable focal-power code.
        min_fp: i16,
    },
    /// `MMA` + mode code (answer to `MMA`; see [`Mode::from_active_code`]).
    ActiveMode {
        /// 1..7.
        code: u8,
    },
    /// `PD` + FP code (answer to `PrDA`).
    FocalPower {
        /// Focal-power code.
        code: i16,
    },
    /// `PT` + status + max FP + min FP (answer to `PwTA`).
    TemperatureLimits {
        /// Status byte #1.
        status: u8,
        /// Largest reachable focal-power code.
        max_fp: i16,
        /// Smallest reachable focal-power code.
        min_fp: i16,
    },
    /// `TCA` + degC x 16 (answer to `TCA`; 4095 = no sensor).
    Temperature {
        /// degC x 16.
        raw: i16,
    },
    /// `TA` + status + degC x 16 (answer to the old `TA`; status 0 = ok, 0xFF = failed).
    TemperatureLegacy {
        /// 0 ok, 0xFF failed.
        status: u8,
        /// degC x 16.
        raw: i16,
    },
    /// `H` + type letter (A, B, C, E, F).
    FirmwareType(u8),
    /// `F` + branch (0 trunk).
    FirmwareBranch(u8),
    /// `J` + first 6 digits of the firmware part number (3 bytes).
    PartNumber([u8; 3]),
    /// `V` + major + minor + build + revision.
    FirmwareVersion {
        /// Major.
        major: u8,
        /// Minor.
        minor: u8,
        /// Build.
        build: u16,
        /// Revision.
        revision: u16,
    },
    /// `IR` + 8 bytes of driver id.
    DeviceId([u8; 8]),
    /// `X` + 8 bytes of lens serial (eight `0` if the lens EEPROM was not read).
    LensSerial([u8; 8]),
    /// `S` + status bytes #4, #3, #2, #1 (in this order on the wire).
    Status([u8; 4]),
    /// `GAA` + 10-bit ADC value.
    AnalogInput(u16),
    /// `E` + error id (1 CRC failed, 2 not in this firmware, 3 not recognised, 4 lens not
    /// compatible).
    Error(u8),
    /// Bare NACK `N\r\n` (CRC failed, in some firmware).
    Nack,
}

/// The meaning of an error id of an `E` frame (section 4.10).
pub fn error_meaning(id: u8) -> &'static str {
    match id {
        1 => "CRC failed",
        2 => "command not available in this firmware type",
        3 => "command not recognised",
        4 => "lens not compatible with firmware",
        _ => "unknown error",
    }
}

/// Reply headers that carry a CRC, with their total frame length (including CRC and CRLF).
/// Headers are distinct and none is a prefix of another.
const LENGTHS: &[(&[u8], usize)] = &[
    (b"A", 7),
    (b"CMA", 9),
    (b"CUA", 9),
    (b"CLA", 9),
    (b"MDA", 7),
    (b"MSA", 7),
    (b"MQA", 7),
    (b"MTA", 7),
    (b"MAA", 7),
    (b"MCA", 12),
    (b"MMA", 8),
    (b"PD", 8),
    (b"PT", 11),
    (b"TCA", 9),
    (b"TA", 9),
    (b"H", 6),
    (b"F", 6),
    (b"J", 8),
    (b"V", 11),
    (b"IR", 14),
    (b"X", 13),
    (b"S", 9),
    (b"GAA", 9),
    (b"E", 6),
];

/// `Ready\r\n`.
pub const READY: &[u8; 7] = b"Ready\r\n";
/// The bare NACK.
pub const NACK: &[u8; 3] = b"N\r\n";

fn be_i16(d: &[u8; 16], at: usize) -> i16 {
    i16::from_be_bytes([d[at], d[at + 1]])
}

fn be_u16(d: &[u8; 16], at: usize) -> u16 {
    u16::from_be_bytes([d[at], d[at + 1]])
}

impl Reply {
    /// The header bytes this reply starts with.
    pub fn header(&self) -> &'static [u8] {
        match self {
            Reply::Ready => b"Ready",
            Reply::Current { .. } => b"A",
            Reply::MaxCurrent { .. } => b"CMA",
            Reply::UpperLimit { .. } => b"CUA",
            Reply::LowerLimit { .. } => b"CLA",
            Reply::Mode(Mode::Current) => b"MDA",
            Reply::Mode(Mode::Sinusoidal) => b"MSA",
            Reply::Mode(Mode::Rectangular) => b"MQA",
            Reply::Mode(Mode::Triangular) => b"MTA",
            Reply::Mode(Mode::Analog) => b"MAA",
            Reply::Mode(Mode::Controlled) | Reply::ControlledMode { .. } => b"MCA",
            Reply::ActiveMode { .. } => b"MMA",
            Reply::FocalPower { .. } => b"PD",
            Reply::TemperatureLimits { .. } => b"PT",
            Reply::Temperature { .. } => b"TCA",
            Reply::TemperatureLegacy { .. } => b"TA",
            Reply::FirmwareType(_) => b"H",
            Reply::FirmwareBranch(_) => b"F",
            Reply::PartNumber(_) => b"J",
            Reply::FirmwareVersion { .. } => b"V",
            Reply::DeviceId(_) => b"IR",
            Reply::LensSerial(_) => b"X",
            Reply::Status(_) => b"S",
            Reply::AnalogInput(_) => b"GAA",
            Reply::Error(_) => b"E",
            Reply::Nack => b"N",
        }
    }

    /// The bytes on the wire (what the virtual lens sends).
    ///
    /// `Reply::Mode(Mode::Controlled)` has no frame of its own (the driver answers `MwCA`
    /// with [`Reply::ControlledMode`]); it is encoded as that with status 0 and zero limits.
    pub fn encode(&self) -> Vec<u8> {
        match *self {
            Reply::Ready => return READY.to_vec(),
            Reply::Nack => return NACK.to_vec(),
            Reply::Mode(Mode::Controlled) => {
                return Reply::ControlledMode { status: 0, max_fp: 0, min_fp: 0 }.encode();
            }
            _ => {}
        }
        let mut f = Vec::with_capacity(16);
        f.extend_from_slice(self.header());
        match *self {
            Reply::Current { code } | Reply::UpperLimit { code } | Reply::LowerLimit { code } => {
                f.extend_from_slice(&code.to_be_bytes())
            }
            Reply::MaxCurrent { centi_ma } => f.extend_from_slice(&centi_ma.to_be_bytes()),
            Reply::ControlledMode { status, max_fp, min_fp } | Reply::TemperatureLimits { status, max_fp, min_fp } => {
                f.push(status);
                f.extend_from_slice(&max_fp.to_be_bytes());
                f.extend_from_slice(&min_fp.to_be_bytes());
            }
            Reply::ActiveMode { code } => f.push(code),
            Reply::FocalPower { code } => f.extend_from_slice(&code.to_be_bytes()),
            Reply::Temperature { raw } => f.extend_from_slice(&raw.to_be_bytes()),
            Reply::TemperatureLegacy { status, raw } => {
                f.push(status);
                f.extend_from_slice(&raw.to_be_bytes());
            }
            Reply::FirmwareType(b) | Reply::FirmwareBranch(b) | Reply::Error(b) => f.push(b),
            Reply::PartNumber(p) => f.extend_from_slice(&p),
            Reply::FirmwareVersion { major, minor, build, revision } => {
                f.push(major);
                f.push(minor);
                f.extend_from_slice(&build.to_be_bytes());
                f.extend_from_slice(&revision.to_be_bytes());
            }
            Reply::DeviceId(b) | Reply::LensSerial(b) => f.extend_from_slice(&b),
            Reply::Status(s) => f.extend_from_slice(&s),
            Reply::AnalogInput(v) => f.extend_from_slice(&v.to_be_bytes()),
            Reply::Ready | Reply::Nack | Reply::Mode(_) => {}
        }
        append_crc(&mut f);
        f.extend_from_slice(b"\r\n");
        f
    }

    /// The total frame length of the reply whose header starts `buf`, if `buf` starts with
    /// a complete known header; `Err(Incomplete)` if `buf` is a proper prefix of one.
    pub fn frame_len(buf: &[u8]) -> Result<usize, DecodeError> {
        if buf.is_empty() {
            return Err(DecodeError::Incomplete);
        }
        for special in [&READY[..], &NACK[..]] {
            if buf.starts_with(special) {
                return Ok(special.len());
            }
            if special.starts_with(buf) {
                return Err(DecodeError::Incomplete);
            }
        }
        let mut incomplete = false;
        for &(header, len) in LENGTHS {
            if buf.starts_with(header) {
                return Ok(len);
            }
            if header.starts_with(buf) {
                incomplete = true;
            }
        }
        if incomplete {
            Err(DecodeError::Incomplete)
        } else {
            Err(DecodeError::Unknown)
        }
    }

    /// Decodes the reply at the start of `buf`: `Ok((reply, bytes used))`.
    ///
    /// Errors: [`DecodeError::Incomplete`] (read more), [`DecodeError::Unknown`] (no reply
    /// starts so), [`DecodeError::Crc`] (a complete frame with the right terminator whose
    /// CRC fails), [`DecodeError::Malformed`] (no `\r\n` where the length says, or an
    /// unknown mode/firmware field). Never panics, whatever the bytes.
    pub fn decode(buf: &[u8]) -> Result<(Reply, usize), DecodeError> {
        let len = Reply::frame_len(buf)?;
        if buf.len() < len {
            return Err(DecodeError::Incomplete);
        }
        let frame = &buf[..len];
        if frame == READY {
            return Ok((Reply::Ready, len));
        }
        if frame == NACK {
            return Ok((Reply::Nack, len));
        }
        if !frame.ends_with(b"\r\n") {
            return Err(DecodeError::Malformed { len });
        }
        let body = &frame[..len - 2];
        if !crc_ok(body) {
            return Err(DecodeError::Crc { len });
        }
        let h = LENGTHS.iter().map(|(h, _)| *h).find(|h| frame.starts_with(h)).ok_or(DecodeError::Unknown)?;
        let data = body.get(h.len()..body.len() - 2).ok_or(DecodeError::Malformed { len })?;
        // Padded copy: the fixed indices below cannot go out of bounds, whatever the table says.
        let mut d = [0u8; 16];
        if let Some(dst) = d.get_mut(..data.len()) {
            dst.copy_from_slice(data);
        }
        let d = &d;
        let reply = match h {
            b"A" => Reply::Current { code: be_i16(d, 0) },
            b"CMA" => Reply::MaxCurrent { centi_ma: be_i16(d, 0) },
            b"CUA" => Reply::UpperLimit { code: be_i16(d, 0) },
            b"CLA" => Reply::LowerLimit { code: be_i16(d, 0) },
            b"MCA" => Reply::ControlledMode { status: d[0], max_fp: be_i16(d, 1), min_fp: be_i16(d, 3) },
            b"MMA" => Reply::ActiveMode { code: d[0] },
            b"PD" => Reply::FocalPower { code: be_i16(d, 0) },
            b"PT" => Reply::TemperatureLimits { status: d[0], max_fp: be_i16(d, 1), min_fp: be_i16(d, 3) },
            b"TCA" => Reply::Temperature { raw: be_i16(d, 0) },
            b"TA" => Reply::TemperatureLegacy { status: d[0], raw: be_i16(d, 1) },
            b"H" => Reply::FirmwareType(d[0]),
            b"F" => Reply::FirmwareBranch(d[0]),
            b"J" => Reply::PartNumber([d[0], d[1], d[2]]),
            b"V" => Reply::FirmwareVersion { major: d[0], minor: d[1], build: be_u16(d, 2), revision: be_u16(d, 4) },
            b"IR" => Reply::DeviceId([d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]]),
            b"X" => Reply::LensSerial([d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]]),
            b"S" => Reply::Status([d[0], d[1], d[2], d[3]]),
            b"GAA" => Reply::AnalogInput(be_u16(d, 0)),
            b"E" => Reply::Error(d[0]),
            // M?A: the letter is the mode.
            _ => Reply::Mode(Mode::from_letter(h[1]).ok_or(DecodeError::Malformed { len })?),
        };
        Ok((reply, len))
    }
}
