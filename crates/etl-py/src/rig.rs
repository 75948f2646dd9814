//! `etlcal.rig`: the rig's cameras (`RigCamera`, `etlcal.rig.Camera`) and the capture
//! procedures (`rig_capture_views`, `rig_capture_offstate`, `rig_capture_thermal`, behind
//! `etlcal.rig.capture_views` / `capture_offstate` / `capture_thermal`) of etl-rig. A
//! device is a spec string (`"sim"`, `"files:DIR"`, `"aravis:NAME"`; `"virtual"`,
//! `"ld4:PORT"`; `"sim"`, `"manual"`, `"zaber:PORT,microstep_um=UM"`) or a Python object:
//! a camera with `grab()` (a 2-D uint8 or uint16 numpy array; optional `image_size`,
//! (width, height) px, else a first frame tells it), a stage with `move_mm(z_mm)`
//! (returning the position reached, mm, or None for the one asked) and, for lens-off
//! views, `present_offstate_pose(k, count)`; optional `limits_mm()`; a lens with
//! `set_current_ma(e_in_ma)` (returning the current commanded, mA, or None for the one
//! asked) and `temperature_c()`; optional `current_ma()` (else the last current commanded)
//! and `limits_ma()` ((lo, hi) mA; else none: each approach then goes the full 10 mA
//! below its current).

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::AtomicBool;

