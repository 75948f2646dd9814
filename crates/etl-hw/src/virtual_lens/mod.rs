//! A virtual Optotune lens + Lens Driver 4: a device model ([`VirtualDevice`]: the physics
//! of [`model`], the driver's protocol, the fault injection of [`faults`]) that a client
//! reaches either in-process ([`VirtualTransport`], on every platform) or, on Unix,
//! through a pseudo-terminal behind a real serial-port path ([`VirtualLens`]).
//!
//! Time: the model's clock runs at wall time x [`VirtualLensConfig::time_scale`] (1 =
//! real time; tests use e.g. 100 so that a 60 s thermal time constant passes in 0.6 s),
//! plus explicit jumps ([`VirtualDevice::advance_s`], [`VirtualDevice::settle`]).
//!
//! ```
//! use etl_hw::client::{LensClient, OpenOptions};
//! use etl_hw::virtual_lens::{VirtualDevice, VirtualLensConfig};
//! let device = VirtualDevice::new(VirtualLensConfig::default()).unwrap();
//! let lens = LensClient::from_transport(device.transport(), OpenOptions::default()).unwrap();
//! lens.set_current_ma(120.0).unwrap();
//! let s = device.state();
//! assert!((s.e_in_ma - 120.0).abs() < 0.04 && s.f_liq_mm > 50.0 && s.f_liq_mm < 121.0);
//! ```

pub mod faults;
#[cfg(unix)]
pub mod folders;
pub mod model;
#[cfg(unix)]
mod pty;
mod responder;

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use etl_core::physics::dynamics::{LensDynamics, LensResponse};
use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;

pub use faults::Faults;
pub use model::{FocalPowerCompensation, LensState, ThermalModel};
#[cfg(unix)]
pub use pty::VirtualLens;

use crate::codec::scaling::{current_code, current_ma, NO_SENSOR_RAW, SENSOR_RANGE_C};
use crate::codec::Mode;
use crate::error::{HwError, Result};
use crate::transport::Transport;
use model::Model;

/// The largest [`VirtualLensConfig::time_scale`], model seconds per wall second.
pub const MAX_TIME_SCALE: f64 = 1e6;

/// The longest reply delay a fault may inject (`Faults::reply_delay`), ms: one minute,
/// longer than any timeout a client uses.
pub const MAX_REPLY_DELAY_MS: f64 = 60_000.0;

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
    /// The membrane's dynamics (`etlcal.lens-dynamics/1`; None: the optics follow the
    /// command at once). With them the optics lag each command (step response, creep,
    /// hysteresis) and the lens heats as they say ([`model`]).
    pub dynamics: Option<LensDynamics>,
    /// The firmware's temperature compensation in focal-power mode (a stated residual).
    pub fp_compensation: FocalPowerCompensation,
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
            dynamics: None,
            fp_compensation: FocalPowerCompensation::default(),
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

struct Shared {
    config: VirtualLensConfig,
    model: Model,
    faults: Faults,
    received: Received,
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

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    // A panic in a test thread must not hide the device's state from the others.
    shared.lock().unwrap_or_else(|p| p.into_inner())
}

/// The virtual lens and driver: the model, its protocol responder and its faults. A
/// handle: clones share one device (a pty server, transports and the test that
/// inspects its true state).
#[derive(Clone)]
pub struct VirtualDevice {
    shared: Arc<Mutex<Shared>>,
}

