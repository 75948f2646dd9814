//! `Calibration`: a calibrated ETL camera (`etlcal.calibration/1`) and what is done with
//! it at run time: (E_in, T) -> E_com -> K(E_com), distortion(E_com) -> project /
//! undistort / rays.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use etl_core::model::{CameraModel, DistortionA, FocalPoly};
use etl_core::runtime::{Camera, Trust};
use etl_core::thermal::ThermalSurface as CoreSurface;
use etl_formats::calibration::{Calibration as CalFile, ModelStd, ThermalRef};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::arrays::{mat3_out, vec_out};
use crate::camera::{self, trust, CameraAt};
use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};
use crate::pose::BoardPose;
use crate::thermal::{ThermalCalibration, ThermalSurface};

/// Parses and checks `etlcal.calibration/1` text (the format's one validator).
fn parse_file(text: &str, path: &Path) -> PyResult<CalFile> {
    CalFile::parse(text, path).py()
}

/// A calibrated ETL camera: the 25 numbers of the paper's model (Eq. 12-18), the
/// temperature compensation (optional), the current range, and the quality figures.
///
/// Build one with `Calibration.load(path)`, `Calibration.paper_rig()`, `calibrate(...)`,
/// or the constructor.
///
/// Args:
///     rotation_rodrigues: Rodrigues vector of R (world -> camera), rad (3 numbers).
///     translation_mm: T (world -> camera), mm (3 numbers).
///     kf_x: `fx(E) = kf_x[0] + kf_x[1] E + kf_x[2] E^2 + kf_x[3] E^3`, px with E in mA.
///     kf_y: fy(E), as kf_x.
///     principal_point: (u0, v0), px.
///     distortion_a: a1..a9 of Eq. 18 (9 numbers).
///     image_size: (width, height), px.
///     e_com_range_ma: (min, max) compensated current the calibration covers, mA.
///     thermal: the temperature compensation: a ThermalCalibration (a surface with the
///         ranges it was fitted over: `at` and `e_com` refuse outside them), a bare
///         ThermalSurface (no ranges known: only `allow_extrapolation=True` evaluates it),
///         or None.
///     rms_px: RMS reprojection error, px, or None.
///
/// Raises: InputError for NaN or infinite numbers, a non-positive image size, an
/// unordered range.
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct Calibration {
    /// Shared with every `CameraAt` of it (the file never changes once wrapped).
    pub(crate) file: Arc<CalFile>,
    /// `file.model()`, kept to avoid rebuilding it on every call.
    pub(crate) model: CameraModel,
}

impl Calibration {
    /// A calibration of `model` with no thermal part, zero standard deviations and zero
    /// RMS (an exact model, not an estimate).
    pub fn from_model(model: CameraModel, image_size: [u32; 2], e_com_range_ma: [f64; 2]) -> Self {
        Calibration { file: Arc::new(CalFile::from_model(&model, image_size, e_com_range_ma)), model }
    }

    /// Wraps a calibration file's content. Errors: a file whose model is invalid (an
    /// unknown distortion model, numbers of the wrong lengths), naming the field.
    pub fn from_file(file: CalFile) -> PyResult<Self> {
        let model = file.model().py()?;
        Ok(Calibration { file: Arc::new(file), model })
    }

    /// The file, to change before it is wrapped for Python (it is shared afterwards).
    pub(crate) fn file_mut(&mut self) -> &mut CalFile {
        Arc::make_mut(&mut self.file)
    }

    /// The camera of `slf` at driver current `e_in_ma` and temperature `temperature_c`
    /// (the calibration's range policy). A calibration without a thermal part is refused,
    /// naming `at_e_com`.
    pub(crate) fn camera_at_setting(
        slf: &Bound<'_, Self>,
        e_in_ma: f64,
        temperature_c: f64,
        allow_extrapolation: bool,
    ) -> PyResult<CameraAt> {
        let cal = slf.get();
        if cal.file.thermal.is_none() {
            return Err(invalid(
                "thermal",
                "this calibration has no temperature compensation (thermal): use at_e_com(e_com_ma) with a known E_com",
            ));
        }
        let inner = cal.camera()?.at_with(e_in_ma, temperature_c, trust(allow_extrapolation)).py()?;
        Ok(CameraAt::new(inner, slf.clone().into_any().unbind(), cal.file.clone()))
    }

