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

/// Keeps the first Python exception of a callable (re-raised as it is after the run) and
/// gives the procedure an error that stops it.
fn keep(raised: &mut Option<PyErr>, e: PyErr) -> etl_calib::Error {
    let msg = e.to_string();
    raised.get_or_insert(e);
    etl_calib::Error::InvalidInput(format!("a Python callable raised: {msg}"))
}

/// The procedure's camera as Python callables.
struct PyCamera<'py> {
    capture: Bound<'py, PyAny>,
    place_board: Option<Bound<'py, PyAny>>,
    raised: Option<PyErr>,
}

impl etl_calib::thermal_calibration::Camera for PyCamera<'_> {
    fn capture(&mut self) -> etl_calib::Result<image::GrayImage> {
        let frame = self.capture.call0().map_err(|e| keep(&mut self.raised, e))?;
        let arr = frame
            .extract::<numpy::PyReadonlyArray2<'_, u8>>()
            .map_err(|_| etl_calib::Error::InvalidInput("capture() must return a 2-D uint8 numpy array".into()))?;
        let (h, w) = {
            use numpy::PyUntypedArrayMethods;
            (arr.shape()[0], arr.shape()[1])
        };
        let data: Vec<u8> = arr.as_array().iter().copied().collect();
        image::GrayImage::from_raw(w as u32, h as u32, data)
            .ok_or_else(|| etl_calib::Error::InvalidInput("capture() returned an inconsistent array".into()))
    }

    fn place_board_in_focus(&mut self) -> etl_calib::Result<()> {
        if let Some(f) = &self.place_board {
            f.call0().map_err(|e| keep(&mut self.raised, e))?;
        }
        Ok(())
    }
}

/// The procedure's climate as a Python callable.
struct PyClimate<'py> {
    set_temperature: Bound<'py, PyAny>,
    raised: Option<PyErr>,
}

impl etl_calib::thermal_calibration::Climate for PyClimate<'_> {
    fn set_temperature_c(&mut self, t_c: f64) -> etl_calib::Result<()> {
        self.set_temperature.call1((t_c,)).map_err(|e| keep(&mut self.raised, e))?;
        Ok(())
    }
}

/// The temperature-calibration procedure of the paper's section 4.1 (Fig. 4) on your rig:
/// for each driver current on the grid, place the board in focus at the first
/// temperature, then at every temperature step refocus by maximising sharpness and record
/// E_T = refocused E_in - the first one; fit the cubic surface (Eq. 7).
///
/// Args:
///     lens: an open `Lens`.
///     capture: callable () -> 2-D uint8 numpy array, a frame at the lens's present state.
///     set_temperature: callable (t_c) -> None that brings the lens to t_c degC and waits.
///     place_board: callable () -> None that puts the board in focus for the present
///         current (None: the board is already there).
///     e_in_grid_ma: driver currents, mA (default the paper's 40..240 by 20).
///     temperatures_c: temperature steps, degC, the first is the reference (default
///         27..37 by 1).
///     search_ma: half width of each refocus search, mA.
///     metric: sharpness measure ("tenengrad" by default; see `sharpness`).
///
/// Returns: dict with "calibration" (a `ThermalCalibration`), "rms_ma", "samples" (an
/// (N, 3) array of temperature_c, e_in_ma, e_t_ma) and "frames".
///
/// Raises: the callables' own exceptions as they are; InputError for bad options or a
/// refocus that ends at the edge of its window; DeviceError / DeviceTimeoutError.
#[pyfunction]
#[pyo3(signature = (lens, capture, set_temperature, place_board=None, e_in_grid_ma=None, temperatures_c=None,
    search_ma=20.0, metric="tenengrad"))]
#[allow(clippy::too_many_arguments)]
pub fn thermal_calibration<'py>(
    py: Python<'py>,
    mut lens: PyRefMut<'py, Lens>,
    capture: Bound<'py, PyAny>,
    set_temperature: Bound<'py, PyAny>,
    place_board: Option<Bound<'py, PyAny>>,
    e_in_grid_ma: Option<Vec<f64>>,
    temperatures_c: Option<Vec<f64>>,
    search_ma: f64,
    metric: &str,
) -> PyResult<Bound<'py, PyDict>> {
    use crate::errors::CoreResultExt;
    use etl_calib::thermal_calibration::{run_procedure, ProcedureOptions};
    let mut options = ProcedureOptions {
        search_half_width_ma: search_ma,
        metric: metric.parse::<etl_calib::sharpness::Metric>().py()?,
        ..ProcedureOptions::default()
    };
    if let Some(g) = e_in_grid_ma {
        options.e_in_grid_ma = g;
    }
    if let Some(t) = temperatures_c {
        options.temperatures_c = t;
    }
    let client = lens.client.as_mut().ok_or_else(|| raise(Kind::Device, "the lens is closed"))?;
    // The camera and climate are Python callables: the procedure runs with the GIL held.
    let mut camera = PyCamera { capture, place_board, raised: None };
    let mut climate = PyClimate { set_temperature, raised: None };
    let result = run_procedure(client, &mut camera, &mut climate, &options, false);
    if let Some(e) = camera.raised.take().or(climate.raised.take()) {
        return Err(e);
    }
    let r = result.py()?;
    let samples: Vec<[f64; 3]> = r.samples.iter().map(|s| [s.temperature_c, s.e_in_ma, s.e_t_ma]).collect();
    let d = PyDict::new(py);
    d.set_item(
        "calibration",
        Py::new(py, crate::thermal::ThermalCalibration { inner: r.calibration, rms_ma: r.rms_ma })?,
    )?;
    d.set_item("rms_ma", r.rms_ma)?;
    d.set_item("samples", crate::arrays::points_out(py, samples, false)?)?;
    d.set_item("frames", r.frames)?;
    Ok(d)
}
