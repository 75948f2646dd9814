//! `Lens` (an Optotune Lens Driver 4 on a serial port, a context manager) and
//! `VirtualLens` (the simulated device on a pseudo-terminal), from `etl_hw`.
//!
//! Every I/O call releases the GIL. Timeouts raise `DeviceTimeoutError`, other device and
//! port failures `DeviceError`, bad arguments (NaN) `InputError`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, TryLockError};
use std::time::Duration;

use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::hold::{duration_from_s, hold, HoldConfig, HoldError, HoldStep};
use etl_hw::virtual_lens::{Faults, VirtualLens as Device, VirtualLensConfig};
use etl_hw::HwError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use etl_core::lens::LensError as _;
use etl_formats::compact;

use crate::errors::{invalid, invalid_value, lens_kind, raise, Kind};
use crate::results::fields_object;
use crate::thermal::ThermalCalibration;

/// `t_c` if the lens temperature sensor can read it (-40..=125 degC), else InputError
/// naming `what`: the virtual lens models no temperature its sensor could not report.
fn sensor_range(what: &str, t_c: f64) -> PyResult<f64> {
    let [lo, hi] = etl_hw::codec::scaling::SENSOR_RANGE_C;
    if (lo..=hi).contains(&t_c) {
        Ok(t_c)
    } else {
        Err(invalid_value(what, t_c, format!("{what} must lie in -40..=125 degC, got {}", compact(t_c))))
    }
}

fn hw_err(e: HwError) -> PyErr {
    match &e {
        // Refused input (its class, InputError, from the lens's kind): name it.
        HwError::Core(c) => {
            let (what, value) = etl_formats::Error::core_input(c);
            crate::errors::input_error_about(e.to_string(), what, value.as_deref())
        }
        _ => raise(lens_kind(e.kind()), e.to_string()),
    }
}

/// A lens on an Optotune Lens Driver 4 (USB serial port), or on a `VirtualLens`'s port.
///
/// Args:
///     port: the serial port path (e.g. "/dev/ttyACM0", or `VirtualLens().port`).
///     handshake: send the `Start` handshake (it zeroes the current); leave False to attach
///         to a lens in use without losing its focus.
///     timeout_ms: deadline of each reply, 1..=60000 ms.
///
/// After a DeviceTimeoutError the next call first resynchronises the line (a late reply
/// is discarded, never taken for a later answer); `set_current_ma` confirms the current by
/// reading it back, so a current the driver rejects raises DeviceError (naming `Aw`).
///
/// The current never leaves the driver's limits: out-of-range requests are clamped (the
/// returned value says what was commanded), NaN raises InputError. Use as a context manager
/// (`with etlcal.Lens(port) as lens:`) or call `close()`.
#[pyclass(module = "etlcal")]
pub struct Lens {
    /// `None` once closed. Every call takes the lock for its own length ([`Lens::call`]);
    /// a procedure for its whole run ([`Lens::procedure`]).
    client: Mutex<Option<LensClient>>,
    /// Set while a procedure (`hold`, `thermal_calibration`) runs: a call from another
    /// thread meanwhile is refused at once instead of waiting for the end of the run.
    busy: AtomicBool,
}

/// The thread rule, said by every refusal of a busy lens.
const BUSY: &str = "the lens is busy: Lens.hold or thermal_calibration runs on another thread, and a Lens \
    serves one procedure at a time (other calls wait for a call in progress, not for a procedure)";

/// A lens held by a procedure: the lock, and the busy flag cleared when it is dropped.
pub(crate) struct Procedure<'a> {
    guard: MutexGuard<'a, Option<LensClient>>,
    busy: &'a AtomicBool,
}

impl Procedure<'_> {
    /// The open client. Errors: the lens is closed.
    pub(crate) fn client_mut(&mut self) -> PyResult<&mut LensClient> {
        self.guard.as_mut().ok_or_else(|| raise(Kind::Device, "the lens is closed"))
    }
}

impl Drop for Procedure<'_> {
    fn drop(&mut self) {
        self.busy.store(false, Ordering::Release);
    }
}

impl Lens {
    fn from_client(client: LensClient) -> Self {
        Lens { client: Mutex::new(Some(client)), busy: AtomicBool::new(false) }
    }

