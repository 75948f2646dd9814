//! [`LensClient`]: an Optotune Lens Driver 4 over a serial port (facts sheet section 9), or
//! over any other [`Transport`] ([`LensClient::from_transport`]).
//!
//! Safety rules it keeps:
//! - no call can command a current outside the driver's software limits (read from the
//!   driver with `CrUA`/`CrLA` when the port is opened) and its max current: requests
//!   beyond them are clamped (the result says so), NaN and infinities are refused;
//! - one lock around each command and its reply (the protocol has no tags);
//! - bytes left on the line (e.g. an unsolicited error frame after a fire-and-forget
//!   `PwDA`) are drained before each command and recorded ([`LensClient::take_unsolicited`]);
//! - a current command is confirmed by reading the current back: a rejected `Aw` is an
//!   error of `set_current_ma`, never "applied";
//! - after a timeout, the next command is preceded by a resynchronising probe, so that a
//!   late reply is never taken for the answer to a later question;
//! - every read has a deadline ([`OpenOptions::timeout`]): no call hangs;
//! - [`LensClient::reconnect`] reopens the port without `Start`, so the lens keeps its
//!   current (and focus); the EEPROM-backed limits are never written.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, SerialPort};

use crate::codec::scaling::{current_code, current_ma, temperature_c, FirmwareType};
use crate::codec::{scan_reply, Command, Mode, Reply, Scan};
use crate::error::{HwError, Result};
pub use crate::transport::Transport;
use etl_core::physics::shaping::ZvShaper;

/// How to open the driver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenOptions {
    /// Send the `Start` handshake (expects `Ready`). It flushes the driver's input and
    /// **zeroes the output current**: leave it off to reconnect to a lens in use.
    pub handshake: bool,
    /// Deadline for each reply, within [`TIMEOUT_RANGE`].
    pub timeout: Duration,
    /// Baud rate (115200 for the USB port; the virtual COM port ignores it).
    pub baud_rate: u32,
    /// Old firmware (before 2016): set the current with `A` instead of `Aw`.
    pub legacy_set_current: bool,
}

impl Default for OpenOptions {
    /// No handshake, 500 ms timeout, 115200 baud, `Aw`.
    fn default() -> Self {
        OpenOptions {
            handshake: false,
            timeout: Duration::from_millis(500),
            baud_rate: 115_200,
            legacy_set_current: false,
        }
    }
}

/// The reply timeouts a client accepts ([`OpenOptions::timeout`]): 1 ms to 60 s.
pub const TIMEOUT_RANGE: [Duration; 2] = [Duration::from_millis(1), Duration::from_secs(60)];

/// Refuses a timeout outside [`TIMEOUT_RANGE`] (a zero one times out every read, a huge
/// one would hang a call and overflow its deadline).
fn check_timeout(options: &OpenOptions) -> Result<()> {
    if (TIMEOUT_RANGE[0]..=TIMEOUT_RANGE[1]).contains(&options.timeout) {
        Ok(())
    } else {
        Err(etl_core::Error::InvalidArgument { what: "reply timeout must lie in 1..=60000 ms" }.into())
    }
}

/// What `identify` reads from the driver.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceInfo {
    /// Firmware type (`H`), which decides the focal-power encoding.
    pub firmware_type: FirmwareType,
    /// Firmware version (`V`) as "major.minor.build.revision".
    pub firmware_version: String,
    /// Lens serial number (`X`), as text ("00000000" when the lens EEPROM was not read).
    pub lens_serial: String,
    /// Status bytes #4..#1 (`Sr`).
    pub status: [u8; 4],
    /// Max-current calibration, mA (`CrMA`).
    pub max_current_ma: f64,
    /// Upper software limit, mA (`CrUA`).
    pub upper_limit_ma: f64,
    /// Lower software limit, mA (`CrLA`).
    pub lower_limit_ma: f64,
}

/// The outcome of a set-current call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetCurrent {
    /// What the caller asked for, mA.
    pub requested_ma: f64,
    /// What was sent (clamped and quantised), mA.
    pub commanded_ma: f64,
    /// The code sent.
    pub code: i16,
    /// The request was outside the limits and was clamped.
    pub clamped: bool,
}