use etl_rig::camera::{Camera, CameraInfo, Frame, Gray16Image, Pixels};
use etl_rig::capture::{capture_offstate, capture_thermal, capture_views, CaptureOptions};
use etl_rig::lens::RigLens;
use etl_rig::rig::{open_camera, open_stage, paper_virtual_lens, Rig, RigSpec};
use etl_rig::spec::{CameraSpec, LensSpec, StageSpec};
use etl_rig::stage::Stage;
use etl_rig::ErrorKind;
use numpy::{PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{raise, Kind};

/// A rig error as a Python exception: device time-outs as `DeviceTimeoutError`, other
/// device failures and refused views as `DeviceError`, files and inputs as etlcal's
/// classes for them.
fn rig_err(e: etl_rig::Error) -> PyErr {
    match (&e, e.kind()) {
        (etl_rig::Error::Formats(_), _) | (_, ErrorKind::InvalidInput) => crate::errors::calib_err(e.into()),
        (_, ErrorKind::Timeout) => raise(Kind::DeviceTimeout, e.to_string()),
        _ => raise(Kind::Device, e.to_string()),
    }
}

/// The first Python exception a Python device raised, re-raised after the capture.
type Raised = Rc<RefCell<Option<PyErr>>>;

/// Keeps `e` (the first only), with a note naming the device (`add_note`, Python 3.11+:
/// the exception stays the object's own, its traceback says which device raised it).
fn keep(raised: &Raised, device: &str, e: PyErr) -> etl_rig::Error {
    let message = format!("a Python method raised: {e}");
    Python::attach(|py| {
        let note =
            format!("raised by the {device} during the capture (what was taken stays whole: call again to resume)");
        let _ = e.value(py).call_method1("add_note", (note,));
    });
    raised.borrow_mut().get_or_insert(e);
    etl_rig::Error::device(device, ErrorKind::Other, message)
}

/// A 2-D uint8 or uint16 numpy array as pixels.
fn pixels_of(obj: &Bound<'_, PyAny>, what: &str) -> Result<Pixels, String> {
    let size = |shape: &[usize]| [shape[1] as u32, shape[0] as u32];
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u8>>() {
        let [w, h] = size(a.shape());
        let raw = a.as_array().iter().copied().collect();
        return image::GrayImage::from_raw(w, h, raw).map(Pixels::Mono8).ok_or_else(|| format!("{what}: bad array"));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u16>>() {
        let [w, h] = size(a.shape());
        let raw = a.as_array().iter().copied().collect();
        return Gray16Image::from_raw(w, h, raw).map(Pixels::Mono16).ok_or_else(|| format!("{what}: bad array"));
    }
    Err(format!("{what} must return a 2-D numpy array of dtype uint8 or uint16"))
}

/// A Python camera object (`grab()`).
struct PyCameraObject {
    obj: Py<PyAny>,
    raised: Raised,
    frames: u64,
}

impl Camera for PyCameraObject {
    fn name(&self) -> String {
        "camera (Python object)".into()
    }

    fn grab(&mut self) -> etl_rig::Result<Frame> {
        let name = self.name();
        Python::attach(|py| {
            let frame = self.obj.bind(py).call_method0("grab").map_err(|e| keep(&self.raised, &name, e))?;
            let pixels =
                pixels_of(&frame, "grab()").map_err(|m| etl_rig::Error::device(&name, ErrorKind::Protocol, m))?;
            self.frames += 1;
            Ok(Frame { pixels, timestamp_ns: self.frames })
        })
    }

    fn set_exposure_us(&mut self, exposure_us: f64) -> etl_rig::Result<()> {
        let name = self.name();
        Python::attach(|py| self.obj.bind(py).call_method1("set_exposure_us", (exposure_us,)).map(|_| ()))
            .map_err(|e| keep(&self.raised, &name, e))
    }

    fn set_gain_db(&mut self, gain_db: f64) -> etl_rig::Result<()> {
        let name = self.name();
        Python::attach(|py| self.obj.bind(py).call_method1("set_gain_db", (gain_db,)).map(|_| ()))
            .map_err(|e| keep(&self.raised, &name, e))
    }

    fn info(&mut self) -> etl_rig::Result<CameraInfo> {
        // The object's `image_size` (width, height) when it has one, else a first frame's.
        let said = Python::attach(|py| self.obj.bind(py).getattr("image_size").and_then(|s| s.extract::<(u32, u32)>()));
        let image_size = match said {
            Ok((w, h)) => [w, h],
            Err(_) => self.grab()?.pixels.size(),
        };
        Ok(CameraInfo { spec: "python".into(), model: "a Python object".into(), image_size })
    }
}

/// A Python stage object (`move_mm(z_mm)`, optional `limits_mm()`, `present_offstate_pose(k, count)`).
struct PyStageObject {
    obj: Py<PyAny>,
    raised: Raised,
    position_mm: Option<f64>,
}

impl PyStageObject {
    fn call(
        &self,
        method: &str,
        args: impl for<'py> FnOnce(Python<'py>) -> Vec<f64>,
    ) -> etl_rig::Result<Option<Vec<f64>>> {
        let name = self.name();
        Python::attach(|py| {
            let obj = self.obj.bind(py);
            if !obj.hasattr(method).unwrap_or(false) {
                return Ok(None);
            }
            let a = args(py);
            let out = match a.len() {
                0 => obj.call_method0(method),
                1 => obj.call_method1(method, (a[0],)),
                _ => obj.call_method1(method, (a[0] as usize, a[1] as usize)),
            }
            .map_err(|e| keep(&self.raised, &name, e))?;
            if out.is_none() {
                return Ok(Some(vec![]));
            }
            out.extract::<Vec<f64>>().or_else(|_| out.extract::<f64>().map(|x| vec![x])).map(Some).map_err(|_| {
                etl_rig::Error::device(&name, ErrorKind::Protocol, format!("{method}() returned no number"))
            })
        })
    }
}

impl Stage for PyStageObject {
    fn name(&self) -> String {
        "stage (Python object)".into()
    }

    fn move_mm(&mut self, z_mm: f64) -> etl_rig::Result<f64> {
        let out = self.call("move_mm", |_| vec![z_mm])?;
        let name = self.name();
        let z = match out {
            None => {
                return Err(etl_rig::Error::device(
                    name,
                    ErrorKind::InvalidInput,
                    "the stage object has no move_mm(z_mm)",
                ))
            }
            Some(v) => v.first().copied().unwrap_or(z_mm),
        };
        self.position_mm = Some(z);
        Ok(z)
    }

    fn position_mm(&mut self) -> etl_rig::Result<f64> {
        let name = self.name();
        self.position_mm.ok_or_else(|| etl_rig::Error::device(name, ErrorKind::Other, "not moved yet"))
    }

    fn home(&mut self) -> etl_rig::Result<()> {
        self.call("home", |_| vec![]).map(|_| ())
    }

    fn limits_mm(&mut self) -> etl_rig::Result<[f64; 2]> {
        match self.call("limits_mm", |_| vec![])? {
            Some(v) if v.len() == 2 => Ok([v[0], v[1]]),
            Some(_) => {
                Err(etl_rig::Error::device(self.name(), ErrorKind::Protocol, "limits_mm() must return (lo, hi) mm"))
            }
            None => Ok([f64::NEG_INFINITY, f64::INFINITY]),
        }
    }

    fn present_offstate_pose(&mut self, k: usize, count: usize) -> etl_rig::Result<()> {
        match self.call("present_offstate_pose", |_| vec![k as f64, count as f64])? {
            Some(_) => Ok(()),
            None => {
                let message = "the stage object has no present_offstate_pose(k, count) for the lens-off views";
                Err(etl_rig::Error::device(self.name(), ErrorKind::InvalidInput, message))
            }
        }
    }
}

/// A Python lens object (`set_current_ma(e_in_ma)`, `temperature_c()`, optional
/// `current_ma()` and `limits_ma()`).
struct PyLensObject {
    obj: Py<PyAny>,
    raised: Raised,
    last_ma: Option<f64>,
}

/// The name of a Python lens in errors.
const PY_LENS: &str = "lens (Python object)";

impl PyLensObject {
    /// `method(args)` as a number (None: the method returned None).
    fn number(&self, method: &str, args: Option<f64>) -> etl_rig::Result<Option<f64>> {
        Python::attach(|py| {
            let obj = self.obj.bind(py);
            let out = match args {
                Some(x) => obj.call_method1(method, (x,)),
                None => obj.call_method0(method),
            }
            .map_err(|e| keep(&self.raised, PY_LENS, e))?;
            if out.is_none() {
                return Ok(None);
            }
            out.extract::<f64>().map(Some).map_err(|_| {
                etl_rig::Error::device(PY_LENS, ErrorKind::Protocol, format!("{method}() returned no number"))
            })
        })
    }

    fn has(&self, method: &str) -> bool {
        Python::attach(|py| self.obj.bind(py).hasattr(method).unwrap_or(false))
    }

    /// The object's `limits_ma()`, or none.
    fn limits_ma(&self) -> etl_rig::Result<[f64; 2]> {
        if !self.has("limits_ma") {
            return Ok([f64::NEG_INFINITY, f64::INFINITY]);
        }
        Python::attach(|py| {
            let out = self.obj.bind(py).call_method0("limits_ma").map_err(|e| keep(&self.raised, PY_LENS, e))?;
            let (lo, hi) = out.extract::<(f64, f64)>().map_err(|_| {
                etl_rig::Error::device(PY_LENS, ErrorKind::Protocol, "limits_ma() must return (lo, hi) mA")
            })?;
            Ok([lo, hi])
        })
    }
}

impl etl_core::lens::Lens for PyLensObject {
    type Error = etl_rig::Error;

    fn set_current_ma(&mut self, e_in_ma: f64) -> etl_rig::Result<f64> {
        let set = self.number("set_current_ma", Some(e_in_ma))?.unwrap_or(e_in_ma);
        self.last_ma = Some(set);
        Ok(set)
    }

    fn current_ma(&mut self) -> etl_rig::Result<f64> {
        if self.has("current_ma") {
            if let Some(e) = self.number("current_ma", None)? {
                return Ok(e);
            }
        }
        self.last_ma.ok_or_else(|| etl_rig::Error::device(PY_LENS, ErrorKind::Other, "no current commanded yet"))
    }

    fn temperature_c(&mut self) -> etl_rig::Result<f64> {
        self.number("temperature_c", None)?.ok_or_else(|| {
            etl_rig::Error::device(PY_LENS, ErrorKind::Protocol, "temperature_c() returned None, not degC")
        })
    }
}

/// A device: a spec string or a Python object.
enum Device<'py> {
    Spec(String),
    Object(Bound<'py, PyAny>),
}

fn device<'py>(obj: Bound<'py, PyAny>) -> Device<'py> {
    match obj.extract::<String>() {
        Ok(s) => Device::Spec(s),
        Err(_) => Device::Object(obj),
    }
}

