//! `Observations` (`etlcal.observations/1`: the corners of the calibration views) and
//! `A0` (`etlcal.a0/1`: the lens-off intrinsics).

use std::path::{Path, PathBuf};

use etl_core::calib::A0 as CoreA0;
use etl_formats::a0::{A0File, FORMAT as A0_FORMAT};
use etl_formats::observations::{Observations as ObsFile, OffstateView, PointObs, ViewObs, FORMAT};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::arrays::{points, points_out};
use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};

/// Points of one view from (N, 3) world points and (N, 2) pixels.
fn view_points(world_mm: &Bound<'_, PyAny>, pixels: &Bound<'_, PyAny>) -> PyResult<Vec<PointObs>> {
    let w = points::<3>(world_mm, "world_mm")?;
    let p = points::<2>(pixels, "pixels")?;
    if w.single || p.single {
        return Err(invalid(
            if w.single { "world_mm" } else { "pixels" },
            "world_mm and pixels must be (N, 3) and (N, 2) arrays",
        ));
    }
    if w.points.len() != p.points.len() {
        return Err(invalid(
            "pixels",
            format!("world_mm and pixels differ in length: {} vs {}", w.points.len(), p.points.len()),
        ));
    }
    Ok(w.points.into_iter().zip(p.points).map(|(world_mm, pixel)| PointObs { world_mm, pixel }).collect())
}

fn points_dict<'py>(py: Python<'py>, pts: &[PointObs]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("world_mm", points_out(py, pts.iter().map(|p| p.world_mm).collect(), false)?)?;
    d.set_item("pixels", points_out(py, pts.iter().map(|p| p.pixel).collect(), false)?)?;
    Ok(d)
}

/// The corners of a calibration: per ETL view its driver current, lens temperature,
/// optional compensated current and the (world point, observed pixel) pairs; optional
/// lens-off views of a planar board (for A0). The content of an `etlcal.observations/1`
/// file.
///
/// Args:
///     image_size: (width, height) of the images, px.
#[pyclass(module = "etlcal", eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct Observations {
    pub(crate) file: ObsFile,
}

/// A view's setting as Python gives it: E_in, T, E_com, focal power (one of E_in and the
/// focal power).
type ViewSetting = (Option<f64>, Option<f64>, Option<f64>, Option<f64>);

impl Observations {
    /// Appends the view of points `world_mm`, `pixels` taken at `setting` (E_in, T, E_com)
    /// to the list `list` picks (ETL or per-setting views: the same arguments), keeping it
    /// only if the file still validates (checked in place so that the message names the
    /// view's index).
    fn push_checked(
        &mut self,
        list: impl Fn(&mut ObsFile) -> &mut Vec<ViewObs>,
        world_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        (e_in_ma, temperature_c, e_com_ma, focal_power_dpt): ViewSetting,
    ) -> PyResult<()> {
        let Some(temperature_c) = temperature_c else {
            return Err(input_error("give the lens temperature temperature_c, degC"));
        };
        if e_in_ma.is_some() == focal_power_dpt.is_some() {
            return Err(input_error("give exactly one of e_in_ma (mA) and focal_power_dpt (dpt)"));
        }
        if let Some(x) = e_in_ma.filter(|x| x.is_nan()) {
            // NaN stands for "no current" in the file's view: a NaN given is refused as
            // the number it is.
            let view = list(&mut self.file).len();
            let message = format!("view {view}: current or temperature is not finite");
            let e = etl_formats::Error::invalid_value(format!("views[{view}].e_in_ma"), x, message);
            return Err(crate::errors::calib_err(e));
        }
        let e_in_ma = e_in_ma.unwrap_or(f64::NAN);
        let points = view_points(world_mm, pixels)?;
        let v = ViewObs { e_in_ma, focal_power_dpt, temperature_c, e_com_ma, points };
        list(&mut self.file).push(v);
        if let Err(e) = self.file.validate() {
            list(&mut self.file).pop();
            return Err(crate::errors::calib_err(e));
        }
        Ok(())
    }
}

#[pymethods]
impl Observations {
    #[new]
    fn new(image_size: (u32, u32)) -> PyResult<Self> {
        crate::errors::guarded("Observations.__new__", || {
            etl_formats::check_image_size([image_size.0, image_size.1], "image_size").py()?;
            Ok(Observations { file: ObsFile::new([image_size.0, image_size.1]) })
        })
    }