/// What [`LensClient::set_current_shaped_ma`] did: the two writes of a zero-vibration
/// shaped step and when the second went out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapedSet {
    /// The current the step started from (read back before it), mA.
    pub from_ma: f64,
    /// The first write: the shaper's fraction of the step.
    pub first: SetCurrent,
    /// The second write: the target.
    pub target: SetCurrent,
    /// When the target went out after the first write was sent, s (the shaper's delay, or
    /// later when the first write's read-back took longer: then `late_s` > 0).
    pub delay_s: f64,
    /// How late the second write was against the shaper's delay, s (0 on time).
    pub late_s: f64,
}

/// A step from `from_ma` to `to_ma` by `shaper` through `set` (any lens's write): the
/// shaper's fraction at once, the target the shaper's delay after that write began (slept,
/// never early). Returns both writes' results and when the second began, s. The one
/// implementation of the shaped step ([`LensClient::set_current_shaped_ma`], a rig's
/// lens).
pub fn shaped_step<T, E>(
    from_ma: f64,
    to_ma: f64,
    shaper: &ZvShaper,
    mut set: impl FnMut(f64) -> std::result::Result<T, E>,
) -> std::result::Result<((T, T), f64), E> {
    let sent = Instant::now();
    let first = set(shaper.command_ma(from_ma, to_ma, 0.0))?;
    std::thread::sleep(Duration::from_secs_f64(shaper.delay_s.max(0.0)).saturating_sub(sent.elapsed()));
    let delay_s = sent.elapsed().as_secs_f64();
    Ok(((first, set(to_ma)?), delay_s))
}

/// An error frame that arrived when no reply was expected (after a fire-and-forget
/// command), found when draining before the next command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unsolicited {
    /// The frame (`Reply::Error(id)` or `Reply::Nack`).
    pub reply: Reply,
    /// The command sent before it (its likely cause).
    pub after: &'static str,
}

/// Bit 2 of status byte #1: no temperature limits received (controlled mode).
pub const STATUS_NO_TEMPERATURE_LIMITS: u8 = 0b100;

/// The meaning of each bit of status byte #1, bit 0 first (docs/PROTOCOL.md, section 4.7).
pub const STATUS_BITS: [&str; 8] = [
    "not all hardware available",
    "no or faulty EEPROM",
    "no temperature limits received",
    "cannot reach focal power",
    "focal-power inversion",
    "temperature outside product specification",
    "focal power outside the guaranteed range",
    "temperature outside the user range",
];

/// The focal-power range controlled mode reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlledRange {
    /// Status byte #1 (bit 2: no temperature limits received).
    pub status: u8,
    /// Smallest reachable focal power, dpt.
    pub min_dpt: f64,
    /// Largest reachable focal power, dpt.
    pub max_dpt: f64,
}

impl ControlledRange {
    /// The status bits set, by their meaning ([`STATUS_BITS`]).
    pub fn status_flags(&self) -> Vec<&'static str> {
        STATUS_BITS.iter().enumerate().filter(|(bit, _)| self.status & (1 << bit) != 0).map(|(_, s)| *s).collect()
    }
}

struct Inner<T> {
    port: Option<T>,
    rx: Vec<u8>,
    last_command: &'static str,
    unsolicited: Vec<Unsolicited>,
    max_current_ma: f64,
    limit_codes: (i16, i16),
    firmware: FirmwareType,
    legacy_temperature: bool,
    fp_range_dpt: Option<(f64, f64)>,
    /// The temperature window (min, max) degC this client sent (`PwTA`) and the driver
    /// accepted: the mode switch needs it first.
    temperature_window_c: Option<(f64, f64)>,
    /// The command that timed out, whose reply may still come (see
    /// [`LensClient::transact`]).
    desynchronised: Option<&'static str>,
}

/// The driver over a [`Transport`], the serial port by default (`LensClient` alone means
/// `LensClient<Box<dyn SerialPort>>`). All methods take `&self` (an internal lock
/// serialises command-reply pairs), so one client can be shared between threads.
///
/// ```
/// # #[cfg(unix)] { // the virtual lens's serial port is a pseudo-terminal
/// use etl_hw::client::{LensClient, OpenOptions};
/// use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
/// let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
/// let lens = LensClient::open(device.path(), OpenOptions { handshake: true, ..Default::default() }).unwrap();
/// let r = lens.set_current_ma(1000.0).unwrap(); // beyond the limits: clamped
/// assert!(r.clamped && (r.commanded_ma - 292.84).abs() < 1e-9);
/// assert!(lens.set_current_ma(f64::NAN).is_err());
/// assert_eq!(lens.identify().unwrap().lens_serial, "ETLV0001");
/// # }
/// ```
pub struct LensClient<T: Transport = Box<dyn SerialPort>> {
    path: PathBuf,
    options: OpenOptions,
    inner: Mutex<Inner<T>>,
}

