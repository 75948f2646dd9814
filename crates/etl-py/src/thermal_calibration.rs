//! `thermal_calibration(...)`: the paper's temperature-calibration procedure (section 4.1,
//! Fig. 4) on a real rig, with the camera and the climate chamber as Python callables and
//! the lens a [`Lens`].

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::lens::Lens;

/// Keeps the first Python exception of a callable (re-raised as it is after the run) and
/// gives the procedure an error that stops it.
/// `callable` names the argument (`capture`, `place_board`, `set_temperature`).
fn keep(raised: &mut Option<PyErr>, callable: &str, e: PyErr) -> etl_calib::Error {
    let msg = e.to_string();
    raised.get_or_insert(e);
    etl_calib::Error::invalid(callable, format!("a Python callable raised: {msg}"))
}

/// The procedure's camera as Python callables.
struct PyCamera<'py> {
    capture: Bound<'py, PyAny>,
    place_board: Option<Bound<'py, PyAny>>,
    raised: Option<PyErr>,
}

impl etl_calib::thermal_calibration::Camera for PyCamera<'_> {
    fn capture(&mut self) -> etl_calib::Result<image::GrayImage> {
        let frame = self.capture.call0().map_err(|e| keep(&mut self.raised, "capture", e))?;
        let pixels = etl_formats::observations::MAX_IMAGE_PIXELS as usize;
        crate::arrays::refuse_oversized(&frame, "capture()", pixels)
            .map_err(|e| keep(&mut self.raised, "capture", e))?;
        let arr = frame
            .extract::<numpy::PyReadonlyArray2<'_, u8>>()
            .map_err(|_| etl_calib::Error::invalid("capture", "capture() must return a 2-D uint8 numpy array"))?;
        let (h, w) = {
            use numpy::PyUntypedArrayMethods;
            (arr.shape()[0], arr.shape()[1])
        };
        let data: Vec<u8> = arr.as_array().iter().copied().collect();
        image::GrayImage::from_raw(w as u32, h as u32, data)
            .ok_or_else(|| etl_calib::Error::invalid("capture", "capture() returned an inconsistent array"))
    }

    fn place_board_in_focus(&mut self) -> etl_calib::Result<()> {
        if let Some(f) = &self.place_board {
            f.call0().map_err(|e| keep(&mut self.raised, "place_board", e))?;
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
        self.set_temperature.call1((t_c,)).map_err(|e| keep(&mut self.raised, "set_temperature", e))?;
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
    lens: PyRef<'py, Lens>,
    capture: Bound<'py, PyAny>,
    set_temperature: Bound<'py, PyAny>,
    place_board: Option<Bound<'py, PyAny>>,
    e_in_grid_ma: Option<Vec<f64>>,
    temperatures_c: Option<Vec<f64>>,
    search_ma: f64,
    metric: &str,
) -> PyResult<Bound<'py, PyAny>> {
    use crate::errors::CoreResultExt;
    use etl_calib::thermal_calibration::{run_procedure, ProcedureOptions};
    let mut options = ProcedureOptions {
        search_half_width_ma: search_ma,
        metric: metric.parse::<etl_image::sharpness::Metric>().py()?,
        ..ProcedureOptions::default()
    };
    if let Some(g) = e_in_grid_ma {
        options.e_in_grid_ma = g;
    }
    if let Some(t) = temperatures_c {
        options.temperatures_c = t;
    }
    let mut held = lens.procedure(py)?;
    let client = held.client_mut()?;
    // The camera and climate are Python callables: the procedure runs with the GIL held.
    let mut camera = PyCamera { capture, place_board, raised: None };
    let mut climate = PyClimate { set_temperature, raised: None };
    let result = run_procedure(client, &mut camera, &mut climate, &options, &etl_core::progress::NoProgress);
    if let Some(e) = camera.raised.take().or(climate.raised.take()) {
        return Err(e);
    }
    // The option the user sets is the argument `search_ma`.
    let result = result.map_err(|e| e.map_what(|w| if w == "search_half_width_ma" { "search_ma".into() } else { w }));
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
    crate::results::make(py, "ThermalCalibrationResult", &d)
}