    /// Builds observations from arrays, one entry per view.
    ///
    /// Args:
    ///     image_size: (width, height), px.
    ///     world_mm: per view an (N_j, 3) array of world points, mm.
    ///     pixels: per view an (N_j, 2) array of observed pixels, px.
    ///     e_in_ma: per view the driver current, mA.
    ///     temperature_c: per view the lens temperature, degC.
    ///     e_com_ma: per view the compensated current, mA (optional; when given it is
    ///         used as is, else it is computed through the thermal surface).
    #[staticmethod]
    #[pyo3(signature = (image_size, world_mm, pixels, e_in_ma, temperature_c, e_com_ma=None))]
    fn from_arrays(
        image_size: (u32, u32),
        world_mm: Vec<Bound<'_, PyAny>>,
        pixels: Vec<Bound<'_, PyAny>>,
        e_in_ma: Vec<f64>,
        temperature_c: Vec<f64>,
        e_com_ma: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let n = world_mm.len();
        if pixels.len() != n
            || e_in_ma.len() != n
            || temperature_c.len() != n
            || e_com_ma.as_ref().is_some_and(|e| e.len() != n)
        {
            return Err(input_error(format!(
                "world_mm, pixels, e_in_ma, temperature_c (and e_com_ma) need one entry per view: got {}, {}, {}, {}{}",
                n,
                pixels.len(),
                e_in_ma.len(),
                temperature_c.len(),
                e_com_ma.as_ref().map(|e| format!(", {}", e.len())).unwrap_or_default()
            )));
        }
        let mut o = Observations::new(image_size)?;
        for i in 0..n {
            let setting = (Some(e_in_ma[i]), Some(temperature_c[i]), e_com_ma.as_ref().map(|e| e[i]), None);
            o.push_checked(|f| &mut f.views, &world_mm[i], &pixels[i], setting)?;
        }
        Ok(o)
    }

