//! `CameraAt`: the camera at one setting (`Calibration.at(e_in_ma, temperature_c)` or
//! `Calibration.at_e_com(e_com_ma)`), the run-time camera of etl-core, and the one
//! implementation of every run-time operation: `Calibration`'s methods that take an
//! `e_com_ma` build a `CameraAt` (the one range check) and call these.

use std::path::PathBuf;
use std::sync::Arc;

use etl_core::calib::projection_uncertainty;
use etl_core::model::DistortionModel;
use etl_core::pnp::{pose_uncertainty, PixelNoise};
use etl_core::runtime::{CameraAt as CoreAt, Trust};
use etl_formats::calibration::Calibration as CalFile;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{mat3_out, parts_out, points, points_out, vec_out};
use crate::errors::{calib_err, CoreResultExt};
use crate::pose::BoardPose;

/// Points above which the per-point operations release the GIL (below it the release
/// costs more than it lets other threads gain).
const DETACH_POINTS: usize = 4096;

/// The out-of-range policy of an `allow_extrapolation` keyword (the same in every method).
pub(crate) fn trust(allow_extrapolation: bool) -> Trust {
    if allow_extrapolation {
        Trust::Extrapolate
    } else {
        Trust::Refuse
    }
}

/// A per-current model function: its parts (row-major blocks) at one setting, given the
/// calibration's image size. `Calibration`'s vectorised methods (`focal_lengths`,
/// `intrinsics`, `distortion`, `to_opencv`) apply it at every current of an array,
/// `CameraAt`'s at its own.
pub(crate) type PerCurrent<const P: usize> = fn(&CoreAt, [u32; 2]) -> PyResult<[Vec<f64>; P]>;

/// fx, fy (Eq. 16), px.
pub(crate) fn focal_parts(at: &CoreAt, _: [u32; 2]) -> PyResult<[Vec<f64>; 2]> {
    let k = at.intrinsics();
    Ok([vec![k.fx], vec![k.fy]])
}

/// K (Eq. 15), 3 x 3, px.
pub(crate) fn intrinsics_parts(at: &CoreAt, _: [u32; 2]) -> PyResult<[Vec<f64>; 1]> {
    Ok([at.intrinsics().matrix().into_iter().flatten().collect()])
}

/// The family's coefficients at capacity (k1 p1 p2 then zeros, or k1 k2 p1 p2 k3):
/// [`distortion_out`] keeps the family's count.
pub(crate) fn distortion_parts(at: &CoreAt, _: [u32; 2]) -> PyResult<[Vec<f64>; 5]> {
    let c = at.distortion().padded();
    Ok(core::array::from_fn(|i| vec![c[i]]))
}

/// OpenCV's K, its five coefficients, and the fit's RMS and maximum error (px).
pub(crate) fn opencv_parts(at: &CoreAt, image_size: [u32; 2]) -> PyResult<[Vec<f64>; 4]> {
    let fit = etl_core::model::fit_opencv5(at.intrinsics(), at.distortion(), image_size).py()?;
    Ok([
        at.intrinsics().matrix().into_iter().flatten().collect(),
        fit.dist_coeffs.to_vec(),
        vec![fit.rms_px],
        vec![fit.max_px],
    ])
}

/// The shapes of [`opencv_parts`], [`distortion_parts`], [`intrinsics_parts`].
pub(crate) const OPENCV_SHAPES: [&[usize]; 4] = [&[3, 3], &[5], &[], &[]];
pub(crate) const DISTORTION_SHAPES: [&[usize]; 5] = [&[]; 5];

/// `etlcal.results.Distortion.of(family, *coefficients)`: the family's named result from
/// the parts of [`distortion_parts`] (its first `coefficient_count` of them).
pub(crate) fn distortion_out<'py>(
    py: Python<'py>,
    family: DistortionModel,
    parts: [Bound<'py, PyAny>; 5],
) -> PyResult<Bound<'py, PyAny>> {
    let mut args = vec![pyo3::types::PyString::new(py, family.name()).into_any()];
    args.extend(parts.into_iter().take(family.coefficient_count()));
    let class = py.import("etlcal.results")?.getattr("Distortion")?;
    class.call_method1("of", PyTuple::new(py, args)?)
}