    /// The lock, waited for with the GIL released (a thread holding the lock may need the
    /// GIL to finish), unless a procedure runs (a DeviceError saying the thread rule).
    fn lock(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, Option<LensClient>>> {
        self.wait_for_lock(py, true)
    }

    /// The lock, polled with the GIL released between tries; while a procedure holds the
    /// lens, refused if `refuse_while_busy` (a call), else waited for (the procedure
    /// itself, which has set the flag). A poisoned lock is taken as it is: the client's own
    /// state survives a panic.
    fn wait_for_lock(&self, py: Python<'_>, refuse_while_busy: bool) -> PyResult<MutexGuard<'_, Option<LensClient>>> {
        loop {
            if refuse_while_busy && self.busy.load(Ordering::Acquire) {
                return Err(raise(Kind::Device, BUSY));
            }
            match self.client.try_lock() {
                Ok(g) => return Ok(g),
                Err(TryLockError::Poisoned(p)) => return Ok(p.into_inner()),
                Err(TryLockError::WouldBlock) => py.detach(|| std::thread::sleep(Duration::from_micros(200))),
            }
        }
    }

    /// Runs `f` on the open client with the GIL released, the lens locked for the call.
    fn call<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&LensClient) -> R + Send) -> PyResult<R> {
        let guard = self.lock(py)?;
        let c = guard.as_ref().ok_or_else(|| raise(Kind::Device, "the lens is closed"))?;
        Ok(py.detach(|| f(c)))
    }

    /// The lens for a procedure that drives it for a while (`hold`, `thermal_calibration`):
    /// refused while another procedure runs; waits for a call in progress.
    pub(crate) fn procedure(&self, py: Python<'_>) -> PyResult<Procedure<'_>> {
        if self.busy.compare_exchange(false, true, Ordering::AcqRel, Ordering::Acquire).is_err() {
            return Err(raise(Kind::Device, BUSY));
        }
        // The flag is set first, so a call that starts meanwhile is refused.
        match self.wait_for_lock(py, false) {
            Ok(guard) => Ok(Procedure { guard, busy: &self.busy }),
            Err(e) => {
                self.busy.store(false, Ordering::Release);
                Err(e)
            }
        }
    }
}

/// The hold's error with its own message ("lens: ..." / "compensation: ..."), the class
/// from what failed.
fn hold_err(e: HoldError<HwError>) -> PyErr {
    match &e {
        HoldError::Lens(l) => raise(lens_kind(l.kind()), e.to_string()),
        HoldError::Core(c) => {
            let (what, value) = etl_formats::Error::core_input(c);
            crate::errors::input_error_about(e.to_string(), what, value.as_deref())
        }
        // The wanted E_com is beyond what the driver's limits give: the caller's input.
        HoldError::Unreachable { e_com_ma, .. } => invalid_value("e_com_ma", *e_com_ma, e.to_string()),
    }
}

/// One step of a hold as an `etlcal.results.HoldStep`.
fn step_object<'py>(py: Python<'py>, s: &HoldStep) -> PyResult<Bound<'py, PyAny>> {
    fields_object!(py, "HoldStep", s, [index, temperature_c, e_in_ma, e_com_ma, error_ma, extrapolated])
}

#[pymethods]
impl Lens {
    #[new]
    #[pyo3(signature = (port, handshake=false, timeout_ms=500))]
    fn new(py: Python<'_>, port: std::path::PathBuf, handshake: bool, timeout_ms: u64) -> PyResult<Self> {
        crate::errors::guarded("Lens.__new__", || {
            let options =
                OpenOptions { handshake, timeout: Duration::from_millis(timeout_ms), ..OpenOptions::default() };
            let client = py.detach(|| LensClient::open(&port, options)).map_err(hw_err)?;
            Ok(Lens::from_client(client))
        })
    }