    /// Reads an `etlcal.observations/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        Ok(Observations { file: ObsFile::load(&path).py()? })
    }

    /// Writes an `etlcal.observations/1` file (atomically).
    ///
    /// Args:
    ///     path: the file (str or os.PathLike); its directory must exist.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.file.save(&path).py()
    }

    /// The `etlcal.observations/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.file).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.observations/1` JSON text (checked as `load` checks a file).
    ///
    /// Args:
    ///     text: the JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let p = Path::new("<json>");
        let f: ObsFile = etl_formats::parse_json(text, p, FORMAT).py()?;
        f.validate().map_err(|e| etl_calib::Error::Parse { path: p.to_owned(), message: e.to_string() }).py()?;
        Ok(Observations { file: f })
    }

    /// (width, height), px.
    #[getter]
    fn image_size(&self) -> (u32, u32) {
        (self.file.image_size[0], self.file.image_size[1])
    }

    /// Adds an ETL view.
    ///
    /// Args:
    ///     world_mm: (N, 3) world points, mm.
    ///     pixels: (N, 2) observed pixels, px.
    ///     e_in_ma: driver current, mA.
    ///     temperature_c: lens temperature, degC.
    ///     e_com_ma: compensated current, mA (optional: used as is when given).
    ///     focal_power_dpt: the commanded focal power, dpt, instead of `e_in_ma` (a view
    ///         in the driver's focal-power mode; keyword only; every view of a set has
    ///         the same kind of setting).
    #[pyo3(signature = (world_mm, pixels, e_in_ma=None, temperature_c=None, e_com_ma=None, *, focal_power_dpt=None))]
    fn add_view(
        &mut self,
        world_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        e_in_ma: Option<f64>,
        temperature_c: Option<f64>,
        e_com_ma: Option<f64>,
        focal_power_dpt: Option<f64>,
    ) -> PyResult<()> {
        let setting = (e_in_ma, temperature_c, e_com_ma, focal_power_dpt);
        self.push_checked(|f| &mut f.views, world_mm, pixels, setting)
    }

    /// Adds a lens-off view of a planar board (points with Z = 0), for A0.
    ///
    /// Args:
    ///     world_mm: (N, 3) board points, mm (Z = 0).
    ///     pixels: (N, 2) observed pixels, px.
    fn add_offstate_view(&mut self, world_mm: &Bound<'_, PyAny>, pixels: &Bound<'_, PyAny>) -> PyResult<()> {
        let pts = view_points(world_mm, pixels)?;
        let world = pts.iter().flat_map(|p| p.world_mm).map(|x| ("world_mm", x));
        if let Some((what, x)) =
            world.chain(pts.iter().flat_map(|p| p.pixel).map(|x| ("pixels", x))).find(|(_, x)| !x.is_finite())
        {
            return Err(invalid_value(what, x, "offstate view: a point is not finite"));
        }
        self.file.offstate_views.push(OffstateView { points: pts });
        Ok(())
    }

    /// Adds a view for the per-setting baseline (`calibrate(..., method="per-setting")`):
    /// a planar board in a free pose at one lens setting. Views whose E_com agree within
    /// 0.5 mA form one setting; the baseline needs >= 3 views at each of >= 3 settings.
    ///
    /// Args:
    ///     world_mm: (N, 3) board points, mm (Z = 0).
    ///     pixels: (N, 2) observed pixels, px.
    ///     e_in_ma: driver current, mA.
    ///     temperature_c: lens temperature, degC.
    ///     e_com_ma: compensated current, mA (optional: used as is when given).
    #[pyo3(signature = (world_mm, pixels, e_in_ma, temperature_c, e_com_ma=None))]
    fn add_setting_view(
        &mut self,
        world_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        e_in_ma: f64,
        temperature_c: f64,
        e_com_ma: Option<f64>,
    ) -> PyResult<()> {
        let setting = (Some(e_in_ma), Some(temperature_c), e_com_ma, None);
        self.push_checked(|f| &mut f.setting_views, world_mm, pixels, setting)
    }

    /// Number of ETL views.
    fn __len__(&self) -> PyResult<usize> {
        crate::errors::guarded_value("Observations.__len__", || self.file.views.len())
    }

    /// ETL view `index` as a View (negative counts from the end; IndexError outside).
    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        crate::errors::guarded("Observations.__getitem__", || view_dict(py, pick(&self.file.views, index)?))
    }

    /// The ETL views in order, as View objects (a snapshot: views added while iterating
    /// are not seen).
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::errors::guarded("Observations.__iter__", || {
            let views = self.file.views.iter().map(|v| view_dict(py, v)).collect::<PyResult<Vec<_>>>()?;
            Ok(pyo3::types::PyList::new(py, views)?.try_iter()?.into_any())
        })
    }

    /// Number of lens-off views.
    #[getter]
    fn offstate_count(&self) -> usize {
        self.file.offstate_views.len()
    }

    /// Number of per-setting baseline views.
    #[getter]
    fn setting_count(&self) -> usize {
        self.file.setting_views.len()
    }

    /// Total number of points over the ETL views.
    #[getter]
    fn point_count(&self) -> usize {
        self.file.views.iter().map(|v| v.points.len()).sum()
    }

    /// ETL view `index` (also `obs[index]`): a View (attributes, also dict keys): world_mm ((N, 3), mm), pixels ((N, 2), px), e_in_ma,
    /// temperature_c and e_com_ma (None when not recorded).
    ///
    /// Args:
    ///     index: view number (negative counts from the end).
    fn view<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        view_dict(py, pick(&self.file.views, index)?)
    }

    /// Lens-off view `index`: an OffstateView (attributes, also dict keys): world_mm ((N, 3), mm) and pixels ((N, 2), px).
    ///
    /// Args:
    ///     index: view number (negative counts from the end).
    fn offstate_view<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        let d = points_dict(py, &pick(&self.file.offstate_views, index)?.points)?;
        crate::results::make(py, "OffstateView", &d)
    }

    /// Per-setting baseline view `index`: a View, as `view(index)`.
    ///
    /// Args:
    ///     index: view number (negative counts from the end).
    fn setting_view<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        view_dict(py, pick(&self.file.setting_views, index)?)
    }

    /// E_com of every view, mA: as recorded, or compensated from (e_in_ma,
    /// temperature_c) through `thermal`.
    ///
    /// Args:
    ///     thermal: a ThermalCalibration or "paper", needed when a view has no recorded
    ///         E_com (none is assumed).
    ///
    /// Raises: InputError naming a view without E_com when no thermal calibration is
    /// given, or a view outside the thermal calibration's ranges.
    #[pyo3(signature = (thermal=None))]
    fn e_com_ma(&self, thermal: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<f64>> {
        let t = thermal.map(crate::calibration::thermal_ref).transpose()?;
        self.file.e_com_ma(t.as_ref()).map_err(crate::errors::calib_err)
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("Observations.__repr__", || {
            format!(
                "Observations(image_size={:?}, views={}, points={}, offstate_views={})",
                self.file.image_size,
                self.file.views.len(),
                self.point_count(),
                self.file.offstate_views.len()
            )
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("Observations.__reduce__", || {
            let py = slf.py();
            let text = slf.borrow().to_json()?;
            let ctor = py.get_type::<Observations>().getattr("from_json")?;
            Ok((ctor, PyTuple::new(py, [text])?))
        })
    }
}

/// A view as `Observations.view` returns it (an `etlcal.results.View`).
fn view_dict<'py>(py: Python<'py>, v: &ViewObs) -> PyResult<Bound<'py, PyAny>> {
    let d = points_dict(py, &v.points)?;
    d.set_item("e_in_ma", (!v.e_in_ma.is_nan()).then_some(v.e_in_ma))?;
    d.set_item("temperature_c", v.temperature_c)?;
    d.set_item("e_com_ma", v.e_com_ma)?;
    d.set_item("focal_power_dpt", v.focal_power_dpt)?;
    crate::results::make(py, "View", &d)
}

