//! `Calibration`: a calibrated ETL camera (`etlcal.calibration/1`) and what is done with
//! it at run time: (E_in, T) -> E_com -> K(E_com), distortion(E_com) -> project /
//! undistort / rays.

use std::path::{Path, PathBuf};

use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface as CoreSurface;
use etl_formats::calibration::{Calibration as CalFile, ModelStd, ThermalRef};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::arrays::{mat3_out, points, points_out, vec_out};
use crate::errors::{input_error, CoreResultExt};
use crate::pose::BoardPose;
use crate::thermal::ThermalSurface;

/// Points above which `project` / `undistort` release the GIL (below it the release
/// costs more than it lets other threads gain).
const DETACH_POINTS: usize = 4096;

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
///     kf_x: fx(E) = kf_x[0] + kf_x[1] E + kf_x[2] E^2 + kf_x[3] E^3, px with E in mA.
///     kf_y: fy(E), as kf_x.
///     principal_point: (u0, v0), px.
///     distortion_a: a1..a9 of Eq. 18 (9 numbers).
///     image_size: (width, height), px.
///     e_com_range_ma: (min, max) compensated current the calibration covers, mA.
///     thermal: the temperature compensation (a ThermalSurface), or None.
///     rms_px: RMS reprojection error, px, or None.
///
/// Raises: InputError for NaN or infinite numbers, a non-positive image size, an
/// unordered range.
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct Calibration {
    pub(crate) file: CalFile,
    /// `file.model()`, kept to avoid rebuilding it on every call.
    pub(crate) model: CameraModel,
}

impl Calibration {
    /// A calibration of `model` with no thermal part, zero standard deviations and zero
    /// RMS (an exact model, not an estimate).
    pub fn from_model(model: CameraModel, image_size: [u32; 2], e_com_range_ma: [f64; 2]) -> Self {
        Calibration::from_file(CalFile::from_model(&model, image_size, e_com_range_ma))
    }

    /// Wraps a calibration file's content.
    pub fn from_file(file: CalFile) -> Self {
        let model = file.model();
        Calibration { file, model }
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
        thermal: Option<ThermalSurface>,
        rms_px: f64,
    ) -> PyResult<Self> {
        use crate::arrays::fixed;
        let model = CameraModel {
            rotation_rodrigues: fixed::<3>(rotation_rodrigues, "rotation_rodrigues")?,
            translation_mm: fixed::<3>(translation_mm, "translation_mm")?,
            kf_x: fixed::<4>(kf_x, "kf_x")?,
            kf_y: fixed::<4>(kf_y, "kf_y")?,
            principal_point: fixed::<2>(principal_point, "principal_point")?,
            distortion_a: fixed::<9>(distortion_a, "distortion_a")?,
        };
        model.validate().py()?;
        etl_core::error::finite(rms_px, "rms_px").py()?;
        let mut c = Calibration::from_model(model, [image_size.0, image_size.1], [e_com_range_ma.0, e_com_range_ma.1]);
        c.file.thermal = thermal.map(|t| ThermalRef { coefficients: t.inner.coefficients });
        c.file.rms_reprojection_px = rms_px;
        c.file.validate(Path::new("<Calibration>")).py()?;
        Ok(c)
    }