fn open_port(path: &Path, options: &OpenOptions) -> Result<Box<dyn SerialPort>> {
    let name = path.to_string_lossy().into_owned();
    let port = serialport::new(name.clone(), options.baud_rate)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(options.timeout)
        .open()
        .map_err(|e| HwError::Open { path: name.clone(), message: e.to_string() })?;
    port.clear(ClearBuffer::All).map_err(|e| HwError::Open { path: name, message: e.to_string() })?;
    Ok(port)
}

impl LensClient {
    /// Opens the driver at `path`: optional `Start` handshake, then reads the max current,
    /// the software limits and the firmware type (needed to clamp and encode).
    ///
    /// Errors: the port cannot be opened ([`HwError::Open`]); no or bad replies
    /// ([`HwError::Timeout`], [`HwError::Crc`], [`HwError::Device`],
    /// [`HwError::UnexpectedReply`]); a max current <= 0 ([`HwError::BadMaxCurrent`]) or
    /// limits with lower > upper ([`HwError::InvertedLimits`]); a timeout outside
    /// [`TIMEOUT_RANGE`] ([`HwError::Core`], nothing opened).
    pub fn open(path: impl AsRef<Path>, options: OpenOptions) -> Result<LensClient> {
        check_timeout(&options)?;
        let path = path.as_ref().to_owned();
        let port = open_port(&path, &options)?;
        LensClient::start(port, path, options)
    }

    /// Reopens the port at the same path without `Start` (the lens keeps its current)
    /// and re-reads the limits. Use after an I/O error (cable pulled and plugged back).
    pub fn reconnect(&self) -> Result<()> {
        {
            let mut i = self.lock();
            i.port = None; // close first: the port is opened exclusively
            i.rx.clear();
            // A fresh port has no late reply of the old one.
            i.desynchronised = None;
        }
        let port = open_port(&self.path, &self.options)?;
        self.lock().port = Some(port);
        self.read_calibration()
    }
}

impl<T: Transport> LensClient<T> {
    /// The driver over `transport` (already open and configured), as [`LensClient::open`]
    /// does it over a serial port: optional `Start` handshake, then the max current, the
    /// limits and the firmware type. `options.baud_rate` is not used; the name in messages
    /// is [`Transport::name`].
    ///
    /// ```
    /// use etl_hw::client::{LensClient, OpenOptions};
    /// use etl_hw::virtual_lens::{VirtualDevice, VirtualLensConfig};
    /// let device = VirtualDevice::new(VirtualLensConfig::default()).unwrap();
    /// let lens = LensClient::from_transport(device.transport(), OpenOptions::default()).unwrap();
    /// assert_eq!(lens.max_current_ma(), 292.84);
    /// ```
    pub fn from_transport(transport: T, options: OpenOptions) -> Result<LensClient<T>> {
        check_timeout(&options)?;
        let path = PathBuf::from(transport.name());
        LensClient::start(transport, path, options)
    }

    fn start(port: T, path: PathBuf, options: OpenOptions) -> Result<LensClient<T>> {
        let client = LensClient {
            path,
            options,
            inner: Mutex::new(Inner {
                port: Some(port),
                rx: Vec::new(),
                last_command: "",
                unsolicited: Vec::new(),
                max_current_ma: crate::codec::scaling::DEFAULT_MAX_CURRENT_MA,
                limit_codes: (0, 0),
                firmware: FirmwareType::Other(b'?'),
                legacy_temperature: false,
                fp_range_dpt: None,
                temperature_window_c: None,
                desynchronised: None,
            }),
        };
        if options.handshake {
            match client.transact(Command::Start)? {
                Some(Reply::Ready) => {}
                other => return Err(unexpected(Command::Start, other)),
            }
        }
        client.read_calibration()?;
        Ok(client)
    }

