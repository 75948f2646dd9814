//! Host -> driver commands (facts sheet sections 2 and 4.1-4.7): encoding, and decoding
//! (which the virtual lens uses to parse what the client sends).
//!
//! Deliberately absent: the EEPROM writes of section 4.2 (`CwMA`, `CwUA`, `CwLA`: rated
//! for ~100k cycles, not for routine use) and every command of section 4.9 (`Zw`, `D`,
//! `RESET`, `IW`), which can corrupt the lens calibration or brick the driver.

use super::crc::{append_crc, crc_ok};
use super::DecodeError;

/// An operation mode of the driver (`Mw` + letter + `A`, section 4.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// DC / current mode (`D`).
    Current,
    /// Sinusoidal signal generator (`S`).
    Sinusoidal,
    /// Rectangular signal generator (`Q`).
    Rectangular,
    /// Triangular signal generator (`T`).
    Triangular,
    /// The analog input drives the current (`A`).
    Analog,
    /// Focal-power controlled mode (`C`).
    Controlled,
}

impl Mode {
    /// All modes.
    pub const ALL: [Mode; 6] =
        [Mode::Current, Mode::Sinusoidal, Mode::Rectangular, Mode::Triangular, Mode::Analog, Mode::Controlled];

    /// The letter of the mode in `Mw?A` and in the reply `M?A`.
    pub fn letter(self) -> u8 {
        match self {
            Mode::Current => b'D',
            Mode::Sinusoidal => b'S',
            Mode::Rectangular => b'Q',
            Mode::Triangular => b'T',
            Mode::Analog => b'A',
            Mode::Controlled => b'C',
        }
    }

    /// The mode of a letter.
    pub fn from_letter(letter: u8) -> Option<Mode> {
        Mode::ALL.into_iter().find(|m| m.letter() == letter)
    }

    /// The code `MMA` reports for this mode (section 4.3: 1 current, 2 sinusoidal,
    /// 3 triangular, 4 rectangular, 5 controlled, 6 analog; 7 is position controlled, which
    /// has no `Mw` letter).
    pub fn active_code(self) -> u8 {
        match self {
            Mode::Current => 1,
            Mode::Sinusoidal => 2,
            Mode::Triangular => 3,
            Mode::Rectangular => 4,
            Mode::Controlled => 5,
            Mode::Analog => 6,
        }
    }

    /// The mode of an `MMA` code (None for 7, position controlled, and unknown codes).
    pub fn from_active_code(code: u8) -> Option<Mode> {
        Mode::ALL.into_iter().find(|m| m.active_code() == code)
    }
}

/// A command the host sends. Integers are big-endian on the wire; every command but
/// [`Command::Start`] carries a CRC-16/ARC, low byte first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// `Start` handshake (no CRC): answered `Ready\r\n`; zeroes the output current.
    Start,
    /// `Aw` + current code: set the current (no reply on success).
    SetCurrent {
        /// Current code, +-4095 = +- the max-current calibration.
        code: i16,
    },
    /// Legacy `A` + current code (firmware before 2016; no reply).
    SetCurrentLegacy {
        /// Current code.
        code: i16,
    },
    /// `Ar 00 00`: read the current code.
    GetCurrent,
    /// `CrMA 00 00`: read the max-current calibration (mA x 100).
    ReadMaxCurrent,
    /// `CrUA 00 00`: read the upper software current limit (current code).
    ReadUpperLimit,
    /// `CrLA 00 00`: read the lower software current limit (current code).
    ReadLowerLimit,
    /// `Mw?A`: switch the operation mode.
    SetMode(Mode),
    /// `MMA`: read the active mode.
    ReadMode,
    /// `PwDA` + FP code + `00 00`: set the focal power (controlled mode; no reply).
    SetFocalPower {
        /// Focal-power code (encoding depends on the firmware type).
        code: i16,
    },
    /// `PrDA 00 00 00 00`: read the focal power.
    GetFocalPower,
    /// `PwTA` + Tmax x 16 + Tmin x 16: temperature limits for controlled mode.
    SetTemperatureLimits {
        /// Upper temperature limit, degC x 16.
        max_x16: i16,
        /// Lower temperature limit, degC x 16.
        min_x16: i16,
    },
    /// `PwUA` + code + `00 00`: upper swing of the signal generator (no reply).
    SetSignalUpper {
        /// Current code.
        code: i16,
    },
    /// `PwLA` + code + `00 00`: lower swing of the signal generator (no reply).
    SetSignalLower {
        /// Current code.
        code: i16,
    },
    /// `PwFA` + uint32 Hz x 1000: signal-generator frequency (no reply).
    SetFrequency {
        /// Frequency in mHz.
        millihertz: u32,
    },
    /// `TCA`: lens temperature (current firmware).
    Temperature,
    /// `TA`: lens temperature with a status byte (old firmware).
    TemperatureLegacy,
    /// `H`: firmware type.
    FirmwareType,
    /// `F`: firmware branch.
    FirmwareBranch,
    /// `J`: firmware part number.
    PartNumber,
    /// `V`: firmware version.
    FirmwareVersion,
    /// `IR` + 8 x `00`: device (driver) id.
    DeviceId,
    /// `X`: lens serial number.
    LensSerial,
    /// `Sr`: status bytes.
    Status,
    /// `GAA`: analog input reading.
    AnalogInput,
}

