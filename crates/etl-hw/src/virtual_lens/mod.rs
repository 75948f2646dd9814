//! A virtual Optotune lens + Lens Driver 4: a thread serving the driver's protocol on a
//! pseudo-terminal, so that the real client talks to it through a real serial-port path,
//! driven by the physical model of [`model`] and with the fault injection of [`faults`].
//!
//! Time: the model's clock runs at wall time x [`VirtualLensConfig::time_scale`] (1 =
//! real time; tests use e.g. 100 so that a 60 s thermal time constant passes in 0.6 s),
//! plus explicit jumps ([`VirtualLens::advance_s`], [`VirtualLens::settle`]).
//!
//! Port path: [`VirtualLens::path`] is a symlink (in a private temporary directory) to the
//! pty's slave, like a udev symlink to `/dev/ttyACM0`. [`VirtualLens::disconnect`] closes
//! the pty (the client sees an I/O error, as when the USB cable is pulled) and
//! [`VirtualLens::reconnect`] opens a new one behind the same path; the lens keeps its
//! current and temperature.
//!
//! ```
//! use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
//! use etl_core::lens::Lens;
//! let mut lens = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
//! lens.set_current_ma(120.0).unwrap(); // directly, without the serial port
//! let s = lens.state();
//! assert!((s.e_in_ma - 120.0).abs() < 0.04 && s.f_liq_mm > 50.0 && s.f_liq_mm < 121.0);
//! assert!(lens.path().exists());
//! ```

pub mod faults;
pub mod model;

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;
use nix::poll::{poll, PollFd, PollFlags};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};

pub use faults::Faults;
pub use model::{LensState, ThermalModel};

use crate::codec::scaling::{current_code, current_ma, FirmwareType, NO_SENSOR_RAW};
use crate::codec::{Command, DecodeError, Mode, Reply};
use crate::error::{HwError, Result};
use model::Model;

/// How the virtual lens is built.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualLensConfig {
    /// Firmware type letter (`H`): `A` uses the offset focal-power encoding.
    pub firmware_type: u8,
    /// Firmware version (major, minor, build, revision).
    pub firmware_version: (u8, u8, u16, u16),
    /// Old firmware: speaks `A` and `TA` instead of `Aw` and `TCA` (answers the new ones
    /// with `E 03`, and the new firmware answers the old ones so).
    pub legacy_firmware: bool,
    /// Answer a command with a bad CRC by `N\r\n` instead of `E 01`.
    pub nack_on_crc: bool,
    /// Lens serial number (`X`).
    pub lens_serial: [u8; 8],
    /// Driver id (`IR`).
    pub device_id: [u8; 8],
    /// Max-current calibration, mA x 100 (`CrMA`; 29284 = 292.84 mA).
    pub max_current_centi_ma: i16,
    /// Upper software current limit, current code (`CrUA`).
    pub upper_limit_code: i16,
    /// Lower software current limit, current code (`CrLA`).
    pub lower_limit_code: i16,
    /// The lens's physics (Eq. 1-10).
    pub physics: LensPhysics,
    /// The true E_T(T, E_in) surface of this lens.
    pub surface: ThermalSurface,
    /// The thermal model.
    pub thermal: ThermalModel,
    /// Initial lens temperature, degC (None: the equilibrium at zero current).
    pub initial_temperature_c: Option<f64>,
    /// Whether the lens has a temperature sensor (else `TCA` answers 4095).
    pub has_sensor: bool,
    /// Sensor update period, s (0.1 for the SE97).
    pub sensor_period_s: f64,
    /// Model seconds per wall second.
    pub time_scale: f64,
}

impl Default for VirtualLensConfig {
    /// An EL-10-30-TC-like lens with the paper's physics and thermal surface on a driver
    /// with the default calibration (292.84 mA), limits +-4095 (+-292.84 mA), 25 degC
    /// ambient, real time.
    fn default() -> Self {
        VirtualLensConfig {
            firmware_type: b'C',
            firmware_version: (3, 8, 1, 5),
            legacy_firmware: false,
            nack_on_crc: false,
            lens_serial: *b"ETLV0001",
            device_id: *b"LD4VIRT1",
            max_current_centi_ma: 29284,
            upper_limit_code: 4095,
            lower_limit_code: -4095,
            physics: LensPhysics::paper(),
            surface: ThermalSurface::PAPER,
            thermal: ThermalModel::default(),
            initial_temperature_c: None,
            has_sensor: true,
            sensor_period_s: 0.1,
            time_scale: 1.0,
        }
    }
}