    /// The camera of `slf` at a known compensated current `e_com_ma`, refused outside the
    /// calibrated E_com range (margin 5 mA) unless `allow_extrapolation`: the one range
    /// check of every method taking `e_com_ma`.
    pub(crate) fn camera_at_e_com(
        slf: &Bound<'_, Self>,
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<CameraAt> {
        let cal = slf.get();
        let inner = cal.camera()?.at_e_com(e_com_ma, trust(allow_extrapolation)).py()?;
        Ok(CameraAt::new(inner, slf.clone().into_any().unbind(), cal.file.clone()))
    }
}

#[pymethods]
impl Calibration {
    #[new]
    #[pyo3(signature = (rotation_rodrigues, translation_mm, kf_x, kf_y, principal_point, distortion_a,
        image_size=(1936, 1458), e_com_range_ma=(0.0, 250.0), thermal=None, rms_px=0.0),
        text_signature = "(rotation_rodrigues, translation_mm, kf_x, kf_y, principal_point, distortion_a, \
            image_size=(1936, 1458), e_com_range_ma=(0.0, 250.0), thermal=None, rms_px=0.0)")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rotation_rodrigues: &Bound<'_, PyAny>,
        translation_mm: &Bound<'_, PyAny>,
        kf_x: &Bound<'_, PyAny>,
        kf_y: &Bound<'_, PyAny>,
        principal_point: &Bound<'_, PyAny>,
        distortion_a: &Bound<'_, PyAny>,
        image_size: (u32, u32),
        e_com_range_ma: (f64, f64),
        thermal: Option<&Bound<'_, PyAny>>,
        rms_px: f64,
    ) -> PyResult<Self> {
        crate::errors::guarded("Calibration.__new__", || {
            use crate::arrays::fixed;
            let model = CameraModel {
                rotation_rodrigues: fixed::<3>(rotation_rodrigues, "rotation_rodrigues")?,
                translation_mm: fixed::<3>(translation_mm, "translation_mm")?,
                kf_x: FocalPoly::cubic(fixed::<4>(kf_x, "kf_x")?),
                kf_y: FocalPoly::cubic(fixed::<4>(kf_y, "kf_y")?),
                principal_point: fixed::<2>(principal_point, "principal_point")?,
                distortion_a: DistortionA::paper(fixed::<9>(distortion_a, "distortion_a")?),
                centre: None,
            };
            model.validate().py()?;
            etl_core::error::finite(rms_px, "rms_px").py()?;
            let mut c =
                Calibration::from_model(model, [image_size.0, image_size.1], [e_com_range_ma.0, e_com_range_ma.1]);
            c.file_mut().thermal = thermal.map(thermal_ref).transpose()?;
            c.file_mut().rms_reprojection_px = rms_px;
            c.file.validate(Path::new("<Calibration>")).py()?;
            Ok(c)
        })
    }

    /// The simulated rig of the paper (section 5.1.2) with the paper's temperature
    /// compensation: 1936 x 1458 px, E_com 80..225 mA.
    #[staticmethod]
    fn paper_rig() -> Self {
        let [w, h] = CameraModel::PAPER_IMAGE_SIZE;
        let mut c = Calibration::from_model(CameraModel::paper_rig(), [w, h], [80.0, 225.0]);
        c.file_mut().thermal = Some(ThermalRef::paper());
        c
    }

    /// Reads an `etlcal.calibration/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    ///
    /// Raises: FileError when it cannot be read; InputError when it is not a valid
    /// calibration file.
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        // The CLI's reader: regular files only, a size cap, and a calibration written as a
        // set with its observations read only once the set is whole.
        Calibration::from_file(CalFile::load(&path).py()?)
    }

    /// Writes the calibration as an `etlcal.calibration/1` file (atomically: a failed
    /// write leaves an earlier file whole).
    ///
    /// Args:
    ///     path: the file (str or os.PathLike); its directory must exist.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.file.save(&path).py()
    }

    /// The `etlcal.calibration/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&*self.file).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.calibration/1` JSON text.
    ///
    /// Args:
    ///     text: the JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Calibration::from_file(parse_file(text, Path::new("<json>"))?)
    }

    /// Rodrigues vector of R (world -> camera), rad.
    #[getter]
    fn rotation_rodrigues<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.file.rotation_rodrigues)
    }

    /// R (world -> camera), a 3 x 3 array.
    #[getter]
    fn rotation_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        mat3_out(py, self.model.rotation_matrix())
    }

    /// T (world -> camera), mm.
    #[getter]
    fn translation_mm<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.model.translation_mm)
    }

    /// kf0x..kf3x of fx(E), px (E in mA).
    #[getter]
    fn kf_x<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, self.model.kf_x.coefficients())
    }

    /// kf0y..kf3y of fy(E), px (E in mA).
    #[getter]
    fn kf_y<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, self.model.kf_y.coefficients())
    }

    /// (u0, v0), px: a float64 array of shape (2,).
    #[getter]
    fn principal_point<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.model.principal_point)
    }

    /// The moving centre (`calibrate(..., centre="moving")`), as the file's `"centre"`:
    /// `{"dz_mm": [0, dz1, dz2], "principal_point_px": [[u0, u1], [v0, v1]]}`, ascending
    /// coefficients in E (mA); dz(E) is the centre's move along the camera's +Z from its
    /// place at E = 0 (`translation_mm`). None for the paper's fixed centre.
    #[getter]
    fn centre<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(c) = &self.file.centre else { return Ok(None) };
        let d = pyo3::types::PyDict::new(py);
        d.set_item("dz_mm", c.dz_mm.clone())?;
        d.set_item("principal_point_px", c.principal_point_px.clone())?;
        Ok(Some(d.into_any()))
    }

    /// fx(E) as a `numpy.polynomial.Polynomial` in E (mA), px: its coefficients are
    /// `kf_x` in ascending powers, so `cal.fx_poly(e_com_ma)` is fx at E_com (no range
    /// check: `focal_lengths` checks the calibrated range).
    #[getter]
    fn fx_poly<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        polynomial(py, self.model.kf_x.coefficients())
    }

    /// fy(E) as a `numpy.polynomial.Polynomial` in E (mA), px (coefficients `kf_y`; as
    /// `fx_poly`).
    #[getter]
    fn fy_poly<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        polynomial(py, self.model.kf_y.coefficients())
    }

    /// a1..a9 of Eq. 18.
    #[getter]
    fn distortion_a<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, self.model.distortion_a.as_slice())
    }

    /// (width, height), px.
    #[getter]
    fn image_size(&self) -> (u32, u32) {
        (self.file.image_size[0], self.file.image_size[1])
    }

    /// (min, max) compensated current the calibration covers, mA.
    #[getter]
    fn e_com_range_ma(&self) -> (f64, f64) {
        (self.file.e_com_range_ma[0], self.file.e_com_range_ma[1])
    }

    /// The temperature compensation (a ThermalSurface), or None.
    #[getter]
    fn thermal(&self) -> Option<ThermalSurface> {
        self.file.thermal.as_ref().map(|t| ThermalSurface { inner: CoreSurface { coefficients: t.coefficients } })
    }

    /// The whole thermal calibration (surface and calibrated ranges), or None when the
    /// calibration has no thermal part or keeps no ranges (an older file).
    #[getter]
    fn thermal_calibration(&self) -> Option<ThermalCalibration> {
        let t = self.file.thermal.as_ref()?;
        Some(ThermalCalibration { inner: t.calibration().ok()?, rms_ma: t.rms_ma.unwrap_or(0.0) })
    }

    /// The corners left out of the final solve as gross outliers, as (view, point,
    /// residual_px): indices into the observations' views and that view's points, and the
    /// corner's reprojection error under the calibration, px. Empty when there are none.
    #[getter]
    fn outliers(&self) -> Vec<(usize, usize, f64)> {
        self.file.outliers.iter().map(|o| (o.view, o.point, o.residual_px)).collect()
    }

    /// The corners Zhang's method left out as gross outliers at the settings of the
    /// per-setting baseline, as (view, point, residual_px): indices into the observations'
    /// setting_views and that view's points, and the corner's distance from Zhang's model
    /// at its setting, px. Empty when there are none (and for the other methods).
    #[getter]
    fn setting_outliers(&self) -> Vec<(usize, usize, f64)> {
        self.file.setting_outliers.iter().map(|o| (o.view, o.point, o.residual_px)).collect()
    }

    /// The observations' setting views as the bundle adjustment solved them with the stage
    /// views (`setting_views="joint"`), in their order: a list of SettingViewSummary
    /// (attributes, also dict keys) e_com_ma (mA), points, rms_px (px), de_ma (mA; its
    /// current correction, 0 for the paper's estimator), and the board's pose, board to
    /// camera, rotation_rodrigues (rad) and translation_mm (mm) as float64 arrays. Empty
    /// when they were not in the solve.
    #[getter]
    fn setting_views<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        self.file
            .setting_views
            .iter()
            .map(|v| {
                let d = PyDict::new(py);
                d.set_item("e_com_ma", v.e_com_ma)?;
                d.set_item("points", v.points)?;
                d.set_item("rms_px", v.rms_px)?;
                d.set_item("de_ma", v.de_ma)?;
                d.set_item("rotation_rodrigues", vec_out(py, &v.rotation_rodrigues))?;
                d.set_item("translation_mm", vec_out(py, &v.translation_mm))?;
                crate::results::make(py, "SettingViewSummary", &d)
            })
            .collect()
    }

    /// Why the calibration may be implausible (outliers left out, an RMS far above the
    /// corner noise, view corrections far beyond their priors), one sentence each; empty
    /// when none. `calibrate` also issues each as a UserWarning.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.file.warnings.clone()
    }

    /// The distortion family: "paper" (Eq. 17, the default) or "opencv" (OpenCV's k1, k2,
    /// p1, p2, k3 in normalised coordinates, each quadratic in 1 / f_mean).
    #[getter]
    fn distortion_model(&self) -> &'static str {
        self.model.distortion_model().name()
    }

    /// The degree of fx(E), fy(E) (3: the paper's cubic).
    #[getter]
    fn focal_degree(&self) -> usize {
        self.model.focal_degree()
    }

    /// How the model was chosen when `calibrate(distortion="auto")` or
    /// `focal_degree="auto"` chose it: a dict {"method", "rule", "candidates": [{
    /// "distortion_model", "focal_degree", "parameters", "fit_rms_px", "prediction_rms_px",
    /// "excess_mse_px2", "excess_se_px2", "chosen", "error"?}]}; None when the model was
    /// given.
    #[getter]
    fn model_selection<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(sel) = &self.file.model_selection else { return Ok(None) };
        let text = serde_json::to_string(sel).map_err(|e| input_error(e.to_string()))?;
        Ok(Some(py.import("json")?.call_method1("loads", (text,))?))
    }

    /// Where the thermal part came from: "paper" (chosen explicitly), a thermal file's
    /// path, or None (no thermal part, or an older file that does not say).
    #[getter]
    fn thermal_source(&self) -> Option<String> {
        self.file.thermal.as_ref()?.source.clone()
    }

    /// The camera at driver current `e_in_ma` and lens temperature `temperature_c`
    /// (E_com = E_in - E_T(T, E_in), then K and distortion at E_com): a CameraAt, which
    /// projects, undistorts, casts rays, solves PnP and exports at that setting.
    ///
    /// Args:
    ///     e_in_ma: driver current, mA.
    ///     temperature_c: lens temperature, degC.
    ///     focal_power_dpt: the commanded focal power, dpt, instead of `e_in_ma`, for a
    ///         focal-power calibration (`setting == "focal_power"`; keyword only).
    ///     allow_extrapolation: return the camera outside the calibrated temperature,
    ///         E_in and E_com (or focal-power) ranges too (then `extrapolated` is True).
    ///
    /// Raises: InputError naming the quantity outside its calibrated range (margins:
    /// 1 degC, 5 mA, 5 mA, 0.25 dpt), when the calibration has no thermal part (then use
    /// `at_e_com` with a known E_com), or when not exactly one of `e_in_ma` and
    /// `focal_power_dpt` is given, or the one given is not the calibration's setting.
    #[pyo3(signature = (e_in_ma=None, temperature_c=None, *, focal_power_dpt=None, allow_extrapolation=false))]
    fn at(
        slf: &Bound<'_, Self>,
        e_in_ma: Option<f64>,
        temperature_c: Option<f64>,
        focal_power_dpt: Option<f64>,
        allow_extrapolation: bool,
    ) -> PyResult<CameraAt> {
        let Some(temperature_c) = temperature_c else {
            return Err(invalid("temperature_c", "give the lens temperature temperature_c, degC"));
        };
        let focal = slf.get().file.setting_kind() == etl_formats::SettingKind::FocalPower;
        match (e_in_ma, focal_power_dpt) {
            (Some(e_in_ma), None) if !focal => {
                Self::camera_at_setting(slf, e_in_ma, temperature_c, allow_extrapolation)
            }
            (None, Some(dpt)) if focal => {
                let cal = slf.get();
                let inner = cal.camera()?.at_focal_power_with(dpt, temperature_c, trust(allow_extrapolation)).py()?;
                Ok(CameraAt::new(inner, slf.clone().into_any().unbind(), cal.file.clone()))
            }
            (Some(_), Some(_)) | (None, None) => {
                Err(invalid("e_in_ma", "give exactly one of e_in_ma (mA) and focal_power_dpt (dpt)"))
            }
            (_, None) => Err(invalid(
                "focal_power_dpt",
                "this calibration's setting is the focal power: give focal_power_dpt=, not e_in_ma",
            )),
            (None, _) => Err(invalid(
                "e_in_ma",
                "this calibration's setting is the lens current: give e_in_ma, not focal_power_dpt",
            )),
        }
    }

    /// What the calibration's setting is: "current" (its polynomials are in E_com, mA) or
    /// "focal_power" (in the focal power commanded in the driver's focal-power mode, dpt).
    #[getter]
    fn setting(&self) -> &'static str {
        self.file.setting_kind().name()
    }

    /// (min, max) focal power a focal-power calibration covers, dpt; None for a current
    /// calibration.
    #[getter]
    fn focal_power_range_dpt(&self) -> Option<(f64, f64)> {
        self.file.focal_power_range_dpt.map(|[a, b]| (a, b))
    }

    /// The focal power (dpt) that focuses a focal-power calibration's camera at
    /// `distance_mm` at lens temperature `temperature_c` (the law in dioptres; the driver
    /// compensates the temperature).
    ///
    /// Raises: InputError when the calibration is not a focal-power one or has no focus
    /// law, for a distance outside the law's calibrated distances (+- 2 %), or a power or
    /// temperature outside the calibrated ranges unless `allow_extrapolation`.
    #[pyo3(signature = (distance_mm, temperature_c, *, allow_extrapolation=false))]
    fn focus_focal_power_dpt(&self, distance_mm: f64, temperature_c: f64, allow_extrapolation: bool) -> PyResult<f64> {
        self.file.focus_focal_power_dpt(distance_mm, temperature_c, trust(allow_extrapolation)).py()
    }

    /// The camera at a known compensated current `e_com_ma` (a calibration without
    /// temperature compensation, `temperature_compensation == "none"`, or E_com
    /// compensated elsewhere): a CameraAt, whose `e_in_ma` and `temperature_c` are None.
    /// Every method of Calibration taking `e_com_ma` is this camera's.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA.
    ///     allow_extrapolation: return the camera outside the calibrated E_com range too
    ///         (then `extrapolated` is True; keyword only).
    ///
    /// Raises: InputError for a current outside the calibrated E_com range (margin 5 mA)
    /// or not finite.
    #[pyo3(signature = (e_com_ma, *, allow_extrapolation=false))]
    fn at_e_com(slf: &Bound<'_, Self>, e_com_ma: f64, allow_extrapolation: bool) -> PyResult<CameraAt> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)
    }

    /// "none" when the calibration was made from views with a recorded E_com and no
    /// thermal calibration (it is used at a known E_com only, `at_e_com`); None otherwise
    /// (a thermal part, or a file that does not say).
    #[getter]
    fn temperature_compensation(&self) -> Option<&'static str> {
        self.file.temperature_compensation.map(|etl_formats::calibration::TemperatureCompensation::None| "none")
    }

    /// RMS reprojection error of the calibration, px (0 for a model given, not estimated).
    #[getter]
    fn rms_px(&self) -> f64 {
        self.file.rms_reprojection_px
    }

    /// RMS reprojection error before bundle adjustment, px (0 when not estimated).
    #[getter]
    fn initial_rms_px(&self) -> f64 {
        self.file.initial_rms_px
    }

    /// The estimator that produced the calibration: "paper", "eiv", or None for a model
    /// given, not estimated.
    #[getter]
    fn estimator(&self) -> Option<String> {
        (!self.file.estimator.is_empty()).then(|| self.file.estimator.clone())
    }

    /// What the covariance accounts for: a dict with "sigma_px" (the pixel noise, px) and,
    /// where the covariance includes the errors of the recorded stage positions and
    /// currents, "sigma_z_mm" and "sigma_e_ma" ("sigma_p_dpt", dpt, at focal powers; the
    /// "eiv" priors, or the "paper" estimator's input noise). None for files written
    /// before it was recorded (a "paper" covariance there is of the pixel noise alone)
    /// and for models given.
    #[getter]
    fn covariance_noise<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(n) = &self.file.covariance_noise else { return Ok(None) };
        let d = PyDict::new(py);
        d.set_item("sigma_px", n.sigma_px)?;
        if let (Some(z), Some(e)) = (n.sigma_z_mm, n.sigma_e_ma) {
            d.set_item("sigma_z_mm", z)?;
            d.set_item("sigma_e_ma", e)?;
        }
        // A focal-power calibration's: the prior on the commanded power, dpt.
        if let (Some(z), Some(p)) = (n.sigma_z_mm, n.sigma_p_dpt) {
            d.set_item("sigma_z_mm", z)?;
            d.set_item("sigma_p_dpt", p)?;
        }
        Ok(Some(d))
    }

    /// Bundle-adjustment iterations (0 when not estimated).
    #[getter]
    fn iterations(&self) -> usize {
        self.file.iterations
    }

    /// Per-view summaries of the calibration: a list of ViewSummary (attributes, also dict
    /// keys) with every key of the
    /// file's `views` entries: e_com_ma (mA), points, rms_px (px), dz_mm (mm) and de_ma
    /// (mA) (the errors-in-variables corrections; 0 for the paper's estimator), fx_px and
    /// fy_px (px; the focal lengths refitted to that view alone).
    #[getter]
    fn views<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        self.file
            .views
            .iter()
            .map(|v| {
                // Through the file's own serialisation, so a key added to the format
                // reaches Python without a second list of names here.
                let serde_json::Value::Object(fields) =
                    serde_json::to_value(v).map_err(|e| input_error(e.to_string()))?
                else {
                    return Err(input_error("a view summary is not a JSON object"));
                };
                let d = PyDict::new(py);
                for (key, value) in fields {
                    match value.as_u64() {
                        Some(n) => d.set_item(key, n)?,
                        None => d.set_item(key, value.as_f64())?,
                    }
                }
                crate::results::make(py, "ViewSummary", &d)
            })
            .collect()
    }

    /// One standard deviation of each model number: a ModelStd (attributes, also dict keys)
    /// rotation_rodrigues, translation_mm, kf_x, kf_y, principal_point, distortion_a
    /// (float64 arrays, units as the numbers'; zeros for a model given, not estimated).
    #[getter]
    fn std<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        std_dict(py, &self.file.std)
    }

    /// The compensated current E_com = E_in - E_T(T, E_in), mA (Eq. 8).
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    ///     allow_extrapolation: evaluate outside the calibrated temperature and E_in
    ///         ranges too (keyword only).
    ///
    /// Raises: InputError when the calibration has no thermal part, or for values
    /// outside the calibrated ranges (naming the quantity; margins 1 degC, 5 mA).
    #[pyo3(signature = (e_in_ma, temperature_c, *, allow_extrapolation=false))]
    fn e_com<'py>(
        &self,
        e_in_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let t = self.file.thermal_ref().map_err(crate::errors::calib_err)?.trust();
        at_temperature(e_in_ma, temperature_c, "e_in_ma", allow_extrapolation, |e, c, policy| {
            Ok(e - t.e_t_ma(e, c, policy).py()?.0)
        })
    }

    /// The driver current that gives `e_com_ma` at `temperature_c`, mA (inverse of
    /// `e_com`).
    ///
    /// Args:
    ///     e_com_ma: wanted compensated current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    ///     allow_extrapolation: as in `e_com` (the E_in found is checked).
    #[pyo3(signature = (e_com_ma, temperature_c, *, allow_extrapolation=false))]
    fn e_in_for_e_com<'py>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let t = self.file.thermal_ref().map_err(crate::errors::calib_err)?.trust();
        at_temperature(e_com_ma, temperature_c, "e_com_ma", allow_extrapolation, |e, c, policy| {
            let e_in = t.surface.e_in_for_e_com(e, c).py()?;
            t.e_t_ma(e_in, c, policy).py()?;
            Ok(e_in)
        })
    }

    /// The focus law of the calibration, or None when it has none: a FocusLaw (attributes,
    /// also dict keys):
    /// coefficients_ma (c0 mA, c1 mA/dpt, c2 mA/dpt^2 of E_com = c0 + c1 V + c2 V^2 with
    /// V = 1000 / distance_mm), distance_range_mm and e_com_range_ma (the fitted views'
    /// (min, max)), rms_ma (the views' current residual) and views (how many were fitted).
    /// The distance is the depth of the plane in focus: along the optical axis from the
    /// camera's centre, mm.
    #[getter]
    fn focus_law<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(law) = &self.file.focus_law else { return Ok(None) };
        let d = PyDict::new(py);
        let c = law.coefficients_ma;
        d.set_item("coefficients_ma", (c[0], c[1], c[2]))?;
        d.set_item("distance_range_mm", (law.distance_range_mm[0], law.distance_range_mm[1]))?;
        d.set_item("e_com_range_ma", (law.e_com_range_ma[0], law.e_com_range_ma[1]))?;
        d.set_item("rms_ma", law.rms_ma)?;
        d.set_item("views", law.views)?;
        crate::results::make(py, "FocusLaw", &d).map(Some)
    }

    /// The driver current E_in (mA) that focuses the camera at `distance_mm` at lens
    /// temperature `temperature_c`: E_com from the focus law, then the E_in that gives it
    /// through the thermal surface.
    ///
    /// Args:
    ///     distance_mm: depth of the plane to focus on (along the optical axis from the
    ///         camera's centre), mm (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    ///     allow_extrapolation: outside the calibrated temperature and current ranges too
    ///         (keyword only; the law's distance range is always enforced).
    ///
    /// Raises: InputError when the calibration has no focus law ("this calibration has no
    /// focus law") or no thermal part, for a distance outside the law's calibrated
    /// distances (+- 2 % of their span), or a setting outside the calibrated ranges.
    #[pyo3(signature = (distance_mm, temperature_c, *, allow_extrapolation=false))]
    fn focus_e_in<'py>(
        &self,
        distance_mm: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        at_temperature(distance_mm, temperature_c, "distance_mm", allow_extrapolation, |d, c, policy| {
            self.file.focus_e_in(d, c, policy).map_err(crate::errors::calib_err)
        })
    }

    /// The distance in focus (mm, as in `focus_e_in`) at driver current `e_in_ma` and lens
    /// temperature `temperature_c`.
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    ///     allow_extrapolation: as in `focus_e_in`.
    ///
    /// Raises: InputError when the calibration has no focus law or no thermal part, for
    /// an E_com outside the law's calibrated currents (+- 2 % of their span), or a
    /// setting outside the calibrated ranges.
    #[pyo3(signature = (e_in_ma, temperature_c, *, allow_extrapolation=false))]
    fn focus_distance_mm<'py>(
        &self,
        e_in_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        at_temperature(e_in_ma, temperature_c, "e_in_ma", allow_extrapolation, |e, c, policy| {
            self.file.focus_distance_mm(e, c, policy).map_err(crate::errors::calib_err)
        })
    }

    /// (fx, fy) at the compensated current, px (Eq. 16: fx(E) = sum kf_x[k] E^k;
    /// `CameraAt.focal_lengths` at each current).
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA: a number, or an array of any shape S
    ///         (vectorised: then fx and fy are float64 arrays of shape S).
    ///     allow_extrapolation: outside the calibrated E_com range too (keyword only).
    ///
    /// Raises: InputError for a current outside the calibrated range (+- 5 mA).
    #[pyo3(signature = (e_com_ma, *, allow_extrapolation=false))]
    fn focal_lengths<'py>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let parts = self.per_current(e_com_ma, allow_extrapolation, [&[], &[]], camera::focal_parts)?;
        Ok(PyTuple::new(e_com_ma.py(), parts)?.into_any())
    }

    /// The intrinsic matrix A(E) = [[fx, 0, u0], [0, fy, v0], [0, 0, 1]] (Eq. 15), px
    /// (`CameraAt.camera_matrix` at each current).
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA: a number, or an array of shape S
    ///         (vectorised).
    ///     allow_extrapolation: outside the calibrated E_com range too (keyword only).
    ///
    /// Returns: a 3 x 3 float64 array (S + (3, 3) for an array of currents).
    #[pyo3(signature = (e_com_ma, *, allow_extrapolation=false))]
    fn intrinsics<'py>(&self, e_com_ma: &Bound<'py, PyAny>, allow_extrapolation: bool) -> PyResult<Bound<'py, PyAny>> {
        let [k] = self.per_current(e_com_ma, allow_extrapolation, [&[3, 3]], camera::intrinsics_parts)?;
        Ok(k)
    }

    /// The distortion coefficients at the compensated current (Eq. 18), named for the
    /// calibration's family (`CameraAt.distortion` at each current):
    ///
    /// - "paper" (Eq. 17, pixel coordinates centred on the principal point, with Weng's
    ///   decentering term): a PaperDistortion (k1 in 1/px^2, p1 and p2 in 1/px), the tuple
    ///   (k1, p1, p2) as before (`k1, p1, p2 = cal.distortion(E)`);
    /// - "opencv" (OpenCV's model in normalised coordinates): an OpenCvDistortion, the
    ///   tuple (k1, k2, p1, p2, k3) in OpenCV's order, dimensionless.
    ///
    /// Each has one attribute per coefficient, `model` (the family), `names` and
    /// `to_dict()`.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA: a number, or an array of shape S
    ///         (vectorised: then each coefficient is a float64 array of shape S).
    ///     allow_extrapolation: outside the calibrated E_com range too (keyword only).
    #[pyo3(signature = (e_com_ma, *, allow_extrapolation=false))]
    fn distortion<'py>(&self, e_com_ma: &Bound<'py, PyAny>, allow_extrapolation: bool) -> PyResult<Bound<'py, PyAny>> {
        let parts =
            self.per_current(e_com_ma, allow_extrapolation, camera::DISTORTION_SHAPES, camera::distortion_parts)?;
        camera::distortion_out(e_com_ma.py(), self.model.distortion_model(), parts)
    }

    /// Projects world points to observed pixels (Eq. 13-18): `at_e_com(e_com_ma).project`.
    ///
    /// Args:
    ///     world_mm: world points, mm: an (N, 3) array (or one point of shape (3,)).
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: the pixels, an (N, 2) float64 array (or (2,)), with (0, 0) the centre of
    /// the top-left pixel.
    ///
    /// Raises: InputError for a NaN, a point at or behind the camera, a current where
    /// the focal length is not positive.
    #[pyo3(signature = (world_mm, e_com_ma, *, allow_extrapolation=false))]
    fn project<'py>(
        slf: &Bound<'py, Self>,
        world_mm: &Bound<'py, PyAny>,
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.project(world_mm)
    }

    /// Removes the distortion from observed pixels: the pixels they would have without
    /// distortion, in the same image frame (Eq. 17 inverted; accurate to 1e-9 px):
    /// `at_e_com(e_com_ma).undistort`.
    ///
    /// Args:
    ///     pixels: observed pixels, px: an (N, 2) array (or (2,)).
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: an (N, 2) float64 array (or (2,)), px.
    ///
    /// Raises: InputError for a NaN or a pixel beyond the fold of the distortion model;
    /// NotConvergedError if the inversion misses its tolerance.
    #[pyo3(signature = (pixels, e_com_ma, *, allow_extrapolation=false))]
    fn undistort<'py>(
        slf: &Bound<'py, Self>,
        pixels: &Bound<'py, PyAny>,
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.undistort(pixels)
    }

    /// The viewing ray of a pixel in world coordinates: `at_e_com(e_com_ma).ray`.
    ///
    /// Args:
    ///     pixel: observed pixel (u, v), px.
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: (origin_mm, direction): the centre of projection in world coordinates
    /// (mm) and the unit direction, float64 arrays of shape (3,).
    #[pyo3(signature = (pixel, e_com_ma, *, allow_extrapolation=false))]
    fn ray<'py>(
        slf: &Bound<'py, Self>,
        pixel: (f64, f64),
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.ray(slf.py(), pixel)
    }

    /// The pose of a planar board from its observed corners (plane-based PnP: a
    /// closed-form start from the homography, then Levenberg-Marquardt through the full
    /// model, distortion included), with its uncertainty: `at_e_com(e_com_ma).solve_pnp`.
    /// The calibration's own R, T are not used.
    ///
    /// The uncertainty (`BoardPose.covariance`, `BoardPose.displacement_std_mm`) is first
    /// order: the pixel noise's sigma^2 (J^T J)^-1, and the calibration's covariance C
    /// carried through S = d pose / d calibration = -(J^T J)^-1 J^T J_cal.
    ///
    /// Args:
    ///     board_mm: (N, 3) board points in the board frame, mm, all with Z = 0 (N >= 4,
    ///         not all on one line).
    ///     pixels: (N, 2) observed pixels, px.
    ///     e_com_ma: compensated current, mA.
    ///     sigma_px: the pixel noise standard deviation, px; None (the default):
    ///         estimated from the fit's residual, sqrt(sum |r|^2 / (2 N - 6)).
    ///
    /// Returns: a BoardPose (board -> camera).
    ///
    /// Raises: InputError for fewer than 4 points, a length mismatch, Z != 0, collinear
    /// points, NaN, a negative sigma_px, a current outside the calibrated range (unless
    /// allow_extrapolation); NotConvergedError if the solver fails.
    #[pyo3(signature = (board_mm, pixels, e_com_ma, sigma_px=None, *, allow_extrapolation=false))]
    fn solve_pnp(
        slf: &Bound<'_, Self>,
        board_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        e_com_ma: f64,
        sigma_px: Option<f64>,
        allow_extrapolation: bool,
    ) -> PyResult<BoardPose> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.solve_pnp(slf.py(), board_mm, pixels, sigma_px)
    }

    /// The covariance of the 25 calibrated numbers, a 25 x 25 float64 array in the order
    /// om1..om3, tx..tz, kf_x, kf_y, u0, v0, a1..a9 (its diagonal is `std` squared), or
    /// None for a calibration without one (files written before it was recorded, a
    /// calibration built from numbers).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.file.covariance.as_deref().and_then(|rows| crate::arrays::square_out(py, rows))
    }

    /// The standard deviation of projected pixels due to the calibration's uncertainty:
    /// sqrt of the diagonal of J_p C J_p^T, with J_p the Jacobian of the projection
    /// (Eq. 13-18) with respect to the 25 numbers and C `covariance` (first order):
    /// `at_e_com(e_com_ma).projection_std`.
    ///
    /// Args:
    ///     world_mm: world points, mm: an (N, 3) array (or one point of shape (3,)).
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: the standard deviations of u and of v, px: an (N, 2) float64 array (or
    /// (2,)).
    ///
    /// Raises: InputError for a calibration without a covariance, a NaN, a point at or
    /// behind the camera, a current outside the calibrated range (unless
    /// allow_extrapolation).
    #[pyo3(signature = (world_mm, e_com_ma, *, allow_extrapolation=false))]
    fn projection_std<'py>(
        slf: &Bound<'py, Self>,
        world_mm: &Bound<'py, PyAny>,
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.projection_std(world_mm)
    }

    /// The standard deviation of the re-projection of the point seen at each pixel, in
    /// mrcal's sense (`mrcal.projection_uncertainty`; `ZhangResult.projection_std` for a
    /// monofocal calibration): the point at `distance_mm` from the projection centre along
    /// the pixel's ray at `e_com_ma`, or for None in that direction (a point at infinity),
    /// held fixed in the stage frame while the calibration varies within its covariance.
    ///
    /// Args:
    ///     pixels: pixels, px: an (N, 2) array (or one pixel of shape (2,)).
    ///     e_com_ma: compensated current, mA.
    ///     distance_mm: the distance along the ray, mm, a number > 0; None: the direction.
    ///     allow_extrapolation: outside the calibrated E_com range too (keyword only).
    ///
    /// Returns: the standard deviations of u and of v, px: an (N, 2) float64 array (or
    /// (2,)).
    ///
    /// Raises: InputError for a calibration without a covariance, a NaN, a distance that
    /// is not a finite number > 0, a pixel that does not unproject, a current outside the
    /// calibrated range (unless allow_extrapolation).
    #[pyo3(signature = (pixels, e_com_ma, distance_mm=None, *, allow_extrapolation=false))]
    fn pixel_projection_std<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        e_com_ma: f64,
        distance_mm: Option<f64>,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = crate::arrays::points::<2>(pixels, "pixels")?;
        let (file, trust) = (&self.file, trust(allow_extrapolation));
        let out = crate::pool::detach(py, || {
            p.points
                .iter()
                .map(|q| file.pixel_projection_std(*q, e_com_ma, distance_mm, trust).map(|u| u.std_px))
                .collect::<etl_formats::Result<Vec<[f64; 2]>>>()
        })
        .map_err(crate::errors::calib_err)?;
        crate::arrays::points_out(py, out, p.single)
    }

    /// The camera at one current in OpenCV's conventions, for `cv2.projectPoints`,
    /// `cv2.undistortPoints`, `cv2.initUndistortRectifyMap`, `cv2.solvePnP`
    /// (`CameraAt.to_opencv` at each current).
    ///
    /// The opencv family (`distortion_model == "opencv"`) is OpenCV's model: K and its own
    /// coefficients at that current, exact (`cv2.projectPoints` reproduces `project`;
    /// `exact` True, fit errors 0). The paper family (Eq. 17) acts on centred pixels, not
    /// on normalised coordinates: the two agree exactly only when fx = fy (k1_cv = k1 f^2,
    /// p1_cv = p2 f, p2_cv = p1 f); otherwise the coefficients are the least-squares fit
    /// over the image, and the result says how far OpenCV's projection with them is from
    /// the model's (`fit_rms_px`, `fit_max_px`; a few hundredths of a pixel on the paper
    /// rig; `exact` False). `export` writes the same.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA: a number, or an array of shape S
    ///         (vectorised).
    ///     allow_extrapolation: outside the calibrated E_com range too (keyword only).
    ///
    /// Returns: an OpenCvCamera: the tuple (K, dist) as before (`K, dist =
    /// cal.to_opencv(E)`): the 3 x 3 camera matrix (px) and the 5 coefficients (k1, k2,
    /// p1, p2, k3); for an array of currents, K of shape S + (3, 3) and dist of shape
    /// S + (5,). Its attributes: camera_matrix, dist_coeffs, fit_rms_px and fit_max_px
    /// (px; shape S for an array), exact.
    #[pyo3(signature = (e_com_ma, *, allow_extrapolation=false))]
    fn to_opencv<'py>(&self, e_com_ma: &Bound<'py, PyAny>, allow_extrapolation: bool) -> PyResult<Bound<'py, PyAny>> {
        let parts = self.per_current(e_com_ma, allow_extrapolation, camera::OPENCV_SHAPES, camera::opencv_parts)?;
        camera::opencv_out(e_com_ma.py(), self.model.distortion_model(), parts)
    }

    /// Writes the camera at one setting for another tool (atomically; nothing on error):
    /// `at(e_in_ma, temperature_c).export(path, format)` (at a known E_com:
    /// `at_e_com(e_com_ma).export(path, format)`).
    ///
    /// Args:
    ///     path: the file to write.
    ///     e_in_ma: driver current, mA.
    ///     temperature_c: lens temperature, degC.
    ///     format: "opencv" (FileStorage YAML: camera_matrix, distortion_coefficients,
    ///         image_width, image_height), "ros" (camera_info YAML) or "mrcal"
    ///         (.cameramodel, LENSMODEL_OPENCV5).
    ///     allow_extrapolation: export outside the calibrated ranges too (keyword only).
    ///
    /// Returns: an ExportResult (attributes, also dict keys): "e_com_ma", "camera_matrix" (3 x 3), "dist_coeffs" (k1, k2,
    /// p1, p2, k3: the least-squares fit of etlcal's distortion over the image) and the
    /// fit's error "fit_rms_px", "fit_max_px" (also written into the file).
    #[pyo3(signature = (path, e_in_ma, temperature_c, format, *, allow_extrapolation=false))]
    fn export<'py>(
        slf: &Bound<'py, Self>,
        path: PathBuf,
        e_in_ma: f64,
        temperature_c: f64,
        format: &str,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        Self::camera_at_setting(slf, e_in_ma, temperature_c, allow_extrapolation)?.export(slf.py(), path, format)
    }

    /// The undistortion maps at the compensated current, in cv2.remap's convention: for
    /// every output pixel (x, y) (pixel centres at integer coordinates), the pixel of the
    /// distorted image it sees: `cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR)` (or
    /// `undistort_image`) undistorts an image taken at that current
    /// (`at_e_com(e_com_ma).undistort_maps`).
    ///
    /// Exact for the model: map = the model's projection (Eq. 15, 17) of the output
    /// pixel's ray ((x - cx) / fx, (y - cy) / fy, 1), computed in float64 and rounded once
    /// to float32 (1.2e-4 px at most over 1936 x 1458); no inversion, no approximation.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA, within the calibrated range (+- 5 mA)
    ///         unless allow_extrapolation=True (keyword only).
    ///     new_camera_matrix: the output camera [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (px,
    ///         no skew), or None for the model's own K(E) without distortion.
    ///     size: (width, height) of the output, px, or None for the calibration's image
    ///         size.
    ///
    /// Returns: (map_x, map_y), float32 arrays of shape (height, width).
    ///
    /// Raises: InputError for a current outside the calibrated range, a zero size, a
    /// matrix that is not a camera matrix.
    #[pyo3(signature = (e_com_ma, new_camera_matrix=None, size=None, *, allow_extrapolation=false))]
    fn undistort_maps<'py>(
        slf: &Bound<'py, Self>,
        e_com_ma: f64,
        new_camera_matrix: Option<&Bound<'py, PyAny>>,
        size: Option<&Bound<'py, PyAny>>,
        allow_extrapolation: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.undistort_maps(slf.py(), new_camera_matrix, size)
    }

    /// The undistorted image: the image taken at the compensated current as the camera
    /// K(E) without distortion sees it (same size), by the exact maps of
    /// `undistort_maps` and bilinear interpolation (pixels whose source lies outside the
    /// image are 0, as cv2.remap's default BORDER_CONSTANT): `at_e_com(e_com_ma).undistort_image`.
    ///
    /// Args:
    ///     image: a numpy array of dtype uint8, uint16 or float32, of shape (h, w) or
    ///         (h, w, 3) (channels interleaved), of the calibration's image size.
    ///     e_com_ma: compensated current, mA, within the calibrated range (+- 5 mA)
    ///         unless allow_extrapolation=True (keyword only).
    ///
    /// Returns: an array of the same shape and dtype.
    ///
    /// Raises: InputError for another dtype or shape, an image of another size than the
    /// calibration's, a current outside the calibrated range.
    #[pyo3(signature = (image, e_com_ma, *, allow_extrapolation=false))]
    fn undistort_image<'py>(
        slf: &Bound<'py, Self>,
        image: &Bound<'py, PyAny>,
        e_com_ma: f64,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        Self::camera_at_e_com(slf, e_com_ma, allow_extrapolation)?.undistort_image(image)
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("Calibration.__repr__", || {
            let m = &self.model;
            format!(
            "Calibration(kf_x={:?}, kf_y={:?}, principal_point={:?}, image_size={:?}, e_com_range_ma={:?}, thermal={}, rms_px={:?})",
            m.kf_x.coefficients(),
            m.kf_y.coefficients(),
            m.principal_point,
            self.file.image_size,
            self.file.e_com_range_ma,
            self.file.thermal.is_some(),
            self.file.rms_reprojection_px
        )
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("Calibration.__reduce__", || {
            let py = slf.py();
            let text = slf.get().to_json()?;
            let ctor = py.get_type::<Calibration>().getattr("from_json")?;
            Ok((ctor, PyTuple::new(py, [text])?))
        })
    }
}