/// The rig of the devices given: all specs open as the command line opens them (`sim_roi`
/// for the sim camera); any Python object, each device on its own.
fn open_rig(
    camera: Device<'_>,
    lens: Device<'_>,
    stage: Device<'_>,
    sim: (u64, Option<[u32; 4]>),
    raised: &Raised,
) -> etl_rig::Result<Rig> {
    let (seed, sim_roi) = sim;
    if let (Device::Spec(c), Device::Spec(l), Device::Spec(s)) = (&camera, &lens, &stage) {
        let spec = RigSpec {
            camera: c.parse::<CameraSpec>()?,
            lens: l.parse::<LensSpec>()?,
            stage: s.parse::<StageSpec>()?,
            sim_seed: seed,
            sim_roi,
            virtual_lens: paper_virtual_lens(),
        };
        return Rig::open(&spec);
    }
    let lens = match lens {
        Device::Spec(l) => RigLens::open(&l.parse::<LensSpec>()?, paper_virtual_lens())?,
        Device::Object(o) => {
            let driver = PyLensObject { obj: o.unbind(), raised: Rc::clone(raised), last_ma: None };
            let limits_ma = driver.limits_ma()?;
            RigLens::from_driver(PY_LENS, Box::new(driver), limits_ma)
        }
    };
    let camera: Box<dyn Camera> = match camera {
        Device::Spec(c) if c == "sim" => {
            let message = "the sim camera renders the virtual lens's state on the simulated stage: give lens=\"virtual\" and stage=\"sim\"";
            return Err(etl_rig::Error::device("camera sim", ErrorKind::InvalidInput, message));
        }
        Device::Spec(c) => open_camera(&c.parse::<CameraSpec>()?, seed)?,
        Device::Object(o) => Box::new(PyCameraObject { obj: o.unbind(), raised: Rc::clone(raised), frames: 0 }),
    };
    let stage: Box<dyn Stage> = match stage {
        Device::Spec(s) => open_stage(&s.parse::<StageSpec>()?)?,
        Device::Object(o) => Box::new(PyStageObject { obj: o.unbind(), raised: Rc::clone(raised), position_mm: None }),
    };
    Ok(Rig { camera, lens, stage, sim: None })
}

