//! `Rig` and `RigAt`: a multi-camera ETL rig (`etlcal.rig/1`) at run time, etl-calib's
//! `rig` (the same checks and numbers as `etlcal triangulate` and `etlcal rectify`).
//! `etlcal.rig` (the module) is the capture of a rig's views; `etlcal.Rig` is this class.

use std::path::PathBuf;
use std::sync::Arc;

use etl_calib::rig::{
    maps_files, write_files, CalibrationPart, Rig as CoreRig, RigAt as CoreRigAt, RigSetting, StereoRectification,
};
use etl_formats::export::ExportFormat;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};

use crate::arrays::{mat3_out, matrix_out, vec_out};
use crate::calibration::Calibration;
use crate::camera::{trust, CameraAt};
use crate::errors::{invalid, CoreResultExt};

/// A setting given as a number (the calibration's unit) or a string with its unit
/// (`"150mA"`, `"12.5dpt"`).
fn setting(obj: &Bound<'_, PyAny>, k: usize) -> PyResult<RigSetting> {
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(RigSetting::of(v));
    }
    let s: String = obj
        .extract()
        .map_err(|_| invalid("settings", format!("settings[{k}] must be a number or a string like \"150mA\"")))?;
    s.parse::<RigSetting>().py()
}

/// A calibrated rig of N >= 2 ETL cameras (`etlcal.rig/1`): each camera's calibration and
/// its pose relative to camera 0, which follows the cameras' settings (moving centres).
/// `Rig.load(path)`, then `rig.at(settings, temperatures_c)` for a `RigAt`.
#[pyclass(module = "etlcal", frozen, name = "Rig")]
pub struct Rig {
    inner: CoreRig,
    calibrations: Vec<Py<Calibration>>,
}

impl Rig {
    /// The Python rig of etl-calib's, its calibrations as Python objects.
    pub(crate) fn from_core(py: Python<'_>, inner: CoreRig) -> PyResult<Self> {
        let calibrations = inner
            .calibrations()
            .iter()
            .map(|c| Py::new(py, Calibration::from_file(c.clone())?))
            .collect::<PyResult<_>>()?;
        Ok(Rig { inner, calibrations })
    }
}

#[pymethods]
impl Rig {
    /// Reads `etlcal.rig/1` at `path` with its calibrations (paths relative to the file).
    /// Raises InputError / FileError naming the key (a missing calibration among them).
    #[classmethod]
    fn load(cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        let py = cls.py();
        let inner = py.detach(|| CoreRig::load(&path)).py()?;
        Rig::from_core(py, inner)
    }

    /// Writes the rig as `etlcal.rig/1` at `path`, each calibration inline, atomically
    /// (nothing written if its checks fail). Raises InputError / FileError naming the cause.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.file().save(&path)).py()
    }

    fn __len__(&self) -> PyResult<usize> {
        crate::errors::guarded_value("Rig.__len__", || self.inner.len())
    }

    /// The cameras' names, in the rig's order.
    #[getter]
    fn names(&self) -> Vec<String> {
        (0..self.inner.len()).map(|k| self.inner.name(k).to_owned()).collect()
    }

    /// The cameras' calibrations (`Calibration`), in the rig's order.
    #[getter]
    fn calibrations(&self, py: Python<'_>) -> Vec<Py<Calibration>> {
        self.calibrations.iter().map(|c| c.clone_ref(py)).collect()
    }

    /// The rig at one setting and one lens temperature per camera, in the rig's order:
    /// each setting in its calibration's own unit (the driver current E_in, mA, of a
    /// current calibration, E_com from its thermal part; the focal power, dpt, of a
    /// focal-power one), a number or a string with its unit ("150mA", "12.5dpt", checked
    /// against the calibration's). Raises InputError (one line naming the camera) for a
    /// count that is not the number of cameras, a setting of the other kind, or one
    /// outside the calibrated ranges (unless `allow_extrapolation`).
    #[pyo3(signature = (settings, temperatures_c, allow_extrapolation = false))]
    fn at(
        &self,
        py: Python<'_>,
        settings: Vec<Bound<'_, PyAny>>,
        temperatures_c: Vec<f64>,
        allow_extrapolation: bool,
    ) -> PyResult<RigAt> {
        let s = settings.iter().enumerate().map(|(k, o)| setting(o, k)).collect::<PyResult<Vec<_>>>()?;
        let inner = self.inner.at(&s, &temperatures_c, trust(allow_extrapolation)).py()?;
        let cameras = (0..inner.len())
            .map(|k| {
                let cal = self.calibrations[k].bind(py);
                let file = Arc::clone(&cal.get().file);
                Py::new(py, CameraAt::new(inner.cameras()[k], cal.clone().into_any().unbind(), file))
            })
            .collect::<PyResult<_>>()?;
        Ok(RigAt { inner, cameras })
    }

    /// Bouguet's rectification of a two-camera rig's pair (camera 0 left, camera 1 right)
    /// at `setting_left`, `setting_right` and `temperatures_c` (one per camera), with the
    /// maps of both images through each camera's full model: `rig.at(...)` then
    /// `RigAt.stereo_rectify_maps(0, 1, alpha)` (see there; a rig of more cameras: use
    /// that). `alpha`: only -1 (cv2.stereoRectify's default) is implemented.
    #[pyo3(
        signature = (setting_left, setting_right, temperatures_c, alpha = -1.0, allow_extrapolation = false),
        text_signature = "($self, setting_left, setting_right, temperatures_c, alpha=-1.0, allow_extrapolation=False)"
    )]
    fn stereo_rectify_maps<'py>(
        &self,
        py: Python<'py>,
        setting_left: Bound<'py, PyAny>,
        setting_right: Bound<'py, PyAny>,
        temperatures_c: Vec<f64>,
        alpha: f64,
        allow_extrapolation: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if self.inner.len() != 2 {
            return Err(invalid(
                "settings",
                format!(
                    "the rig has {} cameras: give every camera's setting, rig.at(settings, temperatures_c).stereo_rectify_maps(left, right)",
                    self.inner.len()
                ),
            ));
        }
        let at = self.at(py, vec![setting_left, setting_right], temperatures_c, allow_extrapolation)?;
        at.rectify_maps(py, 0, 1, alpha)
    }
}