impl VirtualDevice {
    /// A device at rest (zero current, at the initial temperature).
    ///
    /// Errors: an invalid configuration (non-finite or non-positive time scale, sensor
    /// period or time constant; limits outside +-4095 or lower > upper; max current <= 0;
    /// invalid physics, surface or dynamics) as [`HwError::Core`].
    pub fn new(config: VirtualLensConfig) -> Result<VirtualDevice> {
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
            dynamics: config.dynamics.map(|d| (d, LensResponse::at_rest(0.0))),
            fp_compensation: config.fp_compensation,
            fp_target_dpt: None,
        };
        let shared =
            Shared { config, model, faults: Faults::default(), received: Received::default(), wall: Instant::now() };
        Ok(VirtualDevice { shared: Arc::new(Mutex::new(shared)) })
    }

    /// An in-process link to this device for [`crate::client::LensClient::from_transport`]
    /// (no pseudo-terminal: works on every platform).
    pub fn transport(&self) -> VirtualTransport {
        VirtualTransport { device: self.clone(), commands: Vec::new(), replies: VecDeque::new() }
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
    if !(c.time_scale > 0.0 && c.time_scale <= MAX_TIME_SCALE) {
        return Err(E::InvalidArgument { what: "time_scale must lie in (0, 1e6] model s per wall s" }.into());
    }
    positive(c.sensor_period_s, "sensor_period_s must be finite and > 0")?;
    if let Some(d) = &c.dynamics {
        d.validate()?;
    }
    let fp = c.fp_compensation;
    if !((0.0..=1.0).contains(&fp.residual_fraction)
        && SENSOR_RANGE_C[0] <= fp.reference_c
        && fp.reference_c <= SENSOR_RANGE_C[1])
    {
        return Err(E::InvalidArgument {
            what: "fp_compensation needs a residual fraction in 0..=1 and a reference in -40..=125 degC",
        }
        .into());
    }
    positive(c.thermal.tau_s, "thermal.tau_s must be finite and > 0")?;
    positive(c.thermal.thermal_resistance_k_per_w, "thermal resistance must be finite and > 0")?;
    if !(c.thermal.coil_resistance_ohm.is_finite() && c.thermal.coil_resistance_ohm >= 0.0) {
        return Err(E::InvalidArgument { what: "coil resistance must be finite and >= 0" }.into());
    }
    // The lens sensor's range: a lens model outside it would report "no sensor".
    let in_sensor_range = |t: f64| (SENSOR_RANGE_C[0]..=SENSOR_RANGE_C[1]).contains(&t);
    if !in_sensor_range(c.thermal.ambient_c) {
        return Err(E::InvalidArgument { what: "ambient temperature must lie in -40..=125 degC" }.into());
    }
    if c.initial_temperature_c.is_some_and(|t| !in_sensor_range(t)) {
        return Err(E::InvalidArgument { what: "initial temperature must lie in -40..=125 degC" }.into());
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

impl etl_core::lens::Lens for VirtualDevice {
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

/// An in-process [`Transport`] to a [`VirtualDevice`]: what the client sends is answered
/// at once by the device's responder (with its faults); a reply becomes readable after
/// the device's reply delay.
pub struct VirtualTransport {
    device: VirtualDevice,
    /// Bytes received that are not a whole command yet.
    commands: Vec<u8>,
    /// Replies sent, each readable from its instant on.
    replies: VecDeque<(Instant, Vec<u8>)>,
}

impl VirtualTransport {
    /// The bytes readable now (the fronts of the reply queue whose instant has come).
    fn ready(&self, now: Instant) -> impl Iterator<Item = &Vec<u8>> {
        self.replies.iter().take_while(move |(at, _)| *at <= now).map(|(_, b)| b)
    }
}

impl Transport for VirtualTransport {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        let shared = &self.device.shared;
        responder::receive(shared, bytes, &mut self.commands);
        let now = Instant::now();
        let replies = &mut self.replies;
        responder::process(shared, &mut self.commands, &mut |delay, frame| replies.push_back((now + delay, frame)));
        Ok(())
    }

    fn bytes_waiting(&mut self) -> std::io::Result<usize> {
        Ok(self.ready(Instant::now()).map(Vec::len).sum())
    }

    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        let now = Instant::now();
        // Wait as a blocking read would: until the next reply is due or the timeout.
        let due = self.replies.front().map_or(timeout, |(at, _)| at.saturating_duration_since(now).min(timeout));
        if !due.is_zero() {
            std::thread::sleep(due);
        }
        let now = Instant::now();
        let mut n = 0;
        while let Some((at, frame)) = self.replies.front_mut() {
            let Some(room) = buf.get_mut(n..).filter(|r| !r.is_empty() && *at <= now) else {
                break;
            };
            let k = room.len().min(frame.len());
            room[..k].copy_from_slice(&frame[..k]);
            frame.drain(..k);
            n += k;
            if frame.is_empty() {
                self.replies.pop_front();
            }
        }
        Ok(n)
    }

    fn discard_input(&mut self) -> std::io::Result<()> {
        let now = Instant::now();
        while self.replies.front().is_some_and(|(at, _)| *at <= now) {
            self.replies.pop_front();
        }
        Ok(())
    }

    fn name(&self) -> String {
        "virtual lens".to_owned()
    }
}