fn load_plan(py: Python<'_>, plan: &Bound<'_, PyAny>) -> PyResult<etl_formats::plan::Plan> {
    if let Ok(path) = plan.extract::<PathBuf>() {
        return etl_formats::plan::Plan::load(&path).map_err(crate::errors::calib_err);
    }
    let text: String = py.import("json")?.call_method1("dumps", (plan,))?.extract()?;
    let parsed: etl_formats::plan::Plan =
        etl_formats::parse_json(&text, std::path::Path::new("plan"), etl_formats::plan::FORMAT)
            .map_err(crate::errors::calib_err)?;
    parsed.validate().map_err(crate::errors::calib_err)?;
    Ok(parsed)
}

#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    offstate_only: bool,
    plan: Bound<'py, PyAny>,
    out: PathBuf,
    camera: Bound<'py, PyAny>,
    lens: Bound<'py, PyAny>,
    stage: Bound<'py, PyAny>,
    options: CaptureOptions,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let plan = load_plan(py, &plan)?;
    let raised: Raised = Rc::new(RefCell::new(None));
    let result = open_rig(device(camera), device(lens), device(stage), (seed, None), &raised).and_then(|mut rig| {
        let (progress, stop) = (etl_core::progress::NoProgress, AtomicBool::new(false));
        if offstate_only {
            capture_offstate(&plan, &mut rig, &out, &options, &progress, &stop)
        } else {
            capture_views(&plan, &mut rig, &out, &options, &progress, &stop)
        }
    });
    if let Some(e) = raised.borrow_mut().take() {
        return Err(e);
    }
    let r = result.map_err(rig_err)?;
    let d = PyDict::new(py);
    d.set_item("dataset", out.join(etl_rig::capture::store::DATASET_FILE))?;
    d.set_item("offstate_kept", r.offstate_kept)?;
    d.set_item("offstate_taken", r.offstate_taken)?;
    d.set_item("views_kept", r.views_kept)?;
    d.set_item("views_taken", r.views_taken)?;
    d.set_item("stopped", r.stopped)?;
    Ok(d)
}

fn options(
    settle_tolerance_px: f64,
    settle_timeout_s: f64,
    max_temperature_change_c: f64,
    autofocus_range_ma: Option<(f64, f64)>,
) -> CaptureOptions {
    CaptureOptions {
        settle_tolerance_px,
        settle_timeout_s,
        max_temperature_change_c,
        autofocus_range_ma: autofocus_range_ma.map(|(a, b)| [a, b]),
        shaper: None,
    }
}