/// `etlcal.results.OpenCvCamera` from the parts of [`opencv_parts`].
pub(crate) fn opencv_out<'py>(
    py: Python<'py>,
    family: DistortionModel,
    [k, dist, rms, max]: [Bound<'py, PyAny>; 4],
) -> PyResult<Bound<'py, PyAny>> {
    let exact = family == DistortionModel::OpenCv;
    py.import("etlcal.results")?.getattr("OpenCvCamera")?.call1((k, dist, rms, max, exact))
}

/// The camera at one setting: E_com = E_in - E_T(T, E_in) (or a known E_com), K(E_com) and
/// the distortion there, and every operation of the camera at that setting. Made by
/// `Calibration.at` and `Calibration.at_e_com`; `Calibration`'s methods taking `e_com_ma`
/// are these at `at_e_com(e_com_ma)`, so the two agree to the bit.
#[pyclass(module = "etlcal", frozen)]
pub struct CameraAt {
    pub(crate) inner: CoreAt,
    /// The `Calibration` this is a setting of, as Python sees it.
    calibration: Py<PyAny>,
    /// Its file: the image size, the covariance (for the uncertainty of poses and pixels)
    /// and the content `export` writes.
    file: Arc<CalFile>,
}

impl CameraAt {
    /// The camera `inner` of the calibration object `calibration` (a `Calibration`),
    /// whose file is `file`: made by `Calibration.at` and `Calibration.at_e_com`, which
    /// check the setting (this module names no `Calibration`, so the two do not import
    /// each other).
    pub(crate) fn new(inner: CoreAt, calibration: Py<PyAny>, file: Arc<CalFile>) -> Self {
        CameraAt { inner, calibration, file }
    }

    /// The parts of a per-current function at this setting, as `Calibration`'s
    /// vectorised methods give them for one current.
    fn parts<'py, const P: usize>(
        &self,
        py: Python<'py>,
        part_shapes: [&[usize]; P],
        f: PerCurrent<P>,
    ) -> PyResult<[Bound<'py, PyAny>; P]> {
        parts_out(py, &[], true, f(&self.inner, self.file.image_size)?, part_shapes)
    }

    /// The image size of its calibration, px.
    pub(crate) fn image_size(&self) -> [u32; 2] {
        self.file.image_size
    }

    /// Whether the setting was given as a known E_com (E_in and T unknown).
    fn given_e_com(&self) -> bool {
        self.inner.e_in_ma().is_nan()
    }
}

