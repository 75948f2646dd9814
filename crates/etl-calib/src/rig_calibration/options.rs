//! The options of [`super::calibrate_rig`].

use crate::request::CalibrationRequest;

/// How the reduced system of each Levenberg-Marquardt step is solved (module docs of
/// [`super`]; docs/BENCHMARKS.md measures both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Dense below [`SPARSE_FROM_CAMERAS`] cameras, sparse from it on: the faster of the
    /// two by the benchmark.
    #[default]
    Auto,
    /// Every correction eliminated, the (sum p_k) square Schur complement factored by
    /// nalgebra's dense Cholesky.
    Dense,
    /// The current corrections eliminated, the stage corrections kept: the sparse
    /// bordered system factored by faer's sparse Cholesky.
    Sparse,
}

/// The fewest cameras from which [`LinearSolver::Auto`] takes the sparse path: the
/// benchmark's crossover (docs/BENCHMARKS.md, `rig_reduced_system`).
pub const SPARSE_FROM_CAMERAS: usize = 12;

impl LinearSolver {
    /// Whether a rig of `cameras` cameras is solved by the sparse path.
    pub fn sparse_for(self, cameras: usize) -> bool {
        match self {
            LinearSolver::Auto => cameras >= SPARSE_FROM_CAMERAS,
            LinearSolver::Dense => false,
            LinearSolver::Sparse => true,
        }
    }
}

/// The options of [`super::calibrate_rig`]: the per-camera calibration's (the same request
/// `etlcal calibrate` takes: model, estimator, priors, A0 source, temperature surface),
/// shared by every camera or given per camera, and the joint solve's.
///
/// Each camera is calibrated alone with its own request ([`Self::request_for`]): the one
/// of [`Self::per_camera`] that names it, else [`Self::request`]. What cannot differ per
/// camera is refused by the calibration, naming the camera: the estimator and the stage's
/// prior (one joint solve, one stage), the per-setting method and a robust loss (as for
/// the shared request), a camera the dataset does not have, a camera given twice.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RigCalibrationOptions {
    /// The request of every camera without its own (the proposed method only).
    pub request: CalibrationRequest,
    /// The linear solver of the joint steps.
    pub solver: LinearSolver,
    /// The most Levenberg-Marquardt iterations of the joint solve (0: the default, 100).
    pub max_iterations: usize,
    /// Cameras calibrated with their own request (each whole: a front end applies its
    /// per-camera options on top of the shared ones, [`CalibrationRequest::overridden`]).
    pub per_camera: Vec<CameraRequest>,
}

/// One camera's own request: its lens's temperature surface, its model choices.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraRequest {
    /// The camera's name in the rig dataset.
    pub camera: String,
    /// Its whole request (not a difference to the shared one).
    pub request: CalibrationRequest,
}

impl RigCalibrationOptions {
    /// These options with `camera` calibrated by `request` (added to [`Self::per_camera`]).
    pub fn with_camera(mut self, camera: impl Into<String>, request: CalibrationRequest) -> Self {
        self.per_camera.push(CameraRequest { camera: camera.into(), request });
        self
    }

    /// The request camera `name` is calibrated with: its own (the first that names it),
    /// else the shared one.
    pub fn request_for(&self, name: &str) -> &CalibrationRequest {
        self.per_camera.iter().find(|c| c.camera == name).map_or(&self.request, |c| &c.request)
    }
}

/// The joint solve's default iteration limit.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;