/// Captures a plan's lens-off views (if it asks for them), then its ETL views, into
/// `out/dataset.json` with the images; resumes what an earlier run left there
/// (`etlcal.rig.capture_views`; docs/RIG.md, "Capture").
///
/// Args:
///     plan: an `etlcal.plan/1` file's path, or its object as a dict.
///     out: the output folder.
///     camera: a spec ("sim", "files:DIR", "aravis:NAME") or an object with `grab()`
///         returning a 2-D uint8/uint16 numpy array.
///     lens: a spec ("virtual", "ld4:PORT") or an object with `set_current_ma(e_in_ma)`
///         and `temperature_c()` (optional `current_ma()`, `limits_ma()`; module docs).
///     stage: a spec ("sim", "manual", "zaber:PORT,microstep_um=UM") or an object with
///         `move_mm(z_mm)` (and `present_offstate_pose(k, count)` for lens-off views).
///     settle_tolerance_px: the lens has settled when the board's corners move at most
///         this between frames (RMS, px).
///     settle_timeout_s: the longest wait for the lens to settle, s.
///     max_temperature_change_c: a view whose lens temperature moved more, degC, is refused.
///     autofocus_range_ma: (lo, hi) mA, for plans with "focus": "autofocus".
///     seed: the sim camera's noise seed.
///
/// Returns: dict with "dataset" (the path), "offstate_kept", "offstate_taken",
/// "views_kept", "views_taken", "stopped".
///
/// Raises: InputError for a bad plan or spec (nothing written); DeviceError or
/// DeviceTimeoutError naming the device that failed (the dataset stays whole: call again
/// to resume); a Python device's own exception as it is.
#[pyfunction]
#[pyo3(signature = (plan, out, camera, lens, stage, *, settle_tolerance_px=0.05, settle_timeout_s=10.0,
    max_temperature_change_c=0.5, autofocus_range_ma=None, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn rig_capture_views<'py>(
    py: Python<'py>,
    plan: Bound<'py, PyAny>,
    out: PathBuf,
    camera: Bound<'py, PyAny>,
    lens: Bound<'py, PyAny>,
    stage: Bound<'py, PyAny>,
    settle_tolerance_px: f64,
    settle_timeout_s: f64,
    max_temperature_change_c: f64,
    autofocus_range_ma: Option<(f64, f64)>,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let o = options(settle_tolerance_px, settle_timeout_s, max_temperature_change_c, autofocus_range_ma);
    run(py, false, plan, out, camera, lens, stage, o, seed)
}

/// The plan's lens-off views only (its `offstate_views`), as `rig_capture_views` takes
/// them (`etlcal.rig.capture_offstate`). Args, returns and raises as `rig_capture_views`.
#[pyfunction]
#[pyo3(signature = (plan, out, camera, lens, stage, *, settle_tolerance_px=0.05, settle_timeout_s=10.0,
    max_temperature_change_c=0.5, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn rig_capture_offstate<'py>(
    py: Python<'py>,
    plan: Bound<'py, PyAny>,
    out: PathBuf,
    camera: Bound<'py, PyAny>,
    lens: Bound<'py, PyAny>,
    stage: Bound<'py, PyAny>,
    settle_tolerance_px: f64,
    settle_timeout_s: f64,
    max_temperature_change_c: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let o = options(settle_tolerance_px, settle_timeout_s, max_temperature_change_c, None);
    run(py, true, plan, out, camera, lens, stage, o, seed)
}

