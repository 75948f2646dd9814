//! The protocol responder of the virtual lens: decodes the commands the host sent,
//! executes them on the model and encodes the replies, with the injected faults. Used by
//! the pseudo-terminal server and by the in-process [`super::VirtualTransport`] alike.

use std::sync::Mutex;
use std::time::Duration;

use super::model::Model;
use super::{lock, Shared};
use crate::codec::scaling::{current_ma, FirmwareType, NO_SENSOR_RAW};
use crate::codec::{Command, DecodeError, Mode, Reply};

/// Appends the bytes the host sent to the command buffer `buf`, losing those the
/// `drop_rx_bytes_next` fault says.
pub(super) fn receive(shared: &Mutex<Shared>, bytes: &[u8], buf: &mut Vec<u8>) {
    let mut s = lock(shared);
    for &b in bytes {
        if s.faults.drop_rx_bytes_next > 0 {
            s.faults.drop_rx_bytes_next -= 1;
        } else {
            buf.push(b);
        }
    }
}

/// Decodes and answers every complete command in `buf`: each reply goes to `emit` with
/// the delay after which the device puts it on the line.
pub(super) fn process(shared: &Mutex<Shared>, buf: &mut Vec<u8>, emit: &mut dyn FnMut(Duration, Vec<u8>)) {
    let mut garbage = false;
    loop {
        let decoded = Command::decode(buf);
        let reply: Option<Reply> = {
            let mut s = lock(shared);
            match decoded {
                Err(DecodeError::Incomplete) => break,
                Err(DecodeError::Unknown) => {
                    buf.remove(0);
                    garbage = true;
                    continue;
                }
                Err(DecodeError::Crc { len }) => {
                    buf.drain(..len);
                    s.received.crc_errors += 1;
                    Some(if s.config.nack_on_crc { Reply::Nack } else { Reply::Error(1) })
                }
                Err(DecodeError::Malformed { len }) => {
                    buf.drain(..len);
                    Some(Reply::Error(3))
                }
                Ok((cmd, len)) => {
                    buf.drain(..len);
                    s.received.commands += 1;
                    if s.faults.crc_error_next > 0 {
                        s.faults.crc_error_next -= 1;
                        s.received.crc_errors += 1;
                        Some(if s.config.nack_on_crc { Reply::Nack } else { Reply::Error(1) })
                    } else if let Some(id) = s.faults.error_frame_next.take() {
                        Some(Reply::Error(id))
                    } else {
                        s.sync();
                        execute(&mut s, cmd, buf)
                    }
                }
            }
        };
        if garbage {
            garbage = false;
            send(shared, emit, Reply::Error(3));
        }
        if let Some(r) = reply {
            send(shared, emit, r);
        }
    }
    if garbage {
        send(shared, emit, Reply::Error(3));
    }
}

/// Encodes a reply with the reply faults applied and hands it to `emit` (unless it is
/// silenced).
fn send(shared: &Mutex<Shared>, emit: &mut dyn FnMut(Duration, Vec<u8>), reply: Reply) {
    let (delay, bytes) = {
        let mut s = lock(shared);
        if s.faults.silence_next > 0 {
            s.faults.silence_next -= 1;
            return;
        }
        let mut bytes = std::mem::take(&mut s.faults.garbage_before_next);
        let mut frame = reply.encode();
        if s.faults.corrupt_next > 0 {
            s.faults.corrupt_next -= 1;
            // The CRC's high byte (just before \r\n; for Ready/N, a letter).
            let at = frame.len().saturating_sub(3);
            if let Some(b) = frame.get_mut(at) {
                *b ^= 0x5A;
            }
        }
        bytes.append(&mut frame);
        (s.faults.reply_delay, bytes)
    };
    emit(delay, bytes);
}