    fn read_calibration(&self) -> Result<()> {
        let max = match self.transact(Command::ReadMaxCurrent)? {
            Some(Reply::MaxCurrent { centi_ma }) if centi_ma > 0 => f64::from(centi_ma) / 100.0,
            Some(Reply::MaxCurrent { centi_ma }) => return Err(HwError::BadMaxCurrent { centi_ma }),
            other => return Err(unexpected(Command::ReadMaxCurrent, other)),
        };
        let upper = match self.transact(Command::ReadUpperLimit)? {
            Some(Reply::UpperLimit { code }) => code.clamp(-4095, 4095),
            other => return Err(unexpected(Command::ReadUpperLimit, other)),
        };
        let lower = match self.transact(Command::ReadLowerLimit)? {
            Some(Reply::LowerLimit { code }) => code.clamp(-4095, 4095),
            other => return Err(unexpected(Command::ReadLowerLimit, other)),
        };
        if lower > upper {
            return Err(HwError::InvertedLimits { lower, upper });
        }
        let fw = match self.transact(Command::FirmwareType)? {
            Some(Reply::FirmwareType(letter)) => FirmwareType::from_letter(letter),
            other => return Err(unexpected(Command::FirmwareType, other)),
        };
        let mut inner = self.lock();
        inner.max_current_ma = max;
        inner.limit_codes = (lower, upper);
        inner.firmware = fw;
        Ok(())
    }

    fn lock(&self) -> MutexGuard<'_, Inner<T>> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The port path (for another transport: its [`Transport::name`]).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The options the client was opened with.
    pub fn options(&self) -> OpenOptions {
        self.options
    }

    /// The software limits, mA ([lower, upper]), as read at open.
    pub fn limits_ma(&self) -> [f64; 2] {
        let i = self.lock();
        [current_ma(i.limit_codes.0, i.max_current_ma), current_ma(i.limit_codes.1, i.max_current_ma)]
    }

    /// The max-current calibration, mA.
    pub fn max_current_ma(&self) -> f64 {
        self.lock().max_current_ma
    }

    /// Error frames drained since the last call (oldest first).
    pub fn take_unsolicited(&self) -> Vec<Unsolicited> {
        std::mem::take(&mut self.lock().unsolicited)
    }

    /// Sends `command` and, if it has a reply, waits for it: the one primitive every other
    /// method uses. Error frames in reply become [`HwError::Device`]/[`HwError::Nack`].
    ///
    /// Resynchronisation: the protocol has no tags, so a reply that comes after its
    /// command timed out would be taken for the answer to the next command of its kind.
    /// After a timeout the client therefore sends the probe `H` before the next command and
    /// discards everything up to the probe's reply (the driver answers in order, so every
    /// late reply comes before it); `H` answers a constant (the firmware type), so a late
    /// probe reply is never a wrong answer. Until a probe is answered every command fails
    /// with [`HwError::Desynchronised`], nothing else being sent.
    pub fn transact(&self, command: Command) -> Result<Option<Reply>> {
        let mut guard = self.lock();
        self.transact_locked(&mut guard, command)
    }

    fn transact_locked(&self, inner: &mut Inner<T>, command: Command) -> Result<Option<Reply>> {
        self.prepare(inner, command.name())?;
        self.send(inner, command)?;
        let Some(expected) = command.reply_header() else {
            return Ok(None);
        };
        match self.await_frame(inner, command.name(), expected.as_bytes())? {
            Reply::Error(id) => Err(HwError::Device { command: command.name(), id }),
            Reply::Nack => Err(HwError::Nack { command: command.name() }),
            r => Ok(Some(r)),
        }
    }

    fn io_error(&self, source: std::io::Error) -> HwError {
        HwError::Io { path: self.path.display().to_string(), source }
    }