impl Calibration {
    /// The run-time camera of this calibration (the model kept, not rebuilt from the file):
    /// model, thermal part with its ranges, calibrated E_com range.
    pub(crate) fn camera(&self) -> PyResult<Camera> {
        match self.file.setting_kind() {
            etl_formats::SettingKind::Current => {
                Camera::new(self.model, self.file.thermal.as_ref().map(ThermalRef::trust), self.file.e_com_range_ma)
                    .py()
            }
            etl_formats::SettingKind::FocalPower => {
                Camera::new_focal_power(self.model, self.file.setting_range(), self.file.focal_power_t_range_c).py()
            }
        }
    }

    /// A per-current model function `f` (`crate::camera`'s `*_parts`, the ones `CameraAt`
    /// uses) at one current or elementwise over an array of them: its `P` parts, part p a
    /// row-major block of shape `part_shapes[p]`. For a scalar current, a part of shape ()
    /// is a float and any other an array of its shape; for an array of shape S, part p is
    /// an array of shape S + `part_shapes[p]` (every current range-checked as for a
    /// scalar).
    fn per_current<'py, const P: usize>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        allow_extrapolation: bool,
        part_shapes: [&[usize]; P],
        f: camera::PerCurrent<P>,
    ) -> PyResult<[Bound<'py, PyAny>; P]> {
        use crate::arrays::{currents, parts_out, Currents};
        let (shape, values, scalar) = match currents(e_com_ma, "e_com_ma")? {
            Currents::Scalar(e) => (Vec::new(), vec![e], true),
            Currents::Array { shape, values } => (shape, values, false),
        };
        let mut blocks: [Vec<f64>; P] = core::array::from_fn(|_| Vec::new());
        // The camera once, not per current.
        let camera = self.camera()?;
        for e in values {
            let at = camera.at_e_com(e, trust(allow_extrapolation)).py()?;
            for (block, part) in blocks.iter_mut().zip(f(&at, self.file.image_size)?) {
                block.extend(part);
            }
        }
        parts_out(e_com_ma.py(), &shape, scalar, blocks, part_shapes)
    }
}

