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
/// `etlcal calibrate` takes, applied to every camera: model, estimator, priors, A0 source)
/// and the joint solve's.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RigCalibrationOptions {
    /// Every camera's calibration request (the proposed method only).
    pub request: CalibrationRequest,
    /// The linear solver of the joint steps.
    pub solver: LinearSolver,
    /// The most Levenberg-Marquardt iterations of the joint solve (0: the default, 100).
    pub max_iterations: usize,
}

/// The joint solve's default iteration limit.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;