    /// Firmware, lens serial, limits and temperature: a LensInfo (attributes, also dict
    /// keys) with `firmware_type`, `firmware_version`, `lens_serial`, `max_current_ma`,
    /// `upper_limit_ma`, `lower_limit_ma` (mA) and `temperature_c` (degC, None without a
    /// sensor).
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (info, t) = self.call(py, |c| (c.identify(), c.temperature_c().ok()))?;
        let info = info.map_err(hw_err)?;
        let d = PyDict::new(py);
        d.set_item("firmware_type", info.firmware_type.letter().to_string())?;
        d.set_item("firmware_version", info.firmware_version)?;
        d.set_item("lens_serial", info.lens_serial)?;
        d.set_item("max_current_ma", info.max_current_ma)?;
        d.set_item("upper_limit_ma", info.upper_limit_ma)?;
        d.set_item("lower_limit_ma", info.lower_limit_ma)?;
        d.set_item("temperature_c", t)?;
        crate::results::make(py, "LensInfo", &d)
    }

    /// Commands the driver current, mA (clamped to the limits); returns the current
    /// actually commanded (after clamping and the driver's 12-bit quantisation), mA.
    fn set_current_ma(&self, py: Python<'_>, e_in_ma: f64) -> PyResult<f64> {
        Ok(self.call(py, |c| c.set_current_ma(e_in_ma))?.map_err(hw_err)?.commanded_ma)
    }

    /// The driver current, mA.
    fn current_ma(&self, py: Python<'_>) -> PyResult<f64> {
        self.call(py, |c| c.current_ma())?.map_err(hw_err)
    }

    /// The lens temperature, degC (the lens's own sensor).
    fn temperature_c(&self, py: Python<'_>) -> PyResult<f64> {
        self.call(py, |c| c.temperature_c())?.map_err(hw_err)
    }

    /// The driver's software limits [lower, upper], mA.
    #[getter]
    fn limits_ma(&self, py: Python<'_>) -> PyResult<(f64, f64)> {
        let [lo, hi] = self.call(py, |c| c.limits_ma())?;
        Ok((lo, hi))
    }

    /// The serial port's path.
    #[getter]
    fn port(&self, py: Python<'_>) -> PyResult<String> {
        self.call(py, |c| c.path().display().to_string())
    }

    /// Reopens the port at the same path without the handshake (the lens keeps its
    /// current) and re-reads the limits: after a DeviceError from a pulled cable.
    fn reconnect(&self, py: Python<'_>) -> PyResult<()> {
        self.call(py, |c| c.reconnect())?.map_err(hw_err)
    }

    /// Live temperature compensation (paper section 2.2.1 iii): holds a wanted E_com while
    /// the lens temperature changes. Each step reads T, solves E_in - E_T(T, E_in) = E_com
    /// for E_in (the calibration's inverse) and sends it. Runs without the GIL; `on_step`,
    /// if given, is called with the GIL after each step.
    ///
    /// Args:
    ///     calibration: a `ThermalCalibration` (its surface and ranges).
    ///     e_com_ma: the compensated current to hold, mA.
    ///     steps: stop after this many steps (None: by `duration_s` or `on_step`).
    ///     duration_s: stop after this long, 0..=1e7 s (None: by `steps` or `on_step`).
    ///     rate_hz: steps per second, Hz: 0 for as fast as the link allows, else
    ///         0.001..=10000.
    ///     on_step: callable(HoldStep) -> bool | None, given each step (attributes, also
    ///         dict keys): `index`, `temperature_c`, `e_in_ma`, `e_com_ma` (the surface's
    ///         E_com at the commanded current), `error_ma` (quantisation and clamping),
    ///         `extrapolated`; returning False stops the loop.
    ///
    /// Returns: a HoldReport (attributes, also dict keys): `commands_sent`, `elapsed_s`,
    /// `achieved_rate_hz`, `worst_e_com_error_ma`, `temperature_range_c` (min, max),
    /// `extrapolated_steps`, `last` (the last HoldStep or None).
    ///
    /// Raises: InputError for a non-finite E_com, a rate or duration outside its range, no
    /// stopping rule, an E_com the surface cannot reach at the temperature read, or one
    /// whose current lies beyond the driver's limits (after that one clamped command); DeviceError /
    /// DeviceTimeoutError from the link; `on_step`'s own exception as it is (also
    /// KeyboardInterrupt).
    #[pyo3(signature = (calibration, e_com_ma, steps=None, duration_s=None, rate_hz=0.0, on_step=None))]
    #[allow(clippy::too_many_arguments)]
    fn hold<'py>(
        &self,
        py: Python<'py>,
        calibration: PyRef<'py, ThermalCalibration>,
        e_com_ma: f64,
        steps: Option<u64>,
        duration_s: Option<f64>,
        rate_hz: f64,
        on_step: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if steps.is_none() && duration_s.is_none() && on_step.is_none() {
            return Err(invalid("steps", "hold needs steps, duration_s or on_step to stop"));
        }
        if steps == Some(0) {
            return Err(invalid_value("steps", 0_u64, "hold steps must be >= 1"));
        }
        let duration = match duration_s.map(|d| (d, duration_from_s(d))) {
            Some((_, Ok(d))) => Some(d),
            Some((d, Err(_))) => {
                return Err(invalid_value(
                    "duration_s",
                    d,
                    format!("duration_s must lie in 0..=1e7 s, got {}", compact(d)),
                ))
            }
            None => None,
        };
        let config = HoldConfig { e_com_ma, rate_hz, duration };
        let cal = calibration.inner;
        let mut lens = self.procedure(py)?;
        let client = lens.client_mut()?;
        let mut raised: Option<PyErr> = None;
        let report = py.detach(|| {
            hold(client, &cal, &config, |s| {
                if steps.is_some_and(|n| s.index + 1 >= n) {
                    return false;
                }
                let Some(f) = &on_step else { return true };
                Python::attach(|py| {
                    let go = py.check_signals().and_then(|_| {
                        let r = f.call1(py, (step_object(py, s)?,))?;
                        Ok(r.is_none(py) || r.is_truthy(py)?)
                    });
                    go.unwrap_or_else(|e| {
                        raised = Some(e);
                        false
                    })
                })
            })
        });
        if let Some(e) = raised {
            return Err(e);
        }
        let r = report.map_err(hold_err)?;
        let d = PyDict::new(py);
        d.set_item("commands_sent", r.commands_sent)?;
        d.set_item("elapsed_s", r.elapsed.as_secs_f64())?;
        d.set_item("achieved_rate_hz", r.achieved_rate_hz)?;
        d.set_item("worst_e_com_error_ma", r.worst_e_com_error_ma)?;
        d.set_item("temperature_range_c", (r.temperature_range_c[0], r.temperature_range_c[1]))?;
        d.set_item("extrapolated_steps", r.extrapolated_steps)?;
        match &r.last {
            Some(s) => d.set_item("last", step_object(py, s)?)?,
            None => d.set_item("last", py.None())?,
        }
        crate::results::make(py, "HoldReport", &d)
    }

    /// Closes the port (the lens keeps its current).
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        *self.lock(py)? = None;
        Ok(())
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyResult<PyRef<'_, Self>> {
        crate::errors::guarded_value("Lens.__enter__", || slf)
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        crate::errors::guarded("Lens.__exit__", || {
            self.close(py)?;
            Ok(false)
        })
    }
}