/// `numpy.polynomial.Polynomial(coefficients)` (ascending powers).
/// `f(x, temperature, policy)` over two floats or arrays broadcast against each other
/// (numpy's rules; `what` names `x` in errors), with the extrapolation policy the caller
/// chose: the methods of a lens setting (or a distance) and a lens temperature.
fn at_temperature<'py>(
    x: &Bound<'py, PyAny>,
    temperature_c: &Bound<'py, PyAny>,
    what: &str,
    allow_extrapolation: bool,
    f: impl Fn(f64, f64, Trust) -> PyResult<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let policy = trust(allow_extrapolation);
    crate::arrays::map2(x, temperature_c, (what, "temperature_c"), |a, c| f(a, c, policy))
}

fn polynomial<'py>(py: Python<'py>, coefficients: &[f64]) -> PyResult<Bound<'py, PyAny>> {
    py.import("numpy.polynomial")?.getattr("Polynomial")?.call1((vec_out(py, coefficients),))
}

/// A `thermal=` argument: a ThermalCalibration (kept with its ranges), the string
/// "paper" (the paper's surface and ranges, chosen explicitly) or a bare ThermalSurface
/// (no ranges known).
pub(crate) fn thermal_ref(t: &Bound<'_, PyAny>) -> PyResult<ThermalRef> {
    if let Ok(word) = t.extract::<String>() {
        return match word.as_str() {
            etl_formats::calibration::PAPER_THERMAL => Ok(ThermalRef::paper()),
            _ => {
                Err(invalid_value("thermal", &word, format!("thermal = {word:?}: the only word accepted is \"paper\"")))
            }
        };
    }
    if let Ok(c) = t.extract::<ThermalCalibration>() {
        let file = etl_formats::thermal::ThermalFile::new(&c.inner, c.rms_ma);
        return Ok(ThermalRef { source: None, ..ThermalRef::from_file(&file, "") });
    }
    let s: ThermalSurface = t
        .extract()
        .map_err(|_| invalid("thermal", "thermal must be a ThermalCalibration, \"paper\", a ThermalSurface or None"))?;
    Ok(ThermalRef {
        coefficients: s.inner.coefficients,
        t_range_c: None,
        e_in_range_ma: None,
        rms_ma: None,
        source: None,
    })
}

/// A `ModelStd` as an `etlcal.results.ModelStd` of float64 arrays under the model's keys.
pub(crate) fn std_dict<'py>(py: Python<'py>, s: &ModelStd) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("rotation_rodrigues", vec_out(py, &s.rotation_rodrigues))?;
    d.set_item("translation_mm", vec_out(py, &s.translation_mm))?;
    d.set_item("kf_x", vec_out(py, &s.kf_x))?;
    d.set_item("kf_y", vec_out(py, &s.kf_y))?;
    d.set_item("principal_point", vec_out(py, &s.principal_point))?;
    d.set_item("distortion_a", vec_out(py, &s.distortion_a))?;
    crate::results::make(py, "ModelStd", &d)
}
