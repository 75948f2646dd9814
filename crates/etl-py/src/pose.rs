//! `BoardPose`: the result of a plane-based PnP (`Calibration.solve_pnp`), with its
//! uncertainty, and the displacement between two poses (the paper's measurement of a stage
//! move) with its standard deviation.

use std::sync::Arc;

use etl_core::calib::params::MAX_PARAMS as PARAMS;
use etl_core::model::rotation::rodrigues_to_matrix;
use etl_core::pnp::{
    displacement_covariance_mm2, displacement_mm, displacement_std_mm, BoardPose as CorePose, PoseUncertainty,
};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{mat3_out, matrix_out, vec_out};
use crate::errors::{input_error, invalid, CoreResultExt};

/// A calibration's covariance, shared by the poses solved with it.
pub(crate) type CalCovariance = Arc<[[f64; PARAMS]; PARAMS]>;

/// Numbers of a pose's uncertainty in its pickled state: sigma, the 6 x 6 pixel-noise
/// covariance, the 6 x p sensitivity (at capacity: p = etl-core's `MAX_PARAMS`).
const STATE: usize = 1 + 36 + 6 * PARAMS;

/// The pose of a planar board (board frame -> camera frame) found by
/// `Calibration.solve_pnp`, with its uncertainty from the pixel noise and the
/// calibration's covariance (a pose built by hand has none).
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct BoardPose {
    pub(crate) inner: CorePose,
    /// The first-order uncertainty (None for a pose built by hand).
    pub(crate) uncertainty: Option<PoseUncertainty>,
    /// The covariance of the calibration the pose was solved with (None: it has none).
    pub(crate) calibration_covariance: Option<CalCovariance>,
}

impl BoardPose {
    /// The uncertainty, or an error naming the pose that has none.
    fn require_uncertainty(&self, which: &str) -> PyResult<PoseUncertainty> {
        self.uncertainty.ok_or_else(|| {
            input_error(format!("{which} pose has no uncertainty (built by hand): get it from Calibration.solve_pnp"))
        })
    }