/// The rig at one setting per camera (`Rig.at`): each camera's `CameraAt`, its pose
/// relative to camera 0 at these settings, triangulation and rectification.
#[pyclass(module = "etlcal", frozen, name = "RigAt")]
pub struct RigAt {
    inner: CoreRigAt,
    cameras: Vec<Py<CameraAt>>,
}

impl RigAt {
    fn rectify(&self, left: usize, right: usize, alpha: f64) -> PyResult<StereoRectification> {
        self.inner.stereo_rectify(left, right, alpha).py()
    }

    fn rectify_maps<'py>(&self, py: Python<'py>, left: usize, right: usize, alpha: f64) -> PyResult<Bound<'py, PyAny>> {
        let rect = self.rectify(left, right, alpha)?;
        let maps = py.detach(|| self.inner.stereo_rectify_maps(&rect)).py()?;
        let d = rectification_dict(py, &rect)?;
        d.set_item("left_maps", crate::undistort::maps_arrays(py, maps.left)?)?;
        d.set_item("right_maps", crate::undistort::maps_arrays(py, maps.right)?)?;
        crate::results::make(py, "StereoRectifyMaps", &d)
    }
}

/// The fields of a rectification (R1, R2, P1, P2, Q and the pair's pose).
fn rectification_dict<'py>(py: Python<'py>, rect: &StereoRectification) -> PyResult<Bound<'py, PyDict>> {
    let x = &rect.rectification;
    let d = PyDict::new(py);
    d.set_item("pair", (rect.pair[0], rect.pair[1]))?;
    d.set_item("image_size", (rect.image_size[0], rect.image_size[1]))?;
    d.set_item("R", mat3_out(py, rect.rotation))?;
    d.set_item("T", vec_out(py, &rect.translation_mm))?;
    d.set_item("baseline_mm", rect.baseline_mm())?;
    d.set_item("R1", mat3_out(py, x.r1))?;
    d.set_item("R2", mat3_out(py, x.r2))?;
    d.set_item("P1", matrix_out(py, &x.p1))?;
    d.set_item("P2", matrix_out(py, &x.p2))?;
    d.set_item("Q", matrix_out(py, &x.q))?;
    Ok(d)
}

#[pymethods]
impl RigAt {
    fn __len__(&self) -> PyResult<usize> {
        crate::errors::guarded_value("RigAt.__len__", || self.inner.len())
    }

    /// Each camera at its setting (`CameraAt`), in the rig's order.
    #[getter]
    fn cameras(&self, py: Python<'_>) -> Vec<Py<CameraAt>> {
        self.cameras.iter().map(|c| c.clone_ref(py)).collect()
    }