#[pymethods]
impl CameraAt {
    /// Driver current, mA (None for a camera at a known E_com, `Calibration.at_e_com`, and
    /// at a focal power).
    #[getter]
    fn e_in_ma(&self) -> Option<f64> {
        let e = self.inner.e_in_ma();
        (!e.is_nan()).then_some(e)
    }
    /// Lens temperature, degC (None for a camera at a known E_com).
    #[getter]
    fn temperature_c(&self) -> Option<f64> {
        let t = self.inner.temperature_c();
        (!t.is_nan()).then_some(t)
    }
    /// Compensated current E_com, mA (NaN for a focal-power calibration's camera).
    #[getter]
    fn e_com_ma(&self) -> f64 {
        self.inner.e_com_ma()
    }
    /// The commanded focal power, dpt (None for a current calibration's camera).
    #[getter]
    fn focal_power_dpt(&self) -> Option<f64> {
        let p = self.inner.focal_power_dpt();
        (!p.is_nan()).then_some(p)
    }
    /// What the setting is: "current" or "focal_power" (the calibration's).
    #[getter]
    fn setting(&self) -> &'static str {
        self.inner.setting_kind().name()
    }
    /// The calibration this camera is a setting of.
    #[getter]
    fn calibration(&self, py: Python<'_>) -> Py<PyAny> {
        self.calibration.clone_ref(py)
    }
    /// Whether the setting lies outside a calibrated range (only with
    /// `allow_extrapolation=True`).
    #[getter]
    fn extrapolated(&self) -> bool {
        self.inner.extrapolated()
    }
    /// The quantities outside their calibrated range: a list of "temperature_c",
    /// "e_in_ma", "e_com_ma" (empty inside every range).
    #[getter]
    fn extrapolated_quantities(&self) -> Vec<&'static str> {
        let f = self.inner.flags();
        [
            (f.temperature, "temperature_c"),
            (f.e_in, "e_in_ma"),
            (f.e_com, "e_com_ma"),
            (f.focal_power, "focal_power_dpt"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
    /// (fx, fy) at E_com, px (Eq. 16; `Calibration.focal_lengths`).
    #[getter]
    fn focal_lengths<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(PyTuple::new(py, self.parts(py, [&[], &[]], focal_parts)?)?.into_any())
    }
    /// The 3 x 3 intrinsic matrix K(E_com), px (`Calibration.intrinsics`).
    #[getter]
    fn camera_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let [k] = self.parts(py, [&[3, 3]], intrinsics_parts)?;
        Ok(k)
    }
    /// The distortion coefficients at E_com, named for the family (a PaperDistortion
    /// (k1, p1, p2) or an OpenCvDistortion (k1, k2, p1, p2, k3); `Calibration.distortion`).
    #[getter]
    fn distortion<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        distortion_out(py, self.inner.distortion().model(), self.parts(py, DISTORTION_SHAPES, distortion_parts)?)
    }
    /// The camera in OpenCV's conventions (`Calibration.to_opencv`): an OpenCvCamera, the
    /// tuple (K, dist) with `exact`, `fit_rms_px`, `fit_max_px`.
    fn to_opencv<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        opencv_out(py, self.inner.distortion().model(), self.parts(py, OPENCV_SHAPES, opencv_parts)?)
    }
    /// Projects world points (N, 3) or (3,), mm, to observed pixels (Eq. 13-18;
    /// `Calibration.project`).
    ///
    /// Raises: InputError for a NaN or a point at or behind the camera.
    pub(crate) fn project<'py>(&self, world_mm: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<3>(world_mm, "world_mm")?;
        let (py, model, e_com_ma) = (world_mm.py(), *self.inner.model(), self.inner.setting_value());
        let mut out = vec![[0.0; 2]; p.points.len()];
        // Rotation, K and distortion once for all points, not once per point.
        let run = |out: &mut [[f64; 2]]| model.project_many(&p.points, e_com_ma, out);
        if p.points.len() > DETACH_POINTS { crate::pool::detach(py, || run(&mut out)) } else { run(&mut out) }.py()?;
        points_out(py, out, p.single)
    }
    /// Removes the distortion from observed pixels (N, 2) or (2,): the pixels they would
    /// have without distortion, same frame (Eq. 17 inverted; `Calibration.undistort`).
    ///
    /// Raises: InputError for a NaN or a pixel beyond the fold of the distortion model;
    /// NotConvergedError if the inversion misses its tolerance.
    pub(crate) fn undistort<'py>(&self, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<2>(pixels, "pixels")?;
        let (py, at) = (pixels.py(), self.inner);
        let mut out = vec![[0.0; 2]; p.points.len()];
        let run = |out: &mut [[f64; 2]]| at.undistort_points(&p.points, out);
        if p.points.len() > DETACH_POINTS { crate::pool::detach(py, || run(&mut out)) } else { run(&mut out) }.py()?;
        points_out(py, out, p.single)
    }
    /// The viewing ray of a pixel in world coordinates: (origin_mm, direction), float64
    /// arrays of shape (3,) (`Calibration.ray`).
    pub(crate) fn ray<'py>(
        &self,
        py: Python<'py>,
        pixel: (f64, f64),
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let r = self.inner.ray([pixel.0, pixel.1]).py()?;
        Ok((vec_out(py, &r.origin_mm), vec_out(py, &r.direction)))
    }
    /// The pose of a planar board (board_mm (N, 3) with Z = 0, pixels (N, 2)), with its
    /// uncertainty (`Calibration.solve_pnp`; sigma_px None: from the residual).
    #[pyo3(signature = (board_mm, pixels, sigma_px=None))]
    pub(crate) fn solve_pnp(
        &self,
        py: Python<'_>,
        board_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        sigma_px: Option<f64>,
    ) -> PyResult<BoardPose> {
        let b = points::<3>(board_mm, "board_mm")?;
        let p = points::<2>(pixels, "pixels")?;
        let noise = sigma_px.map_or(PixelNoise::FromResidual, PixelNoise::Known);
        let at = self.inner;
        let (pose, u) = crate::pool::detach(py, || {
            let pose = at.solve_pnp(&b.points, &p.points)?;
            let u = pose_uncertainty(at.model(), at.setting_value(), &b.points, &p.points, &pose, noise)?;
            Ok::<_, etl_core::Error>((pose, u))
        })
        .py()?;
        let calibration_covariance = self.file.covariance_matrix().map(Arc::new);
        Ok(BoardPose { inner: pose, uncertainty: Some(u), calibration_covariance })
    }
    /// The standard deviation of projected pixels due to the calibration's uncertainty,
    /// px: (N, 2) or (2,) (`Calibration.projection_std`).
    ///
    /// Raises: InputError for a calibration without a covariance, a NaN, a point at or
    /// behind the camera.
    pub(crate) fn projection_std<'py>(&self, world_mm: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<3>(world_mm, "world_mm")?;
        let py = world_mm.py();
        let cov = self.file.require_covariance().map_err(calib_err)?;
        let (model, e_com_ma) = (*self.inner.model(), self.inner.setting_value());
        let out = crate::pool::detach(py, || {
            p.points
                .iter()
                .map(|w| projection_uncertainty(&model, &cov, *w, e_com_ma).map(|u| u.std_px))
                .collect::<etl_core::Result<Vec<[f64; 2]>>>()
        })
        .py()?;
        points_out(py, out, p.single)
    }
    /// The undistortion maps (map_x, map_y) at E_com, float32 (h, w), in cv2.remap's
    /// convention (`Calibration.undistort_maps`): the output camera `new_camera_matrix`
    /// (None: K(E_com)) of `size` (None: the calibration's image size).
    #[pyo3(signature = (new_camera_matrix=None, size=None))]
    pub(crate) fn undistort_maps<'py>(
        &self,
        py: Python<'py>,
        new_camera_matrix: Option<&Bound<'py, PyAny>>,
        size: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let (k, d) = (self.inner.intrinsics(), self.inner.distortion());
        let out = crate::undistort::output_camera(k, new_camera_matrix, size, self.file.image_size)?;
        crate::undistort::maps_out(py, k, d, &out)
    }
    /// The undistorted image (same shape and dtype) of an image taken at this setting
    /// (`Calibration.undistort_image`).
    pub(crate) fn undistort_image<'py>(&self, image: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let (k, d) = (self.inner.intrinsics(), self.inner.distortion());
        crate::undistort::image_out(image, k, d, self.file.image_size)
    }
    /// Writes the camera at this setting for another tool (atomically; nothing on error):
    /// `format` "opencv", "ros" or "mrcal" (`Calibration.export`).
    ///
    /// Returns: an ExportResult: e_com_ma, extrapolated, camera_matrix, dist_coeffs
    /// (OpenCV's five, fitted to etlcal's model over the image), fit_rms_px, fit_max_px.
    pub(crate) fn export<'py>(&self, py: Python<'py>, path: PathBuf, format: &str) -> PyResult<Bound<'py, PyAny>> {
        use etl_formats::export::{export, ExportFormat};
        let format: ExportFormat = format.parse().map_err(calib_err)?;
        let e = export(&self.file, &self.inner, format, &path).map_err(calib_err)?;
        let d = PyDict::new(py);
        d.set_item("e_com_ma", self.inner.e_com_ma())?;
        d.set_item("extrapolated", self.inner.extrapolated())?;
        d.set_item("camera_matrix", mat3_out(py, e.camera_matrix))?;
        d.set_item("dist_coeffs", vec_out(py, &e.fit.dist_coeffs))?;
        d.set_item("fit_rms_px", e.fit.rms_px)?;
        d.set_item("fit_max_px", e.fit.max_px)?;
        let p = self.inner.focal_power_dpt();
        d.set_item("focal_power_dpt", (!p.is_nan()).then_some(p))?;
        crate::results::make(py, "ExportResult", &d)
    }
    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("CameraAt.__repr__", || {
            let k = self.inner.intrinsics();
            let setting = if self.given_e_com() {
                String::new()
            } else {
                format!("e_in_ma={:?}, temperature_c={:?}, ", self.inner.e_in_ma(), self.inner.temperature_c())
            };
            format!(
                "CameraAt({setting}e_com_ma={:?}, fx={:?}, fy={:?}, extrapolated={})",
                self.inner.e_com_ma(),
                k.fx,
                k.fy,
                if self.inner.extrapolated() { "True" } else { "False" }
            )
        })
    }
}
