//! What the solvers return.

use super::options::StopReason;

/// Result of [`super::solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report<const N: usize> {
    /// The solution.
    pub x: [f64; N],
    /// Why the solver stopped.
    pub stop: StopReason,
    /// Sum of squared residuals at `x`.
    pub cost: f64,
    /// Cost at the start.
    pub initial_cost: f64,
    /// Iterations (Jacobian evaluations after the first).
    pub iterations: usize,
    /// Cost evaluations, trial steps included.
    pub evaluations: usize,
    /// Number of residuals.
    pub residuals: usize,
    /// Numerical rank of the Jacobian at `x`.
    pub rank: usize,
    /// Residual variance estimate cost / (residuals - rank) (cost when residuals <= rank).
    pub sigma2: f64,
    /// (J^T J)^-1 sigma2 at `x` (pseudo-inverse on the identified directions when rank
    /// deficient).
    pub covariance: [[f64; N]; N],
}

/// Result of [`super::solve_blocks`] (the block parameters are returned in place): the
/// same fields as [`Report`], with `rank` the rank of the reduced (Schur) system of the
/// shared parameters and `covariance` that of the shared parameters marginalised over the
/// block parameters, (U - sum_b W_b V_b^-1 W_b^T)^-1 sigma2.
pub type BlockReport<const N: usize> = Report<N>;