/// Executes a decoded command on the model; the reply, if the command has one.
fn execute(s: &mut Shared, cmd: Command, buf: &mut Vec<u8>) -> Option<Reply> {
    let Shared { config, model: m, received, .. } = s;
    let legacy = config.legacy_firmware;
    let fw = FirmwareType::from_letter(config.firmware_type);
    match cmd {
        Command::Start => {
            // MAN16: zeroes the current and flushes the input buffer.
            m.apply_code(0);
            buf.clear();
            received.handshakes += 1;
            Some(Reply::Ready)
        }
        Command::SetCurrent { code } | Command::SetCurrentLegacy { code } => {
            if legacy != matches!(cmd, Command::SetCurrentLegacy { .. }) {
                return Some(Reply::Error(3));
            }
            received.current_codes.push(code);
            m.apply_code(code);
            None
        }
        Command::GetCurrent => Some(Reply::Current { code: m.code }),
        Command::ReadMaxCurrent => Some(Reply::MaxCurrent { centi_ma: m.max_current_centi_ma }),
        Command::ReadUpperLimit => Some(Reply::UpperLimit { code: m.upper_limit_code }),
        Command::ReadLowerLimit => Some(Reply::LowerLimit { code: m.lower_limit_code }),
        Command::SetMode(Mode::Controlled) => {
            let status = if m.temperature_limits_x16.is_none() { 0b100 } else { 0 };
            if status == 0 {
                m.mode = Mode::Controlled;
                m.hold_focal_power();
            }
            let (min_fp, max_fp) = fp_range(m, fw);
            Some(Reply::ControlledMode { status, max_fp, min_fp })
        }
        Command::SetMode(mode) => {
            m.mode = mode;
            Some(Reply::Mode(mode))
        }
        Command::ReadMode => Some(Reply::ActiveMode { code: m.mode.active_code() }),
        Command::SetFocalPower { code } => {
            m.fp_code = code;
            // Stored in any mode, applied (and held as the lens's temperature changes) in
            // controlled mode only (XLSX #0310).
            m.fp_target_dpt = Some(fw.fp_dpt(code));
            m.hold_focal_power();
            None
        }
        Command::GetFocalPower => {
            let st = m.state();
            Some(Reply::FocalPower { code: fw.fp_code(st.focal_power_dpt) })
        }
        Command::SetTemperatureLimits { max_x16, min_x16 } => {
            let ok = max_x16 > min_x16;
            if ok {
                m.temperature_limits_x16 = Some((max_x16, min_x16));
            }
            let (min_fp, max_fp) = fp_range(m, fw);
            Some(Reply::TemperatureLimits { status: if ok { 0 } else { 0b100 }, max_fp, min_fp })
        }
        Command::SetSignalUpper { .. } | Command::SetSignalLower { .. } | Command::SetFrequency { .. } => None,
        Command::Temperature | Command::TemperatureLegacy => {
            if legacy != matches!(cmd, Command::TemperatureLegacy) {
                return Some(Reply::Error(3));
            }
            let raw = if m.has_sensor { m.sensor_raw } else { NO_SENSOR_RAW };
            Some(if legacy {
                Reply::TemperatureLegacy { status: if m.has_sensor { 0 } else { 0xFF }, raw }
            } else {
                Reply::Temperature { raw }
            })
        }
        Command::FirmwareType => Some(Reply::FirmwareType(config.firmware_type)),
        Command::FirmwareBranch => Some(Reply::FirmwareBranch(0)),
        Command::PartNumber => Some(Reply::PartNumber([0x12, 0x34, 0x56])),
        Command::FirmwareVersion => {
            let (major, minor, build, revision) = config.firmware_version;
            Some(Reply::FirmwareVersion { major, minor, build, revision })
        }
        Command::DeviceId => Some(Reply::DeviceId(config.device_id)),
        Command::LensSerial => Some(Reply::LensSerial(config.lens_serial)),
        Command::Status => {
            let status1 = if m.temperature_limits_x16.is_none() { 0b100 } else { 0 };
            Some(Reply::Status([0, 0, 0, status1]))
        }
        Command::AnalogInput => Some(Reply::AnalogInput(0)),
    }
}

/// (min, max) focal-power codes over [max(lower limit, 0), upper limit] at the present
/// temperature.
fn fp_range(m: &Model, fw: FirmwareType) -> (i16, i16) {
    let mm = m.max_current_ma();
    let lo = current_ma(m.lower_limit_code, mm).max(0.0);
    let hi = current_ma(m.upper_limit_code, mm);
    let p = |e: f64| {
        let e_t = m.surface.e_t_ma(e, m.temperature_c).unwrap_or(0.0);
        fw.fp_code(m.power_dpt_at(e - e_t))
    };
    (p(lo), p(hi))
}
