//! `ThermalSurface` and `ThermalCalibration`: temperature compensation (paper Eq. 7-8,
//! section 5.2.2) and its fit.
//!
//! Argument order in Python is current first, temperature second, as in
//! `Calibration.e_com(e_in_ma, temperature_c)`.

use std::path::PathBuf;

use etl_core::thermal::{
    Compensation, ThermalCalibration as CoreThermalCal, ThermalFit, ThermalSurface as CoreSurface,
};
use etl_formats::thermal::ThermalFile;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::arrays::{broadcast2, map2, stacked, vec_out, Broadcast2};
use crate::errors::{input_error, invalid, CoreResultExt};
use crate::results::fields_object;

/// The cubic surface E_T(T, E_in) of the paper (section 5.2.2), in mA.
///
/// E_T = c0 + c1 T + c2 E + c3 T^2 + c4 T E + c5 E^2 + c6 T^3 + c7 T^2 E + c8 T E^2 + c9 E^3
/// with T in degC and E = E_in in mA; the compensated current is E_com = E_in - E_T (Eq. 8).
///
/// Args:
///     coefficients: the ten c_k in the order above (mA, degC).
///
/// Every method refuses a temperature outside [-40, 125] degC or a current outside the
/// driver's +-292.84 mA with `InputError` (a kelvin or an ampere passed by mistake).
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct ThermalSurface {
    pub(crate) inner: CoreSurface,
}

#[pymethods]
impl ThermalSurface {
    #[new]
    fn new(coefficients: &Bound<'_, PyAny>) -> PyResult<Self> {
        crate::errors::guarded("ThermalSurface.__new__", || {
            let c = crate::arrays::fixed::<10>(coefficients, "coefficients")?;
            let inner = CoreSurface { coefficients: c };
            inner.validate().py()?;
            Ok(ThermalSurface { inner })
        })
    }

    /// The paper's fitted surface (section 5.2.2; RMSE 0.2106 mA).
    #[staticmethod]
    fn paper() -> Self {
        ThermalSurface { inner: CoreSurface::PAPER }
    }