/// What the device received, for tests.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Received {
    /// Every current code received in `Aw`/`A` (before the firmware's own clamping).
    pub current_codes: Vec<i16>,
    /// Commands decoded (valid CRC).
    pub commands: u64,
    /// Frames with a bad CRC.
    pub crc_errors: u64,
    /// `Start` handshakes.
    pub handshakes: u64,
}

struct Pty {
    master: File,
    // Held open so that the master does not see a hangup while no client has the port open.
    _slave: OwnedFd,
}

#[derive(Default)]
struct Control {
    stop: bool,
    disconnect: bool,
    new_pty: Option<Pty>,
}

struct Shared {
    config: VirtualLensConfig,
    model: Model,
    faults: Faults,
    received: Received,
    control: Control,
    wall: Instant,
}

impl Shared {
    /// Advances the model to the present wall time.
    fn sync(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.wall).as_secs_f64() * self.config.time_scale;
        self.wall = now;
        self.model.advance(dt);
    }
}

/// A running virtual lens (see the module docs). Dropping it stops the server and removes
/// the port symlink.
pub struct VirtualLens {
    shared: Arc<Mutex<Shared>>,
    dir: PathBuf,
    link: PathBuf,
    thread: Option<JoinHandle<()>>,
}

static SERIAL: AtomicU64 = AtomicU64::new(0);

fn open_pty() -> Result<(Pty, PathBuf)> {
    let pty = openpty(None, None).map_err(|e| HwError::Virtual(format!("openpty: {e}")))?;
    let mut t = tcgetattr(&pty.slave).map_err(|e| HwError::Virtual(format!("tcgetattr: {e}")))?;
    cfmakeraw(&mut t);
    tcsetattr(&pty.slave, SetArg::TCSANOW, &t).map_err(|e| HwError::Virtual(format!("tcsetattr: {e}")))?;
    let name = nix::unistd::ttyname(&pty.slave).map_err(|e| HwError::Virtual(format!("ttyname: {e}")))?;
    Ok((Pty { master: File::from(pty.master), _slave: pty.slave }, name))
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    // A panic in a test thread must not hide the device's state from the others.
    shared.lock().unwrap_or_else(|p| p.into_inner())
}