    /// The flat pickled state of the uncertainty (see [`STATE`]).
    fn state(&self) -> Option<Vec<f64>> {
        let u = self.uncertainty?;
        let mut v = vec![u.sigma_px];
        v.extend(u.pixel_covariance.iter().flatten());
        v.extend(u.d_pose_d_params.iter().flatten());
        Some(v)
    }
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
    ) -> PyResult<Self> {
        crate::errors::guarded_value("BoardPose.__new__", || {
            let (a, b, c) = rotation_rodrigues;
            let (x, y, z) = translation_mm;
            BoardPose {
                inner: CorePose { rotation_rodrigues: [a, b, c], translation_mm: [x, y, z], rms_px, iterations },
                uncertainty: None,
                calibration_covariance: None,
            }
        })
    }

    /// Rebuilds a pickled pose (its uncertainty included).
    #[staticmethod]
    fn _restore(
        rotation_rodrigues: (f64, f64, f64),
        translation_mm: (f64, f64, f64),
        rms_px: f64,
        iterations: usize,
        state: Option<Vec<f64>>,
        calibration_covariance: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let mut pose = BoardPose::new(rotation_rodrigues, translation_mm, rms_px, iterations)?;
        if let Some(v) = state {
            if v.len() != STATE {
                return Err(invalid("state", format!("a pose's state has {STATE} numbers, got {}", v.len())));
            }
            let at = |k: usize| v.get(k).copied().unwrap_or(f64::NAN);
            pose.uncertainty = Some(PoseUncertainty {
                sigma_px: at(0),
                pixel_covariance: core::array::from_fn(|i| core::array::from_fn(|j| at(1 + 6 * i + j))),
                d_pose_d_params: core::array::from_fn(|i| core::array::from_fn(|j| at(37 + PARAMS * i + j))),
            });
        }
        if let Some(c) = calibration_covariance {
            if c.len() != PARAMS * PARAMS {
                return Err(invalid(
                    "calibration_covariance",
                    format!("a covariance has {} numbers, got {}", PARAMS * PARAMS, c.len()),
                ));
            }
            let at = |k: usize| c.get(k).copied().unwrap_or(f64::NAN);
            pose.calibration_covariance =
                Some(Arc::new(core::array::from_fn(|i| core::array::from_fn(|j| at(PARAMS * i + j)))));
        }
        Ok(pose)
    }

    /// The pixel noise standard deviation the uncertainty assumes, px (given to
    /// `solve_pnp`, or estimated from the fit's residual), or None for a pose built by
    /// hand.
    #[getter]
    fn sigma_px(&self) -> Option<f64> {
        self.uncertainty.map(|u| u.sigma_px)
    }

    /// The 6 x 6 covariance of (rotation_rodrigues rad, translation_mm mm): the pixel
    /// noise's sigma^2 (J^T J)^-1 plus S C S^T from the calibration's covariance C (S =
    /// d pose / d calibration; the latter term absent when the calibration has no
    /// covariance). None for a pose built by hand.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(u) = self.uncertainty else { return Ok(None) };
        let c = u.covariance(self.calibration_covariance.as_deref()).py()?;
        Ok(Some(matrix_out(py, &c)))
    }

    /// One standard deviation of each component of `displacement_mm(other)`, mm, from the
    /// pixel noise of both images and the calibration's covariance together (the
    /// calibration's error moves both poses alike: its part of the difference is
    /// (S_b - S_a) C (S_b - S_a)^T, not the sum of the two poses').
    ///
    /// Args:
    ///     other: the second pose, solved with the same calibration.
    ///     pixel_noise_only: accept a calibration without a covariance and give the pixel
    ///         noise's part alone (default False: refused).
    ///
    /// Returns: a float64 array of shape (3,), mm.
    ///
    /// Raises: InputError for a pose without uncertainty (built by hand), poses solved
    /// with different calibrations, a calibration without a covariance (unless
    /// pixel_noise_only).
    #[pyo3(signature = (other, pixel_noise_only=false))]
    fn displacement_std_mm<'py>(
        &self,
        py: Python<'py>,
        other: &BoardPose,
        pixel_noise_only: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (ua, ub) = (self.require_uncertainty("this")?, other.require_uncertainty("the other")?);
        if self.calibration_covariance != other.calibration_covariance {
            return Err(invalid("other", "the two poses were solved with different calibrations' covariances"));
        }
        let c = self.calibration_covariance.as_deref();
        if c.is_none() && !pixel_noise_only {
            return Err(invalid(
                "pixel_noise_only",
                "the calibration has no covariance: pass pixel_noise_only=True for the pixel noise's part alone",
            ));
        }
        let cov = displacement_covariance_mm2(&ua, &ub, c).py()?;
        Ok(vec_out(py, &displacement_std_mm(&cov)))
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

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("BoardPose.__repr__", || {
            let p = &self.inner;
            format!(
                "BoardPose(rotation_rodrigues={:?}, translation_mm={:?}, rms_px={:?}, iterations={})",
                p.rotation_rodrigues, p.translation_mm, p.rms_px, p.iterations
            )
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("BoardPose.__reduce__", || {
            let py = slf.py();
            let p = slf.get().inner;
            let r = p.rotation_rodrigues;
            let t = p.translation_mm;
            let pose = slf.get();
            let cal: Option<Vec<f64>> =
                pose.calibration_covariance.as_ref().map(|c| c.iter().flatten().copied().collect());
            let args = ((r[0], r[1], r[2]), (t[0], t[1], t[2]), p.rms_px, p.iterations, pose.state(), cal);
            let ctor = py.get_type::<BoardPose>().getattr("_restore")?;
            Ok((ctor, args.into_pyobject(py)?))
        })
    }
}