/// The temperature procedure over a plan's `thermal` grid on a rig, writing
/// `out/thermal.csv` after every sample and `out/thermal.json` once the grid is done;
/// resumes what an earlier run left there (`etlcal.rig.capture_thermal`; docs/RIG.md,
/// "Temperature capture").
///
/// Args:
///     plan, out, camera, lens, stage: as `rig_capture_views`.
///     settle_timeout_s: the longest wait for each frame's sharpness to settle, s.
///     max_temperature_change_c: a step whose lens temperature moved more, degC, is refused.
///     sim_roi: (x, y, width, height) px: the sim camera renders only that window.
///     seed: the sim camera's noise seed.
///
/// Returns: dict with "table", "thermal" (None until the grid is done), "samples_kept",
/// "samples_taken", "evaluations", "rms_ma" (None until done), "stopped".
///
/// Raises: as `rig_capture_views` (the table stays whole: call again to resume).
#[pyfunction]
#[pyo3(signature = (plan, out, camera, lens, stage, *, settle_timeout_s=10.0, max_temperature_change_c=0.5,
    sim_roi=None, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn rig_capture_thermal<'py>(
    py: Python<'py>,
    plan: Bound<'py, PyAny>,
    out: PathBuf,
    camera: Bound<'py, PyAny>,
    lens: Bound<'py, PyAny>,
    stage: Bound<'py, PyAny>,
    settle_timeout_s: f64,
    max_temperature_change_c: f64,
    sim_roi: Option<(u32, u32, u32, u32)>,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let plan = load_plan(py, &plan)?;
    let options = CaptureOptions { settle_timeout_s, max_temperature_change_c, ..CaptureOptions::default() };
    let raised: Raised = Rc::new(RefCell::new(None));
    let roi = sim_roi.map(|(x, y, w, h)| [x, y, w, h]);
    let result = open_rig(device(camera), device(lens), device(stage), (seed, roi), &raised).and_then(|mut rig| {
        let (progress, stop) = (etl_core::progress::NoProgress, AtomicBool::new(false));
        capture_thermal(&plan, &mut rig, &out, &options, &progress, &stop)
    });
    if let Some(e) = raised.borrow_mut().take() {
        return Err(e);
    }
    let r = result.map_err(rig_err)?;
    let d = PyDict::new(py);
    d.set_item("table", out.join(etl_rig::capture::thermal::THERMAL_TABLE_FILE))?;
    d.set_item("thermal", r.rms_ma.map(|_| out.join(etl_rig::capture::thermal::THERMAL_FILE)))?;
    d.set_item("samples_kept", r.samples_kept)?;
    d.set_item("samples_taken", r.samples_taken)?;
    d.set_item("evaluations", r.evaluations)?;
    d.set_item("rms_ma", r.rms_ma)?;
    d.set_item("stopped", r.stopped)?;
    Ok(d)
}

/// A camera of the rig, opened from its spec (`etlcal.rig.Camera`): `"sim"` (the
/// simulated paper rig at rest), `"files:DIR"`, `"aravis:NAME"` (a GenICam camera; built
/// with the aravis feature).
#[pyclass(module = "etlcal", name = "RigCamera", unsendable)]
pub struct RigCamera {
    inner: Box<dyn Camera>,
}

#[pymethods]
impl RigCamera {
    /// Opens the camera of `spec` (`seed`: the sim camera's noise seed).
    ///
    /// Raises: InputError for an unknown spec; DeviceError if the camera cannot be opened.
    #[staticmethod]
    #[pyo3(signature = (spec, seed=1))]
    fn open(spec: &str, seed: u64) -> PyResult<RigCamera> {
        let spec = spec.parse::<CameraSpec>().map_err(rig_err)?;
        Ok(RigCamera { inner: open_camera(&spec, seed).map_err(rig_err)? })
    }

    /// One frame: a 2-D numpy array, uint8 or uint16 (rows x columns).
    fn grab<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(self.grab_frame(py)?.0)
    }

    /// One frame and its timestamp: (array, timestamp_ns), the camera's clock in ns.
    fn grab_frame<'py>(&mut self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, u64)> {
        let frame = self.inner.grab().map_err(rig_err)?;
        let [w, h] = frame.pixels.size();
        let shape = [h as usize, w as usize];
        let array = match frame.pixels {
            Pixels::Mono8(g) => PyArray2::from_vec2(py, &to_rows(g.as_raw(), shape))?.into_any(),
            Pixels::Mono16(g) => PyArray2::from_vec2(py, &to_rows(g.as_raw(), shape))?.into_any(),
        };
        Ok((array, frame.timestamp_ns))
    }

    /// Sets the exposure time, us.
    fn set_exposure_us(&mut self, exposure_us: f64) -> PyResult<()> {
        self.inner.set_exposure_us(exposure_us).map_err(rig_err)
    }

    /// Sets the gain, dB.
    fn set_gain_db(&mut self, gain_db: f64) -> PyResult<()> {
        self.inner.set_gain_db(gain_db).map_err(rig_err)
    }

    /// (spec, model, (width, height) px).
    fn info(&mut self) -> PyResult<(String, String, (u32, u32))> {
        let i = self.inner.info().map_err(rig_err)?;
        Ok((i.spec, i.model, (i.image_size[0], i.image_size[1])))
    }
}

fn to_rows<T: Copy>(raw: &[T], [h, w]: [usize; 2]) -> Vec<Vec<T>> {
    (0..h).map(|r| raw[r * w..(r + 1) * w].to_vec()).collect()
}