    /// The ten coefficients c0..c9 (float64 array; mA, degC).
    #[getter]
    fn coefficients<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.inner.coefficients)
    }

    /// E_T(T, E_in) in mA (Eq. 7).
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast with e_in_ma).
    ///
    /// Returns: E_T in mA (a float, or an array of the broadcast shape).
    fn e_t<'py>(&self, e_in_ma: &Bound<'py, PyAny>, temperature_c: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.inner;
        map2(e_in_ma, temperature_c, ("e_in_ma", "temperature_c"), |e, t| s.e_t_ma(e, t).py())
    }

    /// E_com = E_in - E_T(T, E_in) in mA (Eq. 8): the current the camera model is indexed by.
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast with e_in_ma).
    fn e_com<'py>(
        &self,
        e_in_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let s = self.inner;
        map2(e_in_ma, temperature_c, ("e_in_ma", "temperature_c"), |e, t| s.e_com_ma(e, t).py())
    }

    /// The driver current E_in (mA) that gives `e_com_ma` at `temperature_c` (the inverse
    /// of `e_com`, to 1e-9 mA).
    ///
    /// Args:
    ///     e_com_ma: wanted compensated current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    fn e_in_for_e_com<'py>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let s = self.inner;
        map2(e_com_ma, temperature_c, ("e_com_ma", "temperature_c"), |e, t| s.e_in_for_e_com(e, t).py())
    }

    /// Least-squares fit of the surface to measured E_T (section 4.1 procedure).
    ///
    /// Args:
    ///     e_in_ma: driver currents of the samples, mA (1-D array).
    ///     temperature_c: temperatures of the samples, degC (same length).
    ///     e_t_ma: measured E_T (refocused E_in - original E_in), mA (same length).
    ///     weights: optional weight per sample (>= 0, e.g. 1 / variance in 1/mA^2).
    ///
    /// Returns: a `ThermalCalibration` (surface, RMS of the residuals in mA, the ranges
    /// of the samples).
    ///
    /// Raises: InputError for fewer than 10 samples, fewer than 4 distinct temperatures
    /// or currents, samples on a line, NaN or out-of-domain values.
    #[staticmethod]
    #[pyo3(signature = (e_in_ma, temperature_c, e_t_ma, weights=None))]
    fn fit(
        py: Python<'_>,
        e_in_ma: &Bound<'_, PyAny>,
        temperature_c: &Bound<'_, PyAny>,
        e_t_ma: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<ThermalCalibration> {
        let e = column(e_in_ma, "e_in_ma")?;
        let t = column(temperature_c, "temperature_c")?;
        let y = column(e_t_ma, "e_t_ma")?;
        let w = match weights {
            Some(w) => column(w, "weights")?,
            None => vec![1.0; e.len()],
        };
        if t.len() != e.len() || y.len() != e.len() || w.len() != e.len() {
            return Err(input_error(format!(
                "e_in_ma, temperature_c, e_t_ma and weights must have the same length, got {}, {}, {}, {}",
                e.len(),
                t.len(),
                y.len(),
                w.len()
            )));
        }
        let (cal, rms) = crate::pool::detach(py, || {
            let mut fit = ThermalFit::new();
            for i in 0..e.len() {
                fit.add_weighted(e[i], t[i], y[i], w[i])?;
            }
            fit.solve_calibration()
        })
        .py()?;
        Ok(ThermalCalibration { inner: cal, rms_ma: rms })
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("ThermalSurface.__repr__", || {
            format!("ThermalSurface({:?})", self.inner.coefficients)
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("ThermalSurface.__reduce__", || {
            let py = slf.py();
            let c = slf.get().inner.coefficients.to_vec();
            Ok((py.get_type::<ThermalSurface>().into_any(), PyTuple::new(py, [c])?))
        })
    }
}

/// A 1-D float column of an array-like.
pub(crate) fn column(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let obj = crate::arrays::real_array(obj, what, crate::arrays::MAX_ARRAY_NUMBERS)?;
    let arr: numpy::PyArrayLikeDyn<'_, f64, numpy::AllowTypeChange> =
        obj.extract().map_err(|e| invalid(what, format!("{what} must be a 1-D array of numbers: {e}")))?;
    use numpy::PyUntypedArrayMethods;
    if arr.ndim() != 1 {
        return Err(invalid(what, format!("{what} must be a 1-D array, got shape {:?}", arr.shape())));
    }
    Ok(arr.as_array().iter().copied().collect())
}

/// A fitted `ThermalSurface` with the ranges it was fitted over and the RMS of its fit:
/// the content of an `etlcal.thermal/1` file.
///
/// Outside the calibrated ranges (but inside the lens's domain) `compensate` and
/// `e_in_for_e_com` still answer and flag the result as extrapolated (so a controller
/// keeps running and can warn); outside the domain they raise InputError.
///
/// Args:
///     surface: the surface.
///     e_in_range_ma: (min, max) driver current of the fitted samples, mA (keyword only).
///     t_range_c: (min, max) temperature of the fitted samples, degC (keyword only).
///     rms_ma: RMS of the fit residuals, mA (>= 0).
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct ThermalCalibration {
    pub(crate) inner: CoreThermalCal,
    pub(crate) rms_ma: f64,
}

impl ThermalCalibration {
    fn file(&self) -> ThermalFile {
        ThermalFile::new(&self.inner, self.rms_ma)
    }
}

#[pymethods]
impl ThermalCalibration {
    #[new]
    // The two ranges are keyword-only: they are both pairs of floats, and a call written for
    // the old positional order (t_range_c first) must fail loudly, not swap them silently.
    #[pyo3(signature = (surface, *, e_in_range_ma, t_range_c, rms_ma=0.0))]
    fn new(surface: ThermalSurface, e_in_range_ma: (f64, f64), t_range_c: (f64, f64), rms_ma: f64) -> PyResult<Self> {
        crate::errors::guarded("ThermalCalibration.__new__", || {
            let c = ThermalCalibration {
                inner: CoreThermalCal {
                    surface: surface.inner,
                    t_range_c: [t_range_c.0, t_range_c.1],
                    e_in_range_ma: [e_in_range_ma.0, e_in_range_ma.1],
                },
                rms_ma,
            };
            c.file().validate(std::path::Path::new("<ThermalCalibration>")).py()?;
            Ok(c)
        })
    }

    /// The paper's surface over the paper's procedure (27..37 degC, 40..240 mA; RMS
    /// 0.2106 mA).
    #[staticmethod]
    fn paper() -> Self {
        ThermalCalibration { inner: CoreThermalCal::PAPER, rms_ma: 0.2106 }
    }

    /// Reads an `etlcal.thermal/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        let f = ThermalFile::load(&path).py()?;
        Ok(ThermalCalibration { inner: f.calibration(), rms_ma: f.rms_ma })
    }

    /// Writes the calibration as an `etlcal.thermal/1` file (atomically).
    ///
    /// Args:
    ///     path: the file (str or os.PathLike); its directory must exist.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.file().save(&path).py()
    }

    /// The `etlcal.thermal/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.file()).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.thermal/1` JSON text.
    ///
    /// Args:
    ///     text: the JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let p = std::path::Path::new("<json>");
        let f: ThermalFile = etl_formats::parse_json(text, p, etl_formats::thermal::THERMAL_FORMAT).py()?;
        f.validate(p).py()?;
        Ok(ThermalCalibration { inner: f.calibration(), rms_ma: f.rms_ma })
    }

    /// The surface.
    #[getter]
    fn surface(&self) -> ThermalSurface {
        ThermalSurface { inner: self.inner.surface }
    }

    /// (min, max) temperature of the fitted samples, degC.
    #[getter]
    fn t_range_c(&self) -> (f64, f64) {
        (self.inner.t_range_c[0], self.inner.t_range_c[1])
    }

    /// (min, max) driver current of the fitted samples, mA.
    #[getter]
    fn e_in_range_ma(&self) -> (f64, f64) {
        (self.inner.e_in_range_ma[0], self.inner.e_in_range_ma[1])
    }

    /// RMS of the fit residuals, mA.
    #[getter]
    fn rms_ma(&self) -> f64 {
        self.rms_ma
    }

    /// Compensates readings: E_T and E_com at driver current `e_in_ma` and temperature
    /// `temperature_c`.
    ///
    /// Out-of-range policy (per reading, as for one): outside the calibrated ranges but
    /// inside the lens's operating domain the result is returned with `extrapolated` True;
    /// outside the operating domain (T in [-40, 125] degC, E_in within the driver's
    /// +-292.84 mA) InputError, for the whole call when one reading of an array is.
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast with e_in_ma).
    ///
    /// Returns: for two numbers a Compensation (attributes, also dict keys): `e_in_ma`,
    /// `e_t_ma`, `e_com_ma` (mA) and `extrapolated` (True when outside the calibrated
    /// ranges); when either is an array a CompensationArray: the same fields as arrays of
    /// the broadcast shape (float64, `extrapolated` bool).
    fn compensate<'py>(
        &self,
        e_in_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let cal = self.inner;
        compensations(e_in_ma, temperature_c, ("e_in_ma", "temperature_c"), |e, t| cal.compensate(e, t).py())
    }

    /// The driver current that gives `e_com_ma` at `temperature_c` (the surface's inverse,
    /// to 1e-9 mA), flagged when outside the calibrated ranges.
    ///
    /// Out-of-range policy as `compensate` (the E_in found is checked against the
    /// calibrated E_in range).
    ///
    /// Args:
    ///     e_com_ma: wanted compensated current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast with e_com_ma).
    ///
    /// Returns: a Compensation or a CompensationArray, as `compensate`.
    fn e_in_for_e_com<'py>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let cal = self.inner;
        compensations(e_com_ma, temperature_c, ("e_com_ma", "temperature_c"), |e, t| cal.e_in_for_e_com(e, t).py())
    }

    /// Whether (E_in, T) lies inside the calibrated ranges.
    ///
    /// Args:
    ///     e_in_ma: driver current, mA.
    ///     temperature_c: lens temperature, degC.
    fn contains(&self, e_in_ma: f64, temperature_c: f64) -> bool {
        self.inner.contains(e_in_ma, temperature_c)
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("ThermalCalibration.__repr__", || {
            format!(
                "ThermalCalibration(e_in_range_ma={:?}, t_range_c={:?}, rms_ma={})",
                self.inner.e_in_range_ma, self.inner.t_range_c, self.rms_ma
            )
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("ThermalCalibration.__reduce__", || {
            let py = slf.py();
            let text = slf.get().to_json()?;
            let ctor = py.get_type::<ThermalCalibration>().getattr("from_json")?;
            Ok((ctor, PyTuple::new(py, [text])?))
        })
    }
}

/// `f` on two numbers (a `Compensation`) or elementwise over two broadcast arrays (a
/// `CompensationArray`; two 0-d arrays give a `Compensation`). Stops at the first error.
fn compensations<'py>(
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    what: (&str, &str),
    f: impl Fn(f64, f64) -> PyResult<Compensation>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = a.py();
    let (shape, x, y) = match broadcast2(a, b, what)? {
        Broadcast2::Scalar(x, y) => return compensation_object(py, &f(x, y)?),
        Broadcast2::Array { shape, x, y } if shape.is_empty() => {
            return compensation_object(py, &f(x[0], y[0])?);
        }
        Broadcast2::Array { shape, x, y } => (shape, x, y),
    };
    let all = x.iter().zip(&y).map(|(u, v)| f(*u, *v)).collect::<PyResult<Vec<Compensation>>>()?;
    let column = |g: fn(&Compensation) -> f64| stacked(py, &shape, &[], all.iter().map(g).collect());
    let flags = ArrayD::from_shape_vec(IxDyn(&shape), all.iter().map(|c| c.extrapolated).collect())
        .map_err(|e| input_error(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("e_in_ma", column(|c| c.e_in_ma)?)?;
    d.set_item("e_t_ma", column(|c| c.e_t_ma)?)?;
    d.set_item("e_com_ma", column(|c| c.e_com_ma)?)?;
    d.set_item("extrapolated", flags.into_pyarray(py))?;
    crate::results::make(py, "CompensationArray", &d)
}

/// One compensation as an `etlcal.results.Compensation`.
fn compensation_object<'py>(py: Python<'py>, c: &Compensation) -> PyResult<Bound<'py, PyAny>> {
    fields_object!(py, "Compensation", c, [e_in_ma, e_t_ma, e_com_ma, extrapolated])
}
