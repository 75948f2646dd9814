//! `Lens` (an Optotune Lens Driver 4 on a serial port, a context manager) and
//! `VirtualLens` (the simulated device on a pseudo-terminal), from `etl_hw`.
//!
//! Every I/O call releases the GIL. Timeouts raise `DeviceTimeoutError`, other device and
//! port failures `DeviceError`, bad arguments (NaN) `InputError`.

use std::time::Duration;

use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{VirtualLens as Device, VirtualLensConfig};
use etl_hw::HwError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{raise, Kind};

fn hw_err(e: HwError) -> PyErr {
    let kind = match &e {
        HwError::Timeout { .. } => Kind::DeviceTimeout,
        HwError::Core(_) => Kind::Input,
        _ => Kind::Device,
    };
    raise(kind, e.to_string())
}

/// A lens on an Optotune Lens Driver 4 (USB serial port), or on a `VirtualLens`'s port.
///
/// Args:
///     port: the serial port path (e.g. "/dev/ttyACM0", or `VirtualLens().port`).
///     handshake: send the `Start` handshake (it zeroes the current); leave False to attach
///         to a lens in use without losing its focus.
///     timeout_ms: deadline of each reply, ms.
///
/// The current never leaves the driver's limits: out-of-range requests are clamped (the
/// returned value says what was commanded), NaN raises InputError. Use as a context manager
/// (`with etlcal.Lens(port) as lens:`) or call `close()`.
#[pyclass(module = "etlcal")]
pub struct Lens {
    client: Option<LensClient>,
}

impl Lens {
    fn client(&self) -> PyResult<&LensClient> {
        self.client.as_ref().ok_or_else(|| raise(Kind::Device, "the lens is closed"))
    }
}

#[pymethods]
impl Lens {
    #[new]
    #[pyo3(signature = (port, handshake=false, timeout_ms=500))]
    fn new(py: Python<'_>, port: std::path::PathBuf, handshake: bool, timeout_ms: u64) -> PyResult<Self> {
        let options = OpenOptions { handshake, timeout: Duration::from_millis(timeout_ms), ..OpenOptions::default() };
        let client = py.detach(|| LensClient::open(&port, options)).map_err(hw_err)?;
        Ok(Lens { client: Some(client) })
    }

    /// Firmware, lens serial, limits and temperature: dict with "firmware_type",
    /// "firmware_version", "lens_serial", "max_current_ma", "upper_limit_ma",
    /// "lower_limit_ma", "temperature_c" (None without a sensor).
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.client()?;
        let info = py.detach(|| c.identify()).map_err(hw_err)?;
        let t = py.detach(|| c.temperature_c()).ok();
        let d = PyDict::new(py);
        d.set_item("firmware_type", info.firmware_type.letter().to_string())?;
        d.set_item("firmware_version", info.firmware_version)?;
        d.set_item("lens_serial", info.lens_serial)?;
        d.set_item("max_current_ma", info.max_current_ma)?;
        d.set_item("upper_limit_ma", info.upper_limit_ma)?;
        d.set_item("lower_limit_ma", info.lower_limit_ma)?;
        d.set_item("temperature_c", t)?;
        Ok(d)
    }

    /// Commands the driver current, mA (clamped to the limits); returns the current
    /// actually commanded (after clamping and the driver's 12-bit quantisation), mA.
    fn set_current_ma(&self, py: Python<'_>, e_in_ma: f64) -> PyResult<f64> {
        let c = self.client()?;
        Ok(py.detach(|| c.set_current_ma(e_in_ma)).map_err(hw_err)?.commanded_ma)
    }

    /// The driver current, mA.
    fn current_ma(&self, py: Python<'_>) -> PyResult<f64> {
        let c = self.client()?;
        py.detach(|| c.current_ma()).map_err(hw_err)
    }

    /// The lens temperature, degC (the lens's own sensor).
    fn temperature_c(&self, py: Python<'_>) -> PyResult<f64> {
        let c = self.client()?;
        py.detach(|| c.temperature_c()).map_err(hw_err)
    }

    /// The driver's software limits [lower, upper], mA.
    #[getter]
    fn limits_ma(&self) -> PyResult<(f64, f64)> {
        let [lo, hi] = self.client()?.limits_ma();
        Ok((lo, hi))
    }

    /// Closes the port (the lens keeps its current).
    fn close(&mut self) {
        self.client = None;
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&mut self, _args: &Bound<'_, pyo3::types::PyTuple>) -> bool {
        self.close();
        false
    }
}

/// A simulated lens and driver speaking the Lens Driver 4 protocol on a pseudo-terminal:
/// the paper's physics at E_com = E_in - E_T(T, E_in) (the paper's surface), a thermal
/// model (ambient 25 degC, coil heating, a heater), the sensor quantised to 1/16 degC.
/// Open it with `Lens(virtual_lens.port)`. It serves until garbage-collected.
#[pyclass(module = "etlcal", unsendable)]
pub struct VirtualLens {
    device: Device,
}

#[pymethods]
impl VirtualLens {
    #[new]
    fn new() -> PyResult<Self> {
        let device = Device::spawn(VirtualLensConfig::default()).map_err(hw_err)?;
        Ok(VirtualLens { device })
    }

    /// The pseudo-terminal's path (pass it to `Lens`).
    #[getter]
    fn port(&self) -> String {
        self.device.path().display().to_string()
    }

    /// The true state: dict with "e_in_ma", "temperature_c", "e_t_ma", "e_com_ma",
    /// "f_com_mm" (mm, mA, degC).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.device.state();
        let d = PyDict::new(py);
        d.set_item("e_in_ma", s.e_in_ma)?;
        d.set_item("temperature_c", s.temperature_c)?;
        d.set_item("e_t_ma", s.e_t_ma)?;
        d.set_item("e_com_ma", s.e_com_ma)?;
        d.set_item("f_com_mm", s.f_com_mm)?;
        Ok(d)
    }

    /// Heats the mount so that the lens settles at `t_c` degC, and jumps to equilibrium.
    fn set_temperature_c(&self, t_c: f64) {
        self.device.set_target_temperature_c(t_c);
        self.device.settle();
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
}