impl VirtualLens {
    /// Creates the pty, starts the serving thread and returns the handle.
    ///
    /// Errors: an invalid configuration (non-finite or non-positive time scale, sensor
    /// period or time constant; limits outside +-4095 or lower > upper; max current <= 0;
    /// invalid physics or surface) as [`HwError::Core`]; the OS refusing a pty or a
    /// temporary directory ([`HwError::Virtual`]).
    pub fn spawn(config: VirtualLensConfig) -> Result<VirtualLens> {
        validate(&config)?;
        let t0 = config.initial_temperature_c.unwrap_or(config.thermal.ambient_c);
        let model = Model {
            physics: config.physics,
            surface: config.surface,
            thermal: config.thermal,
            sensor_period_s: config.sensor_period_s,
            has_sensor: config.has_sensor,
            max_current_centi_ma: config.max_current_centi_ma,
            upper_limit_code: config.upper_limit_code,
            lower_limit_code: config.lower_limit_code,
            time_s: 0.0,
            temperature_c: t0,
            sensor_raw: crate::codec::scaling::temperature_raw(t0),
            code: 0,
            heater_w: 0.0,
            mode: Mode::Current,
            fp_code: 0,
            temperature_limits_x16: None,
        };
        let dir = std::env::temp_dir().join(format!(
            "etl-vlens-{}-{}",
            std::process::id(),
            SERIAL.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| HwError::Virtual(format!("{}: {e}", dir.display())))?;
        let link = dir.join("lens");
        let (pty, name) = open_pty()?;
        std::os::unix::fs::symlink(&name, &link).map_err(|e| HwError::Virtual(format!("{}: {e}", link.display())))?;
        let shared = Arc::new(Mutex::new(Shared {
            config,
            model,
            faults: Faults::default(),
            received: Received::default(),
            control: Control::default(),
            wall: Instant::now(),
        }));
        let s2 = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("virtual-lens".into())
            .spawn(move || serve(s2, pty))
            .map_err(|e| HwError::Virtual(format!("thread: {e}")))?;
        Ok(VirtualLens { shared, dir, link, thread: Some(thread) })
    }

    /// The serial-port path to open (a symlink to the pty's slave).
    pub fn path(&self) -> &Path {
        &self.link
    }

    /// The lens's true state now.
    pub fn state(&self) -> LensState {
        let mut s = lock(&self.shared);
        s.sync();
        s.model.state()
    }

    /// What the device has received so far.
    pub fn received(&self) -> Received {
        lock(&self.shared).received.clone()
    }

    /// The driver's software limits, mA ([lower, upper]).
    pub fn limits_ma(&self) -> [f64; 2] {
        let s = lock(&self.shared);
        let m = s.model.max_current_ma();
        [current_ma(s.model.lower_limit_code, m), current_ma(s.model.upper_limit_code, m)]
    }

    /// Replaces the injected faults.
    pub fn set_faults(&self, faults: Faults) {
        lock(&self.shared).faults = faults;
    }

    /// Edits the injected faults in place.
    pub fn with_faults(&self, edit: impl FnOnce(&mut Faults)) {
        edit(&mut lock(&self.shared).faults);
    }

    /// Sets the heater power, W (negative: cooling).
    pub fn set_heater_w(&self, watts: f64) {
        let mut s = lock(&self.shared);
        s.sync();
        s.model.heater_w = if watts.is_finite() { watts } else { 0.0 };
    }

    /// Sets the heater so that the equilibrium temperature at the present current is
    /// `t_c` (a temperature-controlled mount). Non-finite values are ignored.
    pub fn set_target_temperature_c(&self, t_c: f64) {
        if !t_c.is_finite() {
            return;
        }
        let mut s = lock(&self.shared);
        s.sync();
        s.model.heater_w = s.model.heater_for_c(t_c);
    }

    /// Sets the ambient temperature, degC.
    pub fn set_ambient_c(&self, t_c: f64) {
        let mut s = lock(&self.shared);
        s.sync();
        if t_c.is_finite() {
            s.model.thermal.ambient_c = t_c;
        }
    }

    /// Advances the model clock by `dt_s` model seconds at once (on top of wall time).
    pub fn advance_s(&self, dt_s: f64) {
        let mut s = lock(&self.shared);
        s.sync();
        s.model.advance(dt_s);
    }

    /// Jumps to thermal equilibrium at the present current and heater power.
    pub fn settle(&self) {
        let mut s = lock(&self.shared);
        s.sync();
        s.model.settle();
    }

    /// Pulls the cable: closes the pty; the client's next I/O fails.
    pub fn disconnect(&self) {
        lock(&self.shared).control.disconnect = true;
        // Let the server drop the pty before the caller goes on.
        for _ in 0..200 {
            if !lock(&self.shared).control.disconnect {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Plugs the cable back in: a new pty behind the same [`Self::path`]. The lens keeps its
    /// current and temperature.
    pub fn reconnect(&self) -> Result<()> {
        let (pty, name) = open_pty()?;
        let tmp = self.dir.join("lens.new");
        let _ = std::fs::remove_file(&tmp);
        std::os::unix::fs::symlink(&name, &tmp).map_err(|e| HwError::Virtual(format!("{}: {e}", tmp.display())))?;
        std::fs::rename(&tmp, &self.link).map_err(|e| HwError::Virtual(format!("{}: {e}", self.link.display())))?;
        lock(&self.shared).control.new_pty = Some(pty);
        Ok(())
    }

    fn command_code(&self, e_in_ma: f64) -> std::result::Result<i16, etl_core::Error> {
        let e = etl_core::error::finite(e_in_ma, "e_in_ma")?;
        let s = lock(&self.shared);
        let m = s.model.max_current_ma();
        let [lo, hi] = [current_ma(s.model.lower_limit_code, m), current_ma(s.model.upper_limit_code, m)];
        Ok(current_code(e.clamp(lo, hi), m).clamp(s.model.lower_limit_code, s.model.upper_limit_code))
    }
}

fn validate(c: &VirtualLensConfig) -> Result<()> {
    use etl_core::Error as E;
    let positive = |x: f64, what: &'static str| {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(E::InvalidArgument { what })
        }
    };
    positive(c.time_scale, "time_scale must be finite and > 0")?;
    positive(c.sensor_period_s, "sensor_period_s must be finite and > 0")?;
    positive(c.thermal.tau_s, "thermal.tau_s must be finite and > 0")?;
    positive(c.thermal.thermal_resistance_k_per_w, "thermal resistance must be finite and > 0")?;
    if !(c.thermal.coil_resistance_ohm.is_finite() && c.thermal.coil_resistance_ohm >= 0.0) {
        return Err(E::InvalidArgument { what: "coil resistance must be finite and >= 0" }.into());
    }
    etl_core::error::finite(c.thermal.ambient_c, "ambient_c")?;
    if let Some(t) = c.initial_temperature_c {
        etl_core::error::finite(t, "initial_temperature_c")?;
    }
    if c.max_current_centi_ma <= 0 {
        return Err(E::InvalidArgument { what: "max current must be > 0" }.into());
    }
    if !(-4095..=4095).contains(&c.lower_limit_code)
        || !(-4095..=4095).contains(&c.upper_limit_code)
        || c.lower_limit_code > c.upper_limit_code
    {
        return Err(E::InvalidArgument { what: "current limits must lie in -4095..=4095 with lower <= upper" }.into());
    }
    c.physics.validate()?;
    c.surface.validate()?;
    Ok(())
}

impl Drop for VirtualLens {
    fn drop(&mut self) {
        lock(&self.shared).control.stop = true;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_file(&self.link);
        let _ = std::fs::remove_dir(&self.dir);
    }
}

impl etl_core::lens::Lens for VirtualLens {
    type Error = HwError;

    /// Sets the current directly on the model (no serial port), clamped to the driver's
    /// limits like the client does; recorded in [`Received::current_codes`].
    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        let code = self.command_code(e_in_ma)?;
        let mut s = lock(&self.shared);
        s.sync();
        s.received.current_codes.push(code);
        s.model.apply_code(code);
        Ok(s.model.e_in_ma())
    }

    fn current_ma(&mut self) -> Result<f64> {
        Ok(lock(&self.shared).model.e_in_ma())
    }

    fn temperature_c(&mut self) -> Result<f64> {
        let mut s = lock(&self.shared);
        s.sync();
        if !s.model.has_sensor {
            return Err(HwError::NoSensor { raw: NO_SENSOR_RAW });
        }
        Ok(s.model.sensor_c())
    }
}

/// The serving loop: poll the master, decode commands, answer.
fn serve(shared: Arc<Mutex<Shared>>, first: Pty) {
    let mut pty = Some(first);
    let mut buf: Vec<u8> = Vec::new();
    let mut last_rx = Instant::now();
    let mut chunk = [0u8; 4096];
    loop {
        {
            let mut s = lock(&shared);
            if s.control.stop {
                return;
            }
            if s.control.disconnect {
                pty = None;
                buf.clear();
                s.control.disconnect = false;
            }
            if let Some(p) = s.control.new_pty.take() {
                pty = Some(p);
                buf.clear();
            }
        }
        let Some(p) = pty.as_mut() else {
            std::thread::sleep(Duration::from_millis(2));
            continue;
        };
        let ready = {
            let mut fds = [PollFd::new(p.master.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, 20u16) {
                Ok(n) if n > 0 => fds[0].revents().is_some_and(|r| r.contains(PollFlags::POLLIN)),
                Ok(_) => false,
                Err(_) => false,
            }
        };
        if !ready {
            // A partial command left alone for 50 ms is dropped (the host gave up on it).
            if !buf.is_empty() && last_rx.elapsed() > Duration::from_millis(50) {
                buf.clear();
            }
            continue;
        }
        let n = match p.master.read(&mut chunk) {
            Ok(n) => n,
            // EIO: no client has the slave open (after it closed the port). Wait.
            Err(_) => {
                std::thread::sleep(Duration::from_millis(2));
                continue;
            }
        };
        last_rx = Instant::now();
        {
            let mut s = lock(&shared);
            for &b in &chunk[..n] {
                if s.faults.drop_rx_bytes_next > 0 {
                    s.faults.drop_rx_bytes_next -= 1;
                } else {
                    buf.push(b);
                }
            }
        }
        process(&shared, &mut buf, &mut p.master);
    }
}

/// Decodes and answers every complete command in `buf`.
fn process(shared: &Mutex<Shared>, buf: &mut Vec<u8>, out: &mut File) {
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
            send(shared, out, Reply::Error(3));
        }
        if let Some(r) = reply {
            send(shared, out, r);
        }
    }
    if garbage {
        send(shared, out, Reply::Error(3));
    }
}

/// Writes a reply, applying the reply faults.
fn send(shared: &Mutex<Shared>, out: &mut File, reply: Reply) {
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
    if !delay.is_zero() {
        std::thread::sleep(delay);
    }
    let _ = out.write_all(&bytes);
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
            if m.mode == Mode::Controlled {
                // Hold the power at the present temperature: E_com from the optics, then E_in.
                if let Some(e_com) = m.e_com_for_power(fw.fp_dpt(code)) {
                    if let Ok(e_in) = m.surface.e_in_for_e_com(e_com, m.temperature_c) {
                        let c = current_code(e_in, m.max_current_ma());
                        m.apply_code(c);
                    }
                }
            }
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