    fn port<'a>(&self, inner: &'a mut Inner<T>) -> Result<&'a mut T> {
        let closed = || std::io::Error::new(std::io::ErrorKind::NotConnected, "port closed; reconnect");
        inner.port.as_mut().ok_or_else(|| self.io_error(closed()))
    }

    fn send(&self, inner: &mut Inner<T>, command: Command) -> Result<()> {
        inner.last_command = command.name();
        self.port(inner)?.send(&command.encode()).map_err(|e| self.io_error(e))
    }

    /// Before sending `next`: drains what is on the line (stray bytes and error frames of
    /// earlier writes) and, after a timeout, resynchronises with the probe `H`.
    fn prepare(&self, inner: &mut Inner<T>, next: &'static str) -> Result<()> {
        let timeout = self.options.timeout;
        let mut rx = std::mem::take(&mut inner.rx);
        let drained = drain(self.port(inner)?, &mut rx, timeout);
        inner.rx = rx;
        drained.map_err(|e| self.io_error(e))?;
        record_unsolicited(&mut inner.rx, &mut inner.unsolicited, inner.last_command);
        let Some(timed_out) = inner.desynchronised else {
            return Ok(());
        };
        self.send(inner, Command::FirmwareType)?;
        let deadline = Instant::now() + timeout;
        loop {
            match scan_reply(&inner.rx, b"H") {
                Scan::Found { reply: Reply::FirmwareType(_), end, .. } => {
                    // Everything before the probe's reply answered earlier commands.
                    inner.rx.drain(..end);
                    inner.desynchronised = None;
                    return Ok(());
                }
                Scan::Found { reply, end, .. } => {
                    // A late error frame: it answered the command that timed out.
                    inner.unsolicited.push(Unsolicited { reply, after: timed_out });
                    inner.rx.drain(..end);
                    continue;
                }
                Scan::Corrupted { end } => {
                    inner.rx.drain(..end);
                    continue;
                }
                Scan::NeedMore => {}
            }
            if !self.receive_until(inner, deadline)? {
                inner.rx.clear();
                return Err(HwError::Desynchronised { command: next, timeout });
            }
        }
    }

    /// Reads what arrives before `deadline` into `rx`; false once the deadline passed.
    fn receive_until(&self, inner: &mut Inner<T>, deadline: Instant) -> Result<bool> {
        let now = Instant::now();
        if now >= deadline {
            return Ok(false);
        }
        let mut chunk = [0u8; 256];
        let n = self.port(inner)?.receive(&mut chunk, deadline - now).map_err(|e| self.io_error(e))?;
        inner.rx.extend_from_slice(chunk.get(..n).unwrap_or(&chunk));
        Ok(true)
    }

    /// Waits for the reply starting `expected` or an error frame (returned as such) to the
    /// command `name` just sent. A timeout leaves the client desynchronised (see
    /// [`Self::transact`]).
    fn await_frame(&self, inner: &mut Inner<T>, name: &'static str, expected: &[u8]) -> Result<Reply> {
        let deadline = Instant::now() + self.options.timeout;
        loop {
            match scan_reply(&inner.rx, expected) {
                Scan::Found { reply, end, .. } => {
                    inner.rx.drain(..end);
                    return Ok(reply);
                }
                Scan::Corrupted { .. } => {
                    // The whole frame came, so the line stays in step; drop it and what follows.
                    inner.rx.clear();
                    let _ = self.port(inner)?.discard_input();
                    return Err(HwError::Crc { command: name });
                }
                Scan::NeedMore => {}
            }
            if !self.receive_until(inner, deadline)? {
                inner.rx.clear();
                inner.desynchronised = Some(name);
                return Err(HwError::Timeout { command: name, timeout: self.options.timeout });
            }
        }
    }

    /// Reads the firmware type, version, lens serial, status, max current and limits.
    pub fn identify(&self) -> Result<DeviceInfo> {
        self.read_calibration()?;
        let firmware_version = match self.transact(Command::FirmwareVersion)? {
            Some(Reply::FirmwareVersion { major, minor, build, revision }) => {
                format!("{major}.{minor}.{build}.{revision}")
            }
            other => return Err(unexpected(Command::FirmwareVersion, other)),
        };
        let lens_serial = match self.transact(Command::LensSerial)? {
            Some(Reply::LensSerial(b)) => {
                b.iter().map(|&c| if c.is_ascii_graphic() { char::from(c) } else { '?' }).collect()
            }
            other => return Err(unexpected(Command::LensSerial, other)),
        };
        let status = match self.transact(Command::Status)? {
            Some(Reply::Status(s)) => s,
            other => return Err(unexpected(Command::Status, other)),
        };
        let [lower_limit_ma, upper_limit_ma] = self.limits_ma();
        let i = self.lock();
        Ok(DeviceInfo {
            firmware_type: i.firmware,
            firmware_version,
            lens_serial,
            status,
            max_current_ma: i.max_current_ma,
            upper_limit_ma,
            lower_limit_ma,
        })
    }

    /// The code for `ma`, clamped to the limits; `Err` for NaN/infinite.
    fn clamped_code(&self, ma: f64) -> Result<(i16, bool)> {
        let ma = etl_core::error::finite(ma, "current (mA)")?;
        let i = self.lock();
        let (lo, hi) = i.limit_codes;
        let [lo_ma, hi_ma] = [current_ma(lo, i.max_current_ma), current_ma(hi, i.max_current_ma)];
        let clamped = ma < lo_ma || ma > hi_ma;
        // Clamp in mA (no overflow of the i16 code), then the code itself (rounding).
        let code = current_code(ma.clamp(lo_ma, hi_ma), i.max_current_ma).clamp(lo, hi);
        Ok((code, clamped))
    }

    /// Sets the output current (`Aw`): clamped to the driver's software limits, rounded to
    /// the nearest code. NaN/infinite are refused ([`HwError::Core`]).
    ///
    /// `Aw` has no reply on success, only an error frame on failure, so the client confirms
    /// it by reading the current back (`Ar`, one round trip): an error frame before the
    /// `A` reply is the driver rejecting `Aw` ([`HwError::Device`] naming `Aw`), and a
    /// read-back code other than the one sent is [`HwError::CurrentNotApplied`]. Nothing is
    /// reported as applied that the driver did not apply.
    pub fn set_current_ma(&self, ma: f64) -> Result<SetCurrent> {
        let (code, clamped) = self.clamped_code(ma)?;
        let cmd = if self.options.legacy_set_current {
            Command::SetCurrentLegacy { code }
        } else {
            Command::SetCurrent { code }
        };
        let mut guard = self.lock();
        let inner = &mut *guard;
        self.transact_locked(inner, cmd)?;
        self.send(inner, Command::GetCurrent)?;
        let read_code = match self.await_frame(inner, Command::GetCurrent.name(), b"A")? {
            Reply::Current { code } => code,
            Reply::Error(id) => {
                // The driver answers in order: this frame answers the write. Consume the
                // read-back's own reply so that the line stays in step.
                let _ = self.await_frame(inner, Command::GetCurrent.name(), b"A");
                return Err(HwError::Device { command: cmd.name(), id });
            }
            _ => {
                let _ = self.await_frame(inner, Command::GetCurrent.name(), b"A");
                return Err(HwError::Nack { command: cmd.name() });
            }
        };
        if read_code != code {
            return Err(HwError::CurrentNotApplied { command: cmd.name(), sent_code: code, read_code });
        }
        let max = inner.max_current_ma;
        Ok(SetCurrent { requested_ma: ma, commanded_ma: current_ma(code, max), code, clamped })
    }

    /// Steps the output current to `to_ma` by the zero-vibration `shaper`
    /// (`etl_core::physics::shaping`): reads the current, writes the shaper's fraction of
    /// the step at once, then the target the shaper's delay after that write was sent
    /// (each write confirmed by its read-back, as [`Self::set_current_ma`]). The
    /// membrane's ringing cancels and the step settles in about the delay instead of its
    /// transient (3.97 ms against 15.0 ms measured by `etlcal lens characterise` on the
    /// published dynamics). The delay is slept: a first read-back slower than it makes the
    /// target late, reported in [`ShapedSet::late_s`], never early.
    ///
    /// Errors: those of [`Self::current_ma`] and [`Self::set_current_ma`]; a shaper whose
    /// fraction is outside (0, 1] or whose delay is not a finite time >= 0 ([`HwError::Core`]).
    pub fn set_current_shaped_ma(&self, to_ma: f64, shaper: &ZvShaper) -> Result<ShapedSet> {
        let ok = shaper.first_fraction > 0.0 && shaper.first_fraction <= 1.0;
        if !(ok && shaper.delay_s.is_finite() && shaper.delay_s >= 0.0) {
            return Err(HwError::Core(etl_core::Error::InvalidArgument {
                what: "a shaper needs a first fraction in (0, 1] and a delay >= 0 s",
            }));
        }
        let from_ma = self.current_ma()?;
        let ((first, target), delay_s) = shaped_step(from_ma, to_ma, shaper, |ma| self.set_current_ma(ma))?;
        Ok(ShapedSet { from_ma, first, target, delay_s, late_s: (delay_s - shaper.delay_s).max(0.0) })
    }

    /// The output current, mA (`Ar`).
    pub fn current_ma(&self) -> Result<f64> {
        match self.transact(Command::GetCurrent)? {
            Some(Reply::Current { code }) => Ok(current_ma(code, self.max_current_ma())),
            other => Err(unexpected(Command::GetCurrent, other)),
        }
    }

    /// The lens temperature, degC (`TCA`, falling back to the old `TA` when the firmware
    /// answers `E 02`/`E 03`). [`HwError::NoSensor`] for the no-sensor value 4095 or a
    /// reading outside -40..125 degC.
    pub fn temperature_c(&self) -> Result<f64> {
        let legacy = self.lock().legacy_temperature;
        let reply = if legacy {
            self.transact(Command::TemperatureLegacy)?
        } else {
            match self.transact(Command::Temperature) {
                Err(HwError::Device { id: 2 | 3, .. }) => {
                    self.lock().legacy_temperature = true;
                    self.transact(Command::TemperatureLegacy)?
                }
                r => r?,
            }
        };
        let raw = match reply {
            Some(Reply::Temperature { raw }) => raw,
            Some(Reply::TemperatureLegacy { status: 0, raw }) => raw,
            Some(Reply::TemperatureLegacy { raw, .. }) => return Err(HwError::NoSensor { raw }),
            other => {
                let sent =
                    if self.lock().legacy_temperature { Command::TemperatureLegacy } else { Command::Temperature };
                return Err(unexpected(sent, other));
            }
        };
        temperature_c(raw).ok_or(HwError::NoSensor { raw })
    }

    /// Switches the operation mode (`Mw?A`); for controlled mode use
    /// [`Self::enter_controlled_mode`].
    pub fn set_mode(&self, mode: Mode) -> Result<()> {
        if mode == Mode::Controlled {
            return self.enter_controlled_mode().map(|_| ());
        }
        match self.transact(Command::SetMode(mode))? {
            Some(Reply::Mode(m)) if m == mode => Ok(()),
            other => Err(unexpected(Command::SetMode(mode), other)),
        }
    }

    /// The active mode (`MMA`): None for position-controlled (code 7) and unknown codes.
    pub fn mode(&self) -> Result<Option<Mode>> {
        match self.transact(Command::ReadMode)? {
            Some(Reply::ActiveMode { code }) => Ok(Mode::from_active_code(code)),
            other => Err(unexpected(Command::ReadMode, other)),
        }
    }

    /// Sends the temperature limits for controlled mode (`PwTA`, max first), degC.
    pub fn set_temperature_limits_c(&self, max_c: f64, min_c: f64) -> Result<ControlledRange> {
        let max_c = etl_core::error::finite(max_c, "max temperature")?;
        let min_c = etl_core::error::finite(min_c, "min temperature")?;
        if !(min_c < max_c) || min_c < -40.0 || max_c > 125.0 {
            return Err(etl_core::Error::InvalidArgument {
                what: "temperature limits need -40 <= min < max <= 125 degC",
            }
            .into());
        }
        let cmd = Command::SetTemperatureLimits {
            max_x16: crate::codec::scaling::temperature_raw(max_c),
            min_x16: crate::codec::scaling::temperature_raw(min_c),
        };
        match self.transact(cmd)? {
            Some(Reply::TemperatureLimits { status, max_fp, min_fp }) => {
                if status & STATUS_NO_TEMPERATURE_LIMITS == 0 {
                    self.lock().temperature_window_c = Some((min_c, max_c));
                }
                Ok(self.range(status, min_fp, max_fp))
            }
            other => Err(unexpected(cmd, other)),
        }
    }

    /// Enters focal-power controlled mode in the documented order: the temperature window
    /// (`PwTA`, [`Self::set_temperature_limits_c`]), then the mode switch (`MwCA`,
    /// [`Self::enter_controlled_mode`]). The range returned is where
    /// [`Self::set_focal_power_dpt`] accepts a power; a narrower window gives a wider one.
    pub fn enter_focal_power_mode(&self, max_c: f64, min_c: f64) -> Result<ControlledRange> {
        self.set_temperature_limits_c(max_c, min_c)?;
        self.enter_controlled_mode()
    }

    /// The temperature window (min, max) degC this client sent and the driver accepted.
    pub fn temperature_window_c(&self) -> Option<(f64, f64)> {
        self.lock().temperature_window_c
    }

    fn range(&self, status: u8, min_fp: i16, max_fp: i16) -> ControlledRange {
        let fw = self.lock().firmware;
        ControlledRange { status, min_dpt: fw.fp_dpt(min_fp), max_dpt: fw.fp_dpt(max_fp) }
    }

    /// Enters focal-power controlled mode (`MwCA`). Refused without sending anything when
    /// this client has not sent an accepted temperature window first (the firmware needs it
    /// to compensate temperature, and public drivers that skip it leave the lens in a mode
    /// that holds nothing); [`Self::enter_focal_power_mode`] does both in order. Errors with
    /// [`HwError::ControlledModeRefused`] when the driver's status still refuses it.
    pub fn enter_controlled_mode(&self) -> Result<ControlledRange> {
        if self.temperature_window_c().is_none() {
            return Err(etl_core::Error::InvalidArgument {
                what: "send the temperature window (PwTA) before switching to focal-power mode",
            }
            .into());
        }
        match self.transact(Command::SetMode(Mode::Controlled))? {
            Some(Reply::ControlledMode { status, max_fp, min_fp }) => {
                let r = self.range(status, min_fp, max_fp);
                if status & STATUS_NO_TEMPERATURE_LIMITS != 0 {
                    return Err(HwError::ControlledModeRefused { status });
                }
                self.lock().fp_range_dpt = Some((r.min_dpt, r.max_dpt));
                Ok(r)
            }
            other => Err(unexpected(Command::SetMode(Mode::Controlled), other)),
        }
    }

    /// Sets the focal power in controlled mode (`PwDA`, fire-and-forget), dioptres,
    /// encoded for the firmware type; returns the power the code stands for. Refused
    /// (nothing sent) on NaN, outside the range `MwCA` reported (`OutOfRange` with the
    /// range: unlike a current, a power the lens cannot hold at every temperature of the
    /// window is not clamped silently), and when controlled mode was not entered through
    /// this client.
    pub fn set_focal_power_dpt(&self, dpt: f64) -> Result<f64> {
        let dpt = etl_core::error::finite(dpt, "focal power (dpt)")?;
        let (fw, range) = {
            let i = self.lock();
            (i.firmware, i.fp_range_dpt)
        };
        let Some((lo, hi)) = range else {
            return Err(etl_core::Error::InvalidArgument {
                what: "enter controlled mode before setting a focal power",
            }
            .into());
        };
        let (min, max) = (lo.min(hi), hi.max(lo));
        if !(min..=max).contains(&dpt) {
            return Err(etl_core::Error::OutOfRange { what: "focal power (dpt)", value: dpt, min, max }.into());
        }
        let code = fw.fp_code(dpt);
        self.transact(Command::SetFocalPower { code })?;
        Ok(fw.fp_dpt(code))
    }

    /// The focal power the driver reports (`PrDA`), dioptres.
    pub fn focal_power_dpt(&self) -> Result<f64> {
        match self.transact(Command::GetFocalPower)? {
            Some(Reply::FocalPower { code }) => Ok(self.lock().firmware.fp_dpt(code)),
            other => Err(unexpected(Command::GetFocalPower, other)),
        }
    }
}

