//! `CameraAt`: the camera at one setting (`Calibration.at(e_in_ma, temperature_c)`), the
//! run-time camera of etl-core.

use etl_core::camera::{CameraAt as CoreAt, Trust};
use etl_core::pnp::{pose_uncertainty, PixelNoise};
use pyo3::prelude::*;

use crate::arrays::{mat3_out, points, points_out, vec_out};
use crate::errors::CoreResultExt;
use crate::pose::{BoardPose, CalCovariance};

/// The out-of-range policy of an `allow_extrapolation` keyword (the same in every method).
pub(crate) fn trust(allow_extrapolation: bool) -> Trust {
    if allow_extrapolation {
        Trust::Extrapolate
    } else {
        Trust::Refuse
    }
}

/// The camera at one setting: E_com = E_in - E_T(T, E_in), K(E_com) and the distortion
/// there. Made by `Calibration.at`; its methods agree exactly with the Calibration's at
/// `e_com_ma`.
#[pyclass(module = "etlcal", frozen)]
#[derive(Clone)]
pub struct CameraAt {
    pub(crate) inner: CoreAt,
    /// The calibration's covariance, for the uncertainty of `solve_pnp`'s poses.
    pub(crate) calibration_covariance: Option<CalCovariance>,
}

#[pymethods]
impl CameraAt {
    /// Driver current, mA.
    #[getter]
    fn e_in_ma(&self) -> f64 {
        self.inner.e_in_ma()
    }
    /// Lens temperature, degC.
    #[getter]
    fn temperature_c(&self) -> f64 {
        self.inner.temperature_c()
    }
    /// Compensated current E_com, mA.
    #[getter]
    fn e_com_ma(&self) -> f64 {
        self.inner.e_com_ma()
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
        [(f.temperature, "temperature_c"), (f.e_in, "e_in_ma"), (f.e_com, "e_com_ma")]
            .into_iter()
            .filter_map(|(on, name)| on.then_some(name))
            .collect()
    }
    /// The 3 x 3 intrinsic matrix K(E_com), px.
    #[getter]
    fn camera_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        mat3_out(py, self.inner.intrinsics().matrix())
    }
    /// (k1, p1, p2) at E_com (Eq. 18; pixel units, as `Calibration.distortion`).
    #[getter]
    fn distortion(&self) -> (f64, f64, f64) {
        let c = self.inner.distortion().padded();
        (c[0], c[1], c[2])
    }
    /// Projects world points (N, 3) or (3,), mm, to observed pixels.
    fn project<'py>(&self, world_mm: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<3>(world_mm, "world_mm")?;
        let out = p.points.iter().map(|w| self.inner.project(*w)).collect::<etl_core::Result<Vec<_>>>().py()?;
        points_out(world_mm.py(), out, p.single)
    }
    /// Removes the distortion from observed pixels (N, 2) or (2,).
    fn undistort<'py>(&self, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<2>(pixels, "pixels")?;
        let mut out = vec![[0.0; 2]; p.points.len()];
        self.inner.undistort_points(&p.points, &mut out).py()?;
        points_out(pixels.py(), out, p.single)
    }
    /// The world ray of a pixel: (origin_mm, direction).
    fn ray<'py>(&self, py: Python<'py>, pixel: (f64, f64)) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let r = self.inner.ray([pixel.0, pixel.1]).py()?;
        Ok((vec_out(py, &r.origin_mm), vec_out(py, &r.direction)))
    }
    /// The pose of a planar board (board_mm (N, 3) with Z = 0, pixels (N, 2)), with its
    /// uncertainty as `Calibration.solve_pnp`'s (sigma_px None: from the residual).
    #[pyo3(signature = (board_mm, pixels, sigma_px=None))]
    fn solve_pnp(
        &self,
        board_mm: &Bound<'_, PyAny>,
        pixels: &Bound<'_, PyAny>,
        sigma_px: Option<f64>,
    ) -> PyResult<BoardPose> {
        let b = points::<3>(board_mm, "board_mm")?;
        let p = points::<2>(pixels, "pixels")?;
        let pose = self.inner.solve_pnp(&b.points, &p.points).py()?;
        let noise = sigma_px.map_or(PixelNoise::FromResidual, PixelNoise::Known);
        let (model, e) = (self.inner.model(), self.inner.e_com_ma());
        let u = pose_uncertainty(model, e, &b.points, &p.points, &pose, noise).py()?;
        Ok(BoardPose { inner: pose, uncertainty: Some(u), calibration_covariance: self.calibration_covariance.clone() })
    }
    fn __repr__(&self) -> String {
        let k = self.inner.intrinsics();
        format!(
            "CameraAt(e_in_ma={:?}, temperature_c={:?}, e_com_ma={:?}, fx={:?}, fy={:?}, extrapolated={})",
            self.inner.e_in_ma(),
            self.inner.temperature_c(),
            self.inner.e_com_ma(),
            k.fx,
            k.fy,
            if self.inner.extrapolated() { "True" } else { "False" }
        )
    }
}