/// A simulated lens and driver speaking the Lens Driver 4 protocol on a pseudo-terminal:
/// the paper's physics at E_com = E_in - E_T(T, E_in) (the paper's surface), a thermal
/// model (ambient 25 degC, coil heating, a heater), the sensor quantised to 1/16 degC.
/// Open it with `Lens(virtual_lens.port)`. It serves until garbage-collected. Usable from
/// any thread (its state is behind a lock).
#[pyclass(module = "etlcal")]
pub struct VirtualLens {
    device: Device,
}

#[pymethods]
impl VirtualLens {
    /// `dynamics`: the path of an `etlcal.lens-dynamics/1` file (the membrane's step
    /// response, creep, hysteresis and self-heating; `fixtures/lens-dynamics` has the
    /// published EL-10-30's); None: the optics follow the current at once.
    #[new]
    #[pyo3(signature = (dynamics=None))]
    fn new(dynamics: Option<std::path::PathBuf>) -> PyResult<Self> {
        crate::errors::guarded("VirtualLens.__new__", || {
            use crate::errors::CoreResultExt as _;
            let dynamics = match dynamics {
                Some(path) => Some(etl_formats::LensDynamicsFile::load(&path).py()?.dynamics()),
                None => None,
            };
            let device =
                Device::spawn(VirtualLensConfig { dynamics, ..VirtualLensConfig::default() }).map_err(hw_err)?;
            Ok(VirtualLens { device })
        })
    }

    /// The pseudo-terminal's path (pass it to `Lens`).
    #[getter]
    fn port(&self) -> String {
        self.device.path().display().to_string()
    }

