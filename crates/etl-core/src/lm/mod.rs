//! A hand-written Levenberg-Marquardt solver for a fixed number of parameters.
//!
//! Two front ends share one set of options and stop reasons:
//!
//! - [`solve`]: dense problems with `N` parameters. Residual rows are *streamed* through a
//!   [`RowSink`], folded into the triangular factor R of the Jacobian by Givens rotations
//!   as they arrive (MINPACK's `lmstr` idea), so memory is O(N^2) whatever the number of
//!   residuals. The step is Moré's (1978) trust-region Levenberg-Marquardt step with
//!   MINPACK's adaptive column scaling, computed from the SVD ([`crate::linalg::svd`]) of the scaled factor, which
//!   also gives an honest numerical rank.
//! - [`solve_blocks`]: problems with `N` shared parameters and `M` private parameters per
//!   block (a view's pose in Zhang's method; a view's stage/current corrections in the
//!   errors-in-variables bundle adjustment). The private parameters are eliminated by the
//!   Schur complement in caller-provided storage ([`solve_blocks_scratch`]); damping is
//!   Marquardt's diagonal scaling with Nielsen's (1999) update.
//!
//! Cost convention: `cost` = sum of squared residuals (no factor 1/2).
//!
//! ```
//! use etl_core::lm::{solve, Options, Problem, RowSink};
//! // Fit y = a exp(b x) to exact data with a = 2, b = -0.5.
//! struct Exp;
//! impl Problem<2> for Exp {
//!     fn eval(&mut self, x: &[f64; 2], _jac: bool, sink: &mut dyn RowSink<2>) -> etl_core::Result<()> {
//!         for i in 0..10 {
//!             let t = i as f64;
//!             let e = libm::exp(x[1] * t);
//!             sink.push(x[0] * e - 2.0 * libm::exp(-0.5 * t), &[e, x[0] * t * e]);
//!         }
//!         Ok(())
//!     }
//! }
//! let report = solve(&mut Exp, [1.0, 0.0], &Options::default()).unwrap();
//! assert!((report.x[0] - 2.0).abs() < 1e-10 && (report.x[1] + 0.5).abs() < 1e-10);
//! ```

mod blocks;
mod dense;
mod options;
mod report;

pub use blocks::{
    solve_blocks, solve_blocks_scratch, BlockNormal, BlockProblem, BlockRowSink, BlockScratch, BlockStorage,
};
pub use dense::solve;
pub use options::{Accumulation, Options, StopReason};
pub use report::{BlockReport, Report};

use crate::error::Result;

/// Receives residual rows: the residual value and its gradient with respect to the
/// parameters (zeros when the solver asked for no Jacobian).
pub trait RowSink<const N: usize> {
    /// One residual `r` and its gradient row `jac` = dr/dx.
    fn push(&mut self, r: f64, jac: &[f64; N]);
}

/// A least-squares problem with `N` parameters: minimise sum_i r_i(x)^2.
pub trait Problem<const N: usize> {
    /// Streams every residual r_i(x) into `sink`, with its gradient row when `jacobian` is
    /// true (otherwise the row content is ignored). The residuals must come in the same
    /// number on every call. Returning an error at the starting point aborts the solve; at
    /// a trial point it rejects the step (e.g. a point that went behind the camera).
    fn eval(&mut self, x: &[f64; N], jacobian: bool, sink: &mut dyn RowSink<N>) -> Result<()>;

    /// Optionally accumulates J^T J, J^T r, the cost and the residual count at `x` itself,
    /// for problems whose structure makes that cheaper than streaming rows (the bundle
    /// adjustment: each view's rows factor through 13 variables). Used only with
    /// [`Accumulation::NormalEquations`]; must agree with [`Problem::eval`] (same residuals,
    /// same count). The default returns `Ok(false)`: rows are streamed through `eval`.
    fn normal_equations(&mut self, x: &[f64; N], out: &mut NormalEquations<N>) -> Result<bool> {
        let _ = (x, out);
        Ok(false)
    }
}

/// The normal equations of a linearisation: J^T J (upper triangle, row i from column i),
/// J^T r, the cost sum r_i^2 and the number of residuals. Also a [`RowSink`] that folds
/// rows in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalEquations<const N: usize> {
    /// J^T J; only the upper triangle (j >= i) is read.
    pub a: [[f64; N]; N],
    /// J^T r.
    pub g: [f64; N],
    /// sum r_i^2.
    pub cost: f64,
    /// Number of residuals.
    pub rows: usize,
}

impl<const N: usize> NormalEquations<N> {
    /// Empty equations.
    pub const ZERO: Self = NormalEquations { a: [[0.0; N]; N], g: [0.0; N], cost: 0.0, rows: 0 };
}

impl<const N: usize> RowSink<N> for NormalEquations<N> {
    fn push(&mut self, r: f64, jac: &[f64; N]) {
        self.rows += 1;
        self.cost += r * r;
        for (i, (ai, &ji)) in self.a.iter_mut().zip(jac.iter()).enumerate() {
            self.g[i] += ji * r;
            for (aik, &jk) in ai.iter_mut().zip(jac.iter()).skip(i) {
                *aik += ji * jk;
            }
        }
    }
}