/// How a command's header maps to its length and content: (header, total length
/// including the CRC, parser of the data between header and CRC).
type Parser = fn(&[u8]) -> Option<Command>;

fn be_i16(d: &[u8], at: usize) -> Option<i16> {
    Some(i16::from_be_bytes([*d.get(at)?, *d.get(at + 1)?]))
}

fn zeros(d: &[u8]) -> bool {
    d.iter().all(|&b| b == 0)
}

/// Every command header, its full frame length, and how to read its data. `Start` (no
/// CRC) is handled separately. Order matters only for headers that are prefixes of others
/// (`A` vs `Aw`/`Ar`: the legacy `A` is listed last and its data cannot start with `w`
/// or `r` for a valid code, |code| <= 4096).
const TABLE: &[(&[u8], usize, Parser)] = &[
    (b"Aw", 6, |d| Some(Command::SetCurrent { code: be_i16(d, 0)? })),
    (b"Ar", 6, |d| zeros(d).then_some(Command::GetCurrent)),
    (b"CrMA", 8, |d| zeros(d).then_some(Command::ReadMaxCurrent)),
    (b"CrUA", 8, |d| zeros(d).then_some(Command::ReadUpperLimit)),
    (b"CrLA", 8, |d| zeros(d).then_some(Command::ReadLowerLimit)),
    (b"MwDA", 6, |_| Some(Command::SetMode(Mode::Current))),
    (b"MwSA", 6, |_| Some(Command::SetMode(Mode::Sinusoidal))),
    (b"MwQA", 6, |_| Some(Command::SetMode(Mode::Rectangular))),
    (b"MwTA", 6, |_| Some(Command::SetMode(Mode::Triangular))),
    (b"MwAA", 6, |_| Some(Command::SetMode(Mode::Analog))),
    (b"MwCA", 6, |_| Some(Command::SetMode(Mode::Controlled))),
    (b"MMA", 5, |_| Some(Command::ReadMode)),
    (b"PwDA", 10, |d| zeros(d.get(2..)?).then_some(Command::SetFocalPower { code: be_i16(d, 0)? })),
    (b"PrDA", 10, |d| zeros(d).then_some(Command::GetFocalPower)),
    (b"PwTA", 10, |d| Some(Command::SetTemperatureLimits { max_x16: be_i16(d, 0)?, min_x16: be_i16(d, 2)? })),
    (b"PwUA", 10, |d| zeros(d.get(2..)?).then_some(Command::SetSignalUpper { code: be_i16(d, 0)? })),
    (b"PwLA", 10, |d| zeros(d.get(2..)?).then_some(Command::SetSignalLower { code: be_i16(d, 0)? })),
    (b"PwFA", 10, |d| Some(Command::SetFrequency { millihertz: u32::from_be_bytes(d.get(0..4)?.try_into().ok()?) })),
    (b"TCA", 5, |_| Some(Command::Temperature)),
    (b"TA", 4, |_| Some(Command::TemperatureLegacy)),
    (b"H", 3, |_| Some(Command::FirmwareType)),
    (b"F", 3, |_| Some(Command::FirmwareBranch)),
    (b"J", 3, |_| Some(Command::PartNumber)),
    (b"V", 3, |_| Some(Command::FirmwareVersion)),
    (b"IR", 12, |d| zeros(d).then_some(Command::DeviceId)),
    (b"X", 3, |_| Some(Command::LensSerial)),
    (b"Sr", 4, |_| Some(Command::Status)),
    (b"GAA", 5, |_| Some(Command::AnalogInput)),
    (b"A", 5, |d| Some(Command::SetCurrentLegacy { code: be_i16(d, 0)? })),
];