fn pick<T>(xs: &[T], index: isize) -> PyResult<&T> {
    let n = xs.len() as isize;
    let i = if index < 0 { index + n } else { index };
    if i < 0 || i >= n {
        return Err(pyo3::exceptions::PyIndexError::new_err(format!("view index {index} out of range ({n} views)")));
    }
    Ok(&xs[i as usize])
}

/// The lens-off intrinsics A0 (section 4.2): focal lengths at E = 0 and the principal
/// point. The content of an `etlcal.a0/1` file.
///
/// Args:
///     kf0x: fx at E = 0, px (> 0).
///     kf0y: fy at E = 0, px (> 0).
///     u0: principal point u0, px.
///     v0: principal point v0, px.
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct A0 {
    pub(crate) inner: CoreA0,
}

fn check_a0(a: &CoreA0) -> PyResult<()> {
    let r = A0File::new(a);
    let numbers = [("kf0x", r.kf0x, true), ("kf0y", r.kf0y, true), ("u0", r.u0, false), ("v0", r.v0, false)];
    if let Some((what, x, _)) = numbers.into_iter().find(|&(_, x, positive)| !(x.is_finite() && (!positive || x > 0.0)))
    {
        return Err(invalid_value(what, x, "kf0x, kf0y must be positive and u0, v0 finite"));
    }
    Ok(())
}

#[pymethods]
impl A0 {
    #[new]
    fn new(kf0x: f64, kf0y: f64, u0: f64, v0: f64) -> PyResult<Self> {
        crate::errors::guarded("A0.__new__", || {
            let inner = CoreA0 { kf0x, kf0y, u0, v0 };
            check_a0(&inner)?;
            Ok(A0 { inner })
        })
    }

    /// Reads an `etlcal.a0/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        Ok(A0 { inner: A0File::load(&path).py()?.a0() })
    }

    /// Writes an `etlcal.a0/1` file (atomically).
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        A0File::new(&self.inner).save(&path).py()
    }

    /// The `etlcal.a0/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&A0File::new(&self.inner)).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.a0/1` JSON text.
    ///
    /// Args:
    ///     text: the JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let f: A0File = etl_formats::parse_json(text, Path::new("<json>"), A0_FORMAT).py()?;
        A0::new(f.kf0x, f.kf0y, f.u0, f.v0)
    }

    /// fx at E = 0, px.
    #[getter]
    fn kf0x(&self) -> f64 {
        self.inner.kf0x
    }

    /// fy at E = 0, px.
    #[getter]
    fn kf0y(&self) -> f64 {
        self.inner.kf0y
    }

    /// Principal point u0, px.
    #[getter]
    fn u0(&self) -> f64 {
        self.inner.u0
    }

    /// Principal point v0, px.
    #[getter]
    fn v0(&self) -> f64 {
        self.inner.v0
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("A0.__repr__", || {
            let a = &self.inner;
            format!("A0(kf0x={:?}, kf0y={:?}, u0={:?}, v0={:?})", a.kf0x, a.kf0y, a.u0, a.v0)
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("A0.__reduce__", || {
            let py = slf.py();
            let a = slf.get().inner;
            Ok((py.get_type::<A0>().into_any(), PyTuple::new(py, [a.kf0x, a.kf0y, a.u0, a.v0])?))
        })
    }
}
