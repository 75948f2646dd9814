//! `BoardPose`: the result of a plane-based PnP (`Calibration.solve_pnp`), and the
//! displacement between two poses (the paper's measurement of a stage move).

use etl_core::model::rotation::rodrigues_to_matrix;
use etl_core::pnp::{displacement_mm, BoardPose as CorePose};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{mat3_out, vec_out};

/// The pose of a planar board (board frame -> camera frame) found by
/// `Calibration.solve_pnp`.
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct BoardPose {
    pub(crate) inner: CorePose,
}

#[pymethods]
impl BoardPose {
    #[new]
    #[pyo3(signature = (rotation_rodrigues, translation_mm, rms_px=0.0, iterations=0))]
    fn new(
        rotation_rodrigues: (f64, f64, f64),
        translation_mm: (f64, f64, f64),
        rms_px: f64,
        iterations: usize,
    ) -> Self {
        let (a, b, c) = rotation_rodrigues;
        let (x, y, z) = translation_mm;
        BoardPose { inner: CorePose { rotation_rodrigues: [a, b, c], translation_mm: [x, y, z], rms_px, iterations } }
    }

    /// Rodrigues vector of the rotation board -> camera, rad.
    #[getter]
    fn rotation_rodrigues<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.inner.rotation_rodrigues)
    }

    /// Rotation matrix board -> camera (3 x 3).
    #[getter]
    fn rotation_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        mat3_out(py, rodrigues_to_matrix(self.inner.rotation_rodrigues))
    }

    /// The board origin in camera coordinates, mm.
    #[getter]
    fn translation_mm<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        vec_out(py, &self.inner.translation_mm)
    }

    /// RMS reprojection error of the fit, px.
    #[getter]
    fn rms_px(&self) -> f64 {
        self.inner.rms_px
    }

    /// Levenberg-Marquardt iterations.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    /// The displacement of the board origin from this pose to `other`, in camera
    /// coordinates, mm (its norm is the length of a stage move).
    ///
    /// Args:
    ///     other: the second pose.
    fn displacement_mm<'py>(&self, py: Python<'py>, other: &BoardPose) -> Bound<'py, PyAny> {
        vec_out(py, &displacement_mm(&self.inner, &other.inner))
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "BoardPose(rotation_rodrigues={:?}, translation_mm={:?}, rms_px={:?}, iterations={})",
            p.rotation_rodrigues, p.translation_mm, p.rms_px, p.iterations
        )
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let p = slf.get().inner;
        let r = p.rotation_rodrigues;
        let t = p.translation_mm;
        let args = ((r[0], r[1], r[2]), (t[0], t[1], t[2]), p.rms_px, p.iterations).into_pyobject(py)?;
        Ok((py.get_type::<BoardPose>().into_any(), args))
    }
}