    /// The true state: a LensState (attributes, also dict keys) with `e_in_ma` (the
    /// current the driver outputs), `effective_ma` (the current the optics follow: with
    /// dynamics, where the membrane has got to), `temperature_c` (the true lens
    /// temperature, degC), `e_t_ma`, `e_com_ma` (mA, of the effective current) and
    /// `f_com_mm` (the ETL group's focal length f_com(E_com), Eq. 10, mm).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.device.state();
        fields_object!(py, "LensState", s, [e_in_ma, effective_ma, temperature_c, e_t_ma, e_com_ma, f_com_mm])
    }

    /// Heats the mount so that the lens settles at `t_c` degC, and jumps to equilibrium.
    /// `t_c` within the lens sensor's -40..=125 degC (InputError otherwise).
    fn set_temperature_c(&self, t_c: f64) -> PyResult<()> {
        sensor_range("t_c", t_c)?;
        self.device.set_target_temperature_c(t_c);
        self.device.settle();
        Ok(())
    }

    /// Every current code the device received, in order (the wire's truth; +-4095 is
    /// +-`limits_ma`).
    fn received_current_codes(&self) -> Vec<i16> {
        self.device.received().current_codes
    }

    /// The driver's software limits [lower, upper], mA.
    #[getter]
    fn limits_ma(&self) -> (f64, f64) {
        let [lo, hi] = self.device.limits_ma();
        (lo, hi)
    }

    /// Sets the ambient temperature, degC (the lens drifts towards the new equilibrium
    /// in model time; see `advance_s`).
    fn set_ambient_c(&self, t_c: f64) -> PyResult<()> {
        sensor_range("t_c", t_c)?;
        self.device.set_ambient_c(t_c);
        Ok(())
    }

    /// Advances the thermal model by `dt_s` model seconds at once, s: 0..=1e7 s (the
    /// longest hold; InputError otherwise).
    fn advance_s(&self, dt_s: f64) -> PyResult<()> {
        if !(0.0..=etl_hw::hold::MAX_DURATION_S).contains(&dt_s) {
            return Err(invalid_value("dt_s", dt_s, format!("dt_s must lie in 0..=1e7 s, got {}", compact(dt_s))));
        }
        self.device.advance_s(dt_s);
        Ok(())
    }

    /// Injects faults into the link (replacing any before; all off by default): what a
    /// flaky cable, a busy driver or a firmware quirk does to the byte stream.
    ///
    /// Args:
    ///     reply_delay_ms: every reply is sent this long after its command, 0..=60000 ms.
    ///     silence_next: the next N replies are never sent (the command is executed).
    ///     corrupt_next: the next N replies have a CRC byte flipped.
    ///     crc_error_next: the next N commands are treated as failing their CRC.
    ///     error_frame_next: the next command is answered with the error frame `E` + id
    ///         (1 CRC, 2 not in this firmware, 3 unknown command, 4 lens incompatible).
    ///     drop_rx_bytes_next: the next N bytes the host sends are lost.
    ///     garbage_before_next: bytes sent once before the next reply.
    #[pyo3(signature = (reply_delay_ms=0.0, silence_next=0, corrupt_next=0, crc_error_next=0, error_frame_next=None,
        drop_rx_bytes_next=0, garbage_before_next=Vec::new()),
        text_signature = "($self, reply_delay_ms=0.0, silence_next=0, corrupt_next=0, crc_error_next=0, \
            error_frame_next=None, drop_rx_bytes_next=0, garbage_before_next=b'')")]
    #[allow(clippy::too_many_arguments)]
    fn inject_faults(
        &self,
        reply_delay_ms: f64,
        silence_next: u32,
        corrupt_next: u32,
        crc_error_next: u32,
        error_frame_next: Option<u8>,
        drop_rx_bytes_next: u32,
        garbage_before_next: Vec<u8>,
    ) -> PyResult<()> {
        let reply_delay = Faults::reply_delay_from_ms(reply_delay_ms).map_err(|_| {
            let message = format!("reply_delay_ms must lie in 0..=60000 ms, got {}", compact(reply_delay_ms));
            invalid_value("reply_delay_ms", reply_delay_ms, message)
        })?;
        self.device.set_faults(Faults {
            reply_delay,
            silence_next,
            corrupt_next,
            garbage_before_next,
            crc_error_next,
            error_frame_next,
            drop_rx_bytes_next,
        });
        Ok(())
    }

    /// Pulls the cable: closes the pseudo-terminal; the client's next I/O fails with
    /// DeviceError.
    fn disconnect(&self) {
        self.device.disconnect();
    }

    /// Plugs the cable back in (a new pseudo-terminal behind the same `port`); the lens
    /// keeps its current and temperature. Then call `Lens.reconnect()`.
    fn reconnect(&self) -> PyResult<()> {
        self.device.reconnect().map_err(hw_err)
    }
}