/// The `Start` handshake bytes (no CRC, no terminator).
pub const START: &[u8; 5] = b"Start";

impl Command {
    /// A short name for messages (the command's ASCII header).
    pub fn name(&self) -> &'static str {
        self.headers().0
    }

    /// The command's ASCII header and the header of the driver's reply to it (None for the
    /// fire-and-forget commands): one row a command, so that a command cannot be given a
    /// name without deciding its reply.
    fn headers(&self) -> (&'static str, Option<&'static str>) {
        match self {
            Command::Start => ("Start", Some("Ready")),
            Command::SetCurrent { .. } => ("Aw", None),
            Command::SetCurrentLegacy { .. } => ("A", None),
            Command::GetCurrent => ("Ar", Some("A")),
            Command::ReadMaxCurrent => ("CrMA", Some("CMA")),
            Command::ReadUpperLimit => ("CrUA", Some("CUA")),
            Command::ReadLowerLimit => ("CrLA", Some("CLA")),
            Command::SetMode(Mode::Current) => ("MwDA", Some("MDA")),
            Command::SetMode(Mode::Sinusoidal) => ("MwSA", Some("MSA")),
            Command::SetMode(Mode::Rectangular) => ("MwQA", Some("MQA")),
            Command::SetMode(Mode::Triangular) => ("MwTA", Some("MTA")),
            Command::SetMode(Mode::Analog) => ("MwAA", Some("MAA")),
            Command::SetMode(Mode::Controlled) => ("MwCA", Some("MCA")),
            Command::ReadMode => ("MMA", Some("MMA")),
            Command::SetFocalPower { .. } => ("PwDA", None),
            Command::GetFocalPower => ("PrDA", Some("PD")),
            Command::SetTemperatureLimits { .. } => ("PwTA", Some("PT")),
            Command::SetSignalUpper { .. } => ("PwUA", None),
            Command::SetSignalLower { .. } => ("PwLA", None),
            Command::SetFrequency { .. } => ("PwFA", None),
            Command::Temperature => ("TCA", Some("TCA")),
            Command::TemperatureLegacy => ("TA", Some("TA")),
            Command::FirmwareType => ("H", Some("H")),
            Command::FirmwareBranch => ("F", Some("F")),
            Command::PartNumber => ("J", Some("J")),
            Command::FirmwareVersion => ("V", Some("V")),
            Command::DeviceId => ("IR", Some("IR")),
            Command::LensSerial => ("X", Some("X")),
            Command::Status => ("Sr", Some("S")),
            Command::AnalogInput => ("GAA", Some("GAA")),
        }
    }

    /// The bytes on the wire.
    ///
    /// ```
    /// use etl_hw::codec::Command;
    /// assert_eq!(Command::SetCurrent { code: 1202 }.encode(), [0x41, 0x77, 0x04, 0xB2, 0x26, 0x93]);
    /// ```
    pub fn encode(&self) -> Vec<u8> {
        if let Command::Start = self {
            return START.to_vec();
        }
        let mut f = Vec::with_capacity(12);
        f.extend_from_slice(self.name().as_bytes());
        match *self {
            Command::SetCurrent { code } | Command::SetCurrentLegacy { code } => {
                f.extend_from_slice(&code.to_be_bytes())
            }
            Command::GetCurrent | Command::ReadMaxCurrent | Command::ReadUpperLimit | Command::ReadLowerLimit => {
                f.extend_from_slice(&[0, 0])
            }
            Command::SetFocalPower { code } | Command::SetSignalUpper { code } | Command::SetSignalLower { code } => {
                f.extend_from_slice(&code.to_be_bytes());
                f.extend_from_slice(&[0, 0]);
            }
            Command::GetFocalPower => f.extend_from_slice(&[0; 4]),
            Command::SetTemperatureLimits { max_x16, min_x16 } => {
                f.extend_from_slice(&max_x16.to_be_bytes());
                f.extend_from_slice(&min_x16.to_be_bytes());
            }
            Command::SetFrequency { millihertz } => f.extend_from_slice(&millihertz.to_be_bytes()),
            Command::DeviceId => f.extend_from_slice(&[0; 8]),
            _ => {}
        }
        append_crc(&mut f);
        f
    }

    /// The header the driver's reply to this command starts with (facts sheet sections 2
    /// and 4), or None for the fire-and-forget commands (`Aw`, `A`, `PwDA`, `PwUA`, `PwLA`,
    /// `PwFA`), which only ever produce an error frame. The one table of reply shapes: the
    /// client looks its replies up here.
    ///
    /// ```
    /// use etl_hw::codec::{Command, Mode};
    /// assert_eq!(Command::ReadMaxCurrent.reply_header(), Some("CMA"));
    /// assert_eq!(Command::SetMode(Mode::Controlled).reply_header(), Some("MCA"));
    /// assert_eq!(Command::SetCurrent { code: 1 }.reply_header(), None);
    /// ```
    pub fn reply_header(&self) -> Option<&'static str> {
        self.headers().1
    }

    /// Whether the driver answers this command on success (see [`Self::reply_header`]).
    pub fn has_reply(&self) -> bool {
        self.reply_header().is_some()
    }

    /// Decodes the command at the start of `buf`: `Ok((command, bytes used))`.
    ///
    /// Errors: [`DecodeError::Incomplete`] when `buf` is a proper prefix of a command (read
    /// more); [`DecodeError::Crc`] for a complete frame whose CRC fails (its length is in
    /// the error, so a device can skip it); [`DecodeError::Unknown`] when no command starts
    /// with these bytes; [`DecodeError::Malformed`] for dummy bytes that are not zero.
    pub fn decode(buf: &[u8]) -> Result<(Command, usize), DecodeError> {
        if buf.is_empty() {
            return Err(DecodeError::Incomplete);
        }
        if buf.starts_with(START) {
            return Ok((Command::Start, START.len()));
        }
        if START.starts_with(buf) {
            return Err(DecodeError::Incomplete);
        }
        let mut incomplete = false;
        for &(header, len, parse) in TABLE {
            if buf.len() < header.len() {
                if header.starts_with(buf) {
                    incomplete = true;
                }
                continue;
            }
            if !buf.starts_with(header) {
                continue;
            }
            // `A` (legacy) shares its first byte with `Aw`/`Ar`: a lone `A` waits for more.
            if buf.len() < len {
                return Err(DecodeError::Incomplete);
            }
            let frame = &buf[..len];
            if !crc_ok(frame) {
                return Err(DecodeError::Crc { len });
            }
            let data = &frame[header.len()..len - 2];
            return match parse(data) {
                Some(c) => Ok((c, len)),
                None => Err(DecodeError::Malformed { len }),
            };
        }
        if incomplete {
            Err(DecodeError::Incomplete)
        } else {
            Err(DecodeError::Unknown)
        }
    }
}