/// The error for a reply of another shape than `command`'s.
fn unexpected(command: Command, got: Option<Reply>) -> HwError {
    HwError::UnexpectedReply { command: command.name(), expected: command.reply_header().unwrap_or("no"), got }
}

/// Appends every byte waiting on the line to `rx` (they arrived before the command about
/// to be sent, so none is its reply).
fn drain<T: Transport>(port: &mut T, rx: &mut Vec<u8>, timeout: Duration) -> std::io::Result<()> {
    let pending = port.bytes_waiting()?;
    if pending > 0 {
        let mut tmp = vec![0u8; pending];
        let n = port.receive(&mut tmp, timeout)?;
        rx.extend_from_slice(tmp.get(..n).unwrap_or(&tmp));
    }
    Ok(())
}

/// Records the error frames among drained bytes as unsolicited (caused by the command sent
/// `after`, a fire-and-forget one) and empties `rx`; other bytes are stray and dropped.
fn record_unsolicited(rx: &mut Vec<u8>, unsolicited: &mut Vec<Unsolicited>, after: &'static str) {
    let mut at = 0;
    while let Some(rest) = rx.get(at..).filter(|r| !r.is_empty()) {
        match Reply::decode(rest) {
            Ok((r @ (Reply::Error(_) | Reply::Nack), n)) => {
                unsolicited.push(Unsolicited { reply: r, after });
                at += n;
            }
            Ok((_, n)) => at += n,
            Err(_) => at += 1,
        }
    }
    rx.clear();
}

impl<T: Transport> etl_core::lens::Lens for LensClient<T> {
    type Error = HwError;

    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        LensClient::set_current_ma(self, e_in_ma).map(|r| r.commanded_ma)
    }

    fn current_ma(&mut self) -> Result<f64> {
        LensClient::current_ma(self)
    }

    fn temperature_c(&mut self) -> Result<f64> {
        LensClient::temperature_c(self)
    }
}