    /// Each camera's pose relative to camera 0 at these settings, (R (3 x 3), T (3,) mm):
    /// X_k = R X_0 + T (camera 0's the identity).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Vec<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.inner.poses().iter().map(|p| (mat3_out(py, p.rotation), vec_out(py, &p.translation_mm))).collect()
    }

    /// Whether any camera is outside its calibrated ranges.
    #[getter]
    fn extrapolated(&self) -> bool {
        self.inner.extrapolated()
    }

    /// The point seen at `pixels` (one entry per camera in the rig's order: (u, v) px or
    /// None where the camera does not see it; at least two), least squares through each
    /// camera's full model, in camera 0's frame at its setting (mm). Its covariance: the
    /// pixel noise `sigma_px` (px per coordinate) plus the calibration's (each used
    /// the rig file's joint covariance when it has one, else each used camera's model
    /// covariance and pose covariance as independent groups), which a missing covariance
    /// refuses unless `pixel_only`. Returns a `Triangulated`: `point_mm`,
    /// `covariance_mm2`, `std_mm`, `from_pixels_mm2`, `from_calibration_mm2` (None with
    /// `pixel_only`), `calibration_covariance` (`"joint"`, `"independent"`, None with
    /// `pixel_only`), `cameras_used`, `rms_px`, `extrapolated`.
    #[pyo3(signature = (pixels, sigma_px, pixel_only = false))]
    fn triangulate<'py>(
        &self,
        py: Python<'py>,
        pixels: Vec<Option<(f64, f64)>>,
        sigma_px: f64,
        pixel_only: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let px: Vec<Option<[f64; 2]>> = pixels.into_iter().map(|p| p.map(|(u, v)| [u, v])).collect();
        let part = if pixel_only { CalibrationPart::PixelOnly } else { CalibrationPart::Include };
        let t = self.inner.triangulate(&px, sigma_px, part).py()?;
        let d = PyDict::new(py);
        d.set_item("point_mm", vec_out(py, &t.point_mm))?;
        d.set_item("covariance_mm2", mat3_out(py, t.covariance_mm2))?;
        d.set_item("std_mm", vec_out(py, &t.std_mm()))?;
        d.set_item("from_pixels_mm2", mat3_out(py, t.from_pixels))?;
        d.set_item("from_calibration_mm2", t.from_calibration.map(|c| mat3_out(py, c)))?;
        d.set_item("calibration_covariance", t.calibration_covariance.map(|c| c.as_str()))?;
        d.set_item("cameras_used", t.cameras_used.clone())?;
        d.set_item("rms_px", t.rms_px)?;
        d.set_item("extrapolated", t.extrapolated)?;
        crate::results::make(py, "Triangulated", &d)
    }

    /// Bouguet's rectification of cameras `left` and `right` at these settings (as
    /// cv2.stereoRectify with CALIB_ZERO_DISPARITY; `alpha`: only -1 is implemented) and
    /// the maps of both images: for each rectified pixel its ray turned back by R1 / R2
    /// and projected through the camera's full model, so `cv2.remap(image, map_x, map_y,
    /// cv2.INTER_LINEAR)` gives the rectified image (exact to the model in either
    /// distortion family; for an opencv-family camera, cv2.initUndistortRectifyMap's
    /// maps). Returns a `StereoRectifyMaps`: `left_maps`, `right_maps` ((map_x, map_y),
    /// (h, w) float32 each), `R1`, `R2`, `P1`, `P2`, `Q`, `R`, `T` (X_right = R X_left +
    /// T at the settings), `baseline_mm`, `pair`, `image_size`.
    #[pyo3(signature = (left = 0, right = 1, alpha = -1.0), text_signature = "($self, left=0, right=1, alpha=-1.0)")]
    fn stereo_rectify_maps<'py>(
        &self,
        py: Python<'py>,
        left: usize,
        right: usize,
        alpha: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.rectify_maps(py, left, right, alpha)
    }

    /// Writes the rectified pair (`left`, `right`) into `out_dir` as one set: `stereo.yaml`
    /// (OpenCV stereo YAML) always (`formats` None: that alone), `left.yaml`/`right.yaml` (ROS camera_info) for "ros",
    /// one `NAME.cameramodel` per camera (mrcal, extrinsics relative to camera 0) for
    /// "mrcal", and with `maps` the four `.npy` maps (as `etlcal rectify`). Returns the
    /// paths written.
    #[pyo3(
        signature = (out_dir, left = 0, right = 1, formats = None, maps = false, alpha = -1.0),
        text_signature = "($self, out_dir, left=0, right=1, formats=None, maps=False, alpha=-1.0)"
    )]
    #[allow(clippy::too_many_arguments)] // Python's keywords, one each.
    fn export_pair(
        &self,
        py: Python<'_>,
        out_dir: PathBuf,
        left: usize,
        right: usize,
        formats: Option<Vec<String>>,
        maps: bool,
        alpha: f64,
    ) -> PyResult<Vec<PathBuf>> {
        let mut f = vec![ExportFormat::OpenCv];
        for name in formats.iter().flatten() {
            let e = name.parse::<ExportFormat>().py()?;
            if !f.contains(&e) {
                f.push(e);
            }
        }
        let rect = self.rectify(left, right, alpha)?;
        py.detach(|| {
            let mut files: Vec<(String, Vec<u8>)> =
                self.inner.export_pair(&rect, &f)?.into_iter().map(|x| (x.name, x.text.into_bytes())).collect();
            if maps {
                files.extend(maps_files(&self.inner.stereo_rectify_maps(&rect)?)?);
            }
            write_files(&out_dir, files)
        })
        .py()
    }
}