    /// The simulated rig of the paper (section 5.1.2) with the paper's temperature
    /// compensation: 1936 x 1458 px, E_com 80..225 mA.
    #[staticmethod]
    fn paper_rig() -> Self {
        let [w, h] = CameraModel::PAPER_IMAGE_SIZE;
        let mut c = Calibration::from_model(CameraModel::paper_rig(), [w, h], [80.0, 225.0]);
        c.file.thermal = Some(ThermalRef { coefficients: CoreSurface::PAPER.coefficients });
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
        let text = std::fs::read_to_string(&path)
            .map_err(|source| crate::errors::calib_err(etl_calib::Error::Io { path: path.clone(), source }))?;
        Ok(Calibration::from_file(parse_file(&text, &path)?))
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
        serde_json::to_string_pretty(&self.file).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.calibration/1` JSON text.
    ///
    /// Args:
    ///     text: the JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Ok(Calibration::from_file(parse_file(text, Path::new("<json>"))?))
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
        vec_out(py, &self.model.kf_x)
    }

    /// kf0y..kf3y of fy(E), px (E in mA).
    #[getter]
    fn kf_y<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.model.kf_y)
    }

    /// (u0, v0), px.
    #[getter]
    fn principal_point(&self) -> (f64, f64) {
        let [u, v] = self.model.principal_point;
        (u, v)
    }

    /// a1..a9 of Eq. 18.
    #[getter]
    fn distortion_a<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.model.distortion_a)
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
        self.file.thermal.map(|t| ThermalSurface { inner: CoreSurface { coefficients: t.coefficients } })
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

    /// Bundle-adjustment iterations (0 when not estimated).
    #[getter]
    fn iterations(&self) -> usize {
        self.file.iterations
    }

    /// Per-view summaries of the calibration: a list of dicts with every key of the
    /// file's `views` entries: e_com_ma (mA), points, rms_px (px), dz_mm (mm) and de_ma
    /// (mA) (the errors-in-variables corrections; 0 for the paper's estimator), fx_px and
    /// fy_px (px; the focal lengths refitted to that view alone).
    #[getter]
    fn views<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
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
                Ok(d)
            })
            .collect()
    }

    /// One standard deviation of each model number: a dict with the keys
    /// rotation_rodrigues, translation_mm, kf_x, kf_y, principal_point, distortion_a
    /// (float64 arrays, units as the numbers'; zeros for a model given, not estimated).
    #[getter]
    fn std<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        std_dict(py, &self.file.std)
    }

    /// The compensated current E_com = E_in - E_T(T, E_in), mA (Eq. 8).
    ///
    /// Args:
    ///     e_in_ma: driver current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    ///
    /// Raises: InputError when the calibration has no thermal part, or for values
    /// outside the lens's domain.
    fn e_com<'py>(
        &self,
        e_in_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let s = self.surface()?;
        crate::arrays::map2(e_in_ma, temperature_c, ("e_in_ma", "temperature_c"), |e, t| s.e_com_ma(e, t).py())
    }

    /// The driver current that gives `e_com_ma` at `temperature_c`, mA (inverse of
    /// `e_com`).
    ///
    /// Args:
    ///     e_com_ma: wanted compensated current, mA (a float or an array).
    ///     temperature_c: lens temperature, degC (a float or an array; broadcast).
    fn e_in_for_e_com<'py>(
        &self,
        e_com_ma: &Bound<'py, PyAny>,
        temperature_c: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let s = self.surface()?;
        crate::arrays::map2(e_com_ma, temperature_c, ("e_com_ma", "temperature_c"), |e, t| s.e_in_for_e_com(e, t).py())
    }

    /// (fx, fy) at the compensated current, px (Eq. 16).
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA.
    fn focal_lengths(&self, e_com_ma: f64) -> PyResult<(f64, f64)> {
        let k = self.model.intrinsics(e_com_ma).py()?;
        Ok((k.fx, k.fy))
    }

    /// The intrinsic matrix A(E) = [[fx, 0, u0], [0, fy, v0], [0, 0, 1]] (Eq. 15), px.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: a 3 x 3 float64 array.
    fn intrinsics<'py>(&self, py: Python<'py>, e_com_ma: f64) -> PyResult<Bound<'py, PyAny>> {
        let k = self.model.intrinsics(e_com_ma).py()?;
        Ok(mat3_out(py, k.matrix()))
    }

    /// The distortion coefficients (k1 in 1/px^2, p1 and p2 in 1/px) at the compensated
    /// current (Eq. 18), acting in pixel coordinates centred on the principal point
    /// (Eq. 17, with Weng's decentering term).
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA.
    fn distortion(&self, e_com_ma: f64) -> PyResult<(f64, f64, f64)> {
        let d = self.model.distortion(e_com_ma).py()?;
        Ok((d.k1, d.p1, d.p2))
    }

    /// Projects world points to observed pixels (Eq. 13-18).
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
    fn project<'py>(&self, world_mm: &Bound<'py, PyAny>, e_com_ma: f64) -> PyResult<Bound<'py, PyAny>> {
        let py = world_mm.py();
        let p = points::<3>(world_mm, "world_mm")?;
        let model = self.model;
        let mut out = vec![[0.0; 2]; p.points.len()];
        if p.points.len() > DETACH_POINTS {
            py.detach(|| model.project_many(&p.points, e_com_ma, &mut out)).py()?;
        } else {
            model.project_many(&p.points, e_com_ma, &mut out).py()?;
        }
        points_out(py, out, p.single)
    }

    /// Removes the distortion from observed pixels: the pixels they would have without
    /// distortion, in the same image frame (Eq. 17 inverted; accurate to 1e-9 px).
    ///
    /// Args:
    ///     pixels: observed pixels, px: an (N, 2) array (or (2,)).
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: an (N, 2) float64 array (or (2,)), px.
    ///
    /// Raises: InputError for a NaN or a pixel beyond the fold of the distortion model;
    /// NotConvergedError if the inversion misses its tolerance.
    fn undistort<'py>(&self, pixels: &Bound<'py, PyAny>, e_com_ma: f64) -> PyResult<Bound<'py, PyAny>> {
        let py = pixels.py();
        let p = points::<2>(pixels, "pixels")?;
        let model = self.model;
        let run = |pts: &[[f64; 2]]| -> etl_core::Result<Vec<[f64; 2]>> {
            pts.iter().map(|px| model.undistort(*px, e_com_ma)).collect()
        };
        let out = if p.points.len() > DETACH_POINTS { py.detach(|| run(&p.points)) } else { run(&p.points) }.py()?;
        points_out(py, out, p.single)
    }

    /// The viewing ray of a pixel in world coordinates.
    ///
    /// Args:
    ///     pixel: observed pixel (u, v), px.
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: (origin_mm, direction): the centre of projection in world coordinates
    /// (mm) and the unit direction, float64 arrays of shape (3,).
    fn ray<'py>(
        &self,
        py: Python<'py>,
        pixel: (f64, f64),
        e_com_ma: f64,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let r = self.model.ray([pixel.0, pixel.1], e_com_ma).py()?;
        Ok((vec_out(py, &r.origin_mm), vec_out(py, &r.direction)))
    }

    /// The pose of a planar board from its observed corners (plane-based PnP: a
    /// closed-form start from the homography, then Levenberg-Marquardt through the full
    /// model, distortion included). The calibration's own R, T are not used.
    ///
    /// Args:
    ///     board_mm: (N, 3) board points in the board frame, mm, all with Z = 0 (N >= 4,
    ///         not all on one line).
    ///     pixels: (N, 2) observed pixels, px.
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: a BoardPose (board -> camera).
    ///
    /// Raises: InputError for fewer than 4 points, a length mismatch, Z != 0, collinear
    /// points, NaN; NotConvergedError if the solver fails.
    fn solve_pnp(
        &self,
        py: Python<'_>,
        board_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        e_com_ma: f64,
    ) -> PyResult<BoardPose> {
        let b = points::<3>(board_mm, "board_mm")?;
        let p = points::<2>(pixels, "pixels")?;
        let model = self.model;
        let pose = py.detach(|| etl_core::pnp::solve_pnp(&model, e_com_ma, &b.points, &p.points)).py()?;
        Ok(BoardPose { inner: pose })
    }

    /// The camera at one current in OpenCV's conventions, for `cv2.projectPoints`,
    /// `cv2.undistortPoints`, `cv2.solvePnP`.
    ///
    /// OpenCV's distortion acts on normalised coordinates (u / f): k1_cv = k1 f^2 and the
    /// decentering terms swap names, p1_cv = p2 f, p2_cv = p1 f, with f the mean focal
    /// length; k2 = k3 = 0. Exact when fx = fy, an approximation otherwise.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA.
    ///
    /// Returns: (K, dist): the 3 x 3 camera matrix (px) and the 5 coefficients
    /// (k1, k2, p1, p2, k3).
    fn to_opencv<'py>(&self, py: Python<'py>, e_com_ma: f64) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let k = self.model.intrinsics(e_com_ma).py()?;
        let d = self.model.distortion(e_com_ma).py()?;
        let dist = d.to_opencv(0.5 * (k.fx + k.fy));
        Ok((mat3_out(py, k.matrix()), vec_out(py, &dist)))
    }

    /// The undistortion maps at the compensated current, in cv2.remap's convention: for
    /// every output pixel (x, y) (pixel centres at integer coordinates), the pixel of the
    /// distorted image it sees: `cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR)` (or
    /// `undistort_image`) undistorts an image taken at that current.
    ///
    /// Exact for the model: map = the model's projection (Eq. 15, 17) of the output
    /// pixel's ray ((x - cx) / fx, (y - cy) / fy, 1), computed in float64 and rounded once
    /// to float32 (1.2e-4 px at most over 1936 x 1458); no inversion, no approximation.
    ///
    /// Args:
    ///     e_com_ma: compensated current, mA, within the calibrated range (+- 5 mA).
    ///     new_camera_matrix: the output camera [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (px,
    ///         no skew), or None for the model's own K(E) without distortion.
    ///     size: (width, height) of the output, px, or None for the calibration's image
    ///         size.
    ///
    /// Returns: (map_x, map_y), float32 arrays of shape (height, width).
    ///
    /// Raises: InputError for a current outside the calibrated range, a zero size, a
    /// matrix that is not a camera matrix.
    #[pyo3(signature = (e_com_ma, new_camera_matrix=None, size=None))]
    fn undistort_maps<'py>(
        &self,
        py: Python<'py>,
        e_com_ma: f64,
        new_camera_matrix: Option<&Bound<'py, PyAny>>,
        size: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.check_map_current(e_com_ma)?;
        let (k, d) = crate::undistort::model_at(&self.model, e_com_ma)?;
        let out = crate::undistort::output_camera(&k, new_camera_matrix, size, self.file.image_size)?;
        crate::undistort::maps_out(py, &k, &d, &out)
    }

    /// The undistorted image: the image taken at the compensated current as the camera
    /// K(E) without distortion sees it (same size), by the exact maps of
    /// `undistort_maps` and bilinear interpolation (pixels whose source lies outside the
    /// image are 0, as cv2.remap's default BORDER_CONSTANT).
    ///
    /// Args:
    ///     image: a numpy array of dtype uint8, uint16 or float32, of shape (h, w) or
    ///         (h, w, 3) (channels interleaved), of the calibration's image size.
    ///     e_com_ma: compensated current, mA, within the calibrated range (+- 5 mA).
    ///
    /// Returns: an array of the same shape and dtype.
    ///
    /// Raises: InputError for another dtype or shape, an image of another size than the
    /// calibration's, a current outside the calibrated range.
    fn undistort_image<'py>(&self, image: &Bound<'py, PyAny>, e_com_ma: f64) -> PyResult<Bound<'py, PyAny>> {
        self.check_map_current(e_com_ma)?;
        crate::undistort::image_out(image, &self.model, e_com_ma, self.file.image_size)
    }

    fn __repr__(&self) -> String {
        let m = &self.model;
        format!(
            "Calibration(kf_x={:?}, kf_y={:?}, principal_point={:?}, image_size={:?}, e_com_range_ma={:?}, thermal={}, rms_px={:?})",
            m.kf_x,
            m.kf_y,
            m.principal_point,
            self.file.image_size,
            self.file.e_com_range_ma,
            self.file.thermal.is_some(),
            self.file.rms_reprojection_px
        )
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let text = slf.get().to_json()?;
        let ctor = py.get_type::<Calibration>().getattr("from_json")?;
        Ok((ctor, PyTuple::new(py, [text])?))
    }
}

impl Calibration {
    fn surface(&self) -> PyResult<CoreSurface> {
        self.file.thermal_surface().py()
    }

    /// The range policy of the undistortion maps: the calibrated E_com range with the
    /// CLI's margin (`etlcal measure`, `etlcal undistort`). One place to change when the
    /// run-time policy (extrapolation on request) arrives.
    fn check_map_current(&self, e_com_ma: f64) -> PyResult<()> {
        self.file.check_current(e_com_ma, etl_calib::pipeline::measure::CURRENT_MARGIN_MA).py()
    }
}

/// A `ModelStd` as a dict of float64 arrays under the model's keys.
pub(crate) fn std_dict<'py>(py: Python<'py>, s: &ModelStd) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("rotation_rodrigues", vec_out(py, &s.rotation_rodrigues))?;
    d.set_item("translation_mm", vec_out(py, &s.translation_mm))?;
    d.set_item("kf_x", vec_out(py, &s.kf_x))?;
    d.set_item("kf_y", vec_out(py, &s.kf_y))?;
    d.set_item("principal_point", vec_out(py, &s.principal_point))?;
    d.set_item("distortion_a", vec_out(py, &s.distortion_a))?;
    Ok(d)
}
