//! The block solver: N shared parameters, M private parameters per block, the private
//! ones eliminated by the Schur complement.
//!
//! With the Gauss-Newton normal equations of one iteration written in blocks,
//!
//! ```text
//! [ U     W_1 ... W_B ] [dx ]   [-g_x ]      U   = sum J_x^T J_x,   g_x = sum J_x^T r
//! [ W_1^T V_1         ] [dy1] = [-g_y1]      W_b = J_x^T J_y (block b), V_b = J_y^T J_y
//! [ ...         ...   ] [...]   [ ... ]      g_yb = J_y^T r (block b)
//! ```
//!
//! and Marquardt damping (A + mu diag(A)), the shared step solves the reduced system
//! (U* - sum_b W_b V_b*^-1 W_b^T) dx = -(g_x - sum_b W_b V_b*^-1 g_yb), then
//! dy_b = -V_b*^-1 (g_yb + W_b^T dx). Each block keeps W_b, V_b, g_yb and its trial y in
//! caller storage ([`BlockScratch`]). The damping follows Nielsen (1999): after a step with
//! gain ratio rho > 0, mu *= max(1/3, 1 - (2 rho - 1)^3); after a rejected one mu *= nu,
//! nu *= 2. Small systems are inverted through a diagonally scaled Jacobi SVD, whose
//! truncation is the rank decision.

#![allow(clippy::needless_range_loop)] // small fixed-size linear algebra reads best indexed

use super::cholesky::psd_inverse;
use super::options::{Options, StopReason};
use super::report::BlockReport;
use crate::error::{all_finite, Error, Result};

/// Receives residual rows of one block: the residual, its gradient with respect to the
/// shared parameters and with respect to the block's own parameters.
pub trait BlockRowSink<const N: usize, const M: usize> {
    /// One residual and its two gradient rows.
    fn push(&mut self, r: f64, jac_x: &[f64; N], jac_y: &[f64; M]);
}

/// A least-squares problem whose residuals fall into blocks; block b depends only on the
/// shared parameters x and its own y_b.
pub trait BlockProblem<const N: usize, const M: usize> {
    /// Number of blocks.
    fn block_count(&self) -> usize;
    /// Streams the residuals of block `block` (gradients when `jacobian`), as
    /// [`super::Problem::eval`] does.
    fn eval_block(
        &mut self,
        block: usize,
        x: &[f64; N],
        y: &[f64; M],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<N, M>,
    ) -> Result<()>;

    /// Optionally accumulates block `block`'s normal equations at (x, y) itself, for
    /// problems whose structure makes that cheaper than streaming rows; must agree with
    /// [`BlockProblem::eval_block`]. The default returns `Ok(false)` (rows are streamed).
    fn block_normal_equations(
        &mut self,
        block: usize,
        x: &[f64; N],
        y: &[f64; M],
        out: &mut BlockNormal<'_, N, M>,
    ) -> Result<bool> {
        let _ = (block, x, y, out);
        Ok(false)
    }
}

/// Per-block storage of [`solve_blocks`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockScratch<const N: usize, const M: usize> {
    w: [[f64; M]; N],
    v: [[f64; M]; M],
    gy: [f64; M],
    y_trial: [f64; M],
}

impl<const N: usize, const M: usize> BlockScratch<N, M> {
    /// Zeroed storage (any content is fine: [`solve_blocks`] overwrites it).
    pub const ZERO: Self = BlockScratch { w: [[0.0; M]; N], v: [[0.0; M]; M], gy: [0.0; M], y_trial: [0.0; M] };
}

/// Number of [`BlockScratch`] elements [`solve_blocks`] needs for `block_count` blocks.
pub const fn solve_blocks_scratch<const N: usize, const M: usize>(block_count: usize) -> usize {
    block_count
}

/// The normal equations of one block, accumulated into the solver's storage: the block's
/// contribution to U (upper triangle) and g_x, and its own W_b, V_b (upper triangle),
/// g_yb, with the cost and row count. Also a [`BlockRowSink`] that folds rows in.
pub struct BlockNormal<'a, const N: usize, const M: usize> {
    /// sum J_x^T J_x (upper triangle), shared by all blocks.
    pub u: &'a mut [[f64; N]; N],
    /// sum J_x^T r, shared by all blocks.
    pub gx: &'a mut [f64; N],
    /// W_b = J_x^T J_y of this block.
    pub w: &'a mut [[f64; M]; N],
    /// V_b = J_y^T J_y of this block (upper triangle).
    pub v: &'a mut [[f64; M]; M],
    /// g_yb = J_y^T r of this block.
    pub gy: &'a mut [f64; M],
    /// sum r^2 of this block.
    pub cost: f64,
    /// Residuals of this block.
    pub rows: usize,
}

impl<const N: usize, const M: usize> BlockRowSink<N, M> for BlockNormal<'_, N, M> {
    fn push(&mut self, r: f64, jx: &[f64; N], jy: &[f64; M]) {
        self.cost += r * r;
        self.rows += 1;
        for i in 0..N {
            self.gx[i] += jx[i] * r;
            for j in i..N {
                self.u[i][j] += jx[i] * jx[j];
            }
            for k in 0..M {
                self.w[i][k] += jx[i] * jy[k];
            }
        }
        for k in 0..M {
            self.gy[k] += jy[k] * r;
            for l in k..M {
                self.v[k][l] += jy[k] * jy[l];
            }
        }
    }
}

/// The linearisation at (x, y): U (full symmetric), g_x, the cost and the row count; the
/// per-block parts go to `scratch`.
struct Linearization<const N: usize> {
    u: [[f64; N]; N],
    gx: [f64; N],
    cost: f64,
    rows: usize,
}

fn evaluate<const N: usize, const M: usize, P: BlockProblem<N, M>>(
    problem: &mut P,
    x: &[f64; N],
    ys: &[[f64; M]],
    scratch: &mut [BlockScratch<N, M>],
) -> Result<Linearization<N>> {
    let mut lin = Linearization { u: [[0.0; N]; N], gx: [0.0; N], cost: 0.0, rows: 0 };
    for (b, (y, blk)) in ys.iter().zip(scratch.iter_mut()).enumerate() {
        blk.w = [[0.0; M]; N];
        blk.v = [[0.0; M]; M];
        blk.gy = [0.0; M];
        let mut acc = BlockNormal {
            u: &mut lin.u,
            gx: &mut lin.gx,
            w: &mut blk.w,
            v: &mut blk.v,
            gy: &mut blk.gy,
            cost: 0.0,
            rows: 0,
        };
        if !problem.block_normal_equations(b, x, y, &mut acc)? {
            problem.eval_block(b, x, y, true, &mut acc)?;
        }
        lin.cost += acc.cost;
        lin.rows += acc.rows;
        for k in 0..M {
            for l in 0..k {
                blk.v[k][l] = blk.v[l][k];
            }
        }
    }
    for i in 0..N {
        for j in 0..i {
            lin.u[i][j] = lin.u[j][i];
        }
    }
    if !lin.cost.is_finite() {
        return Err(Error::NotFinite { what: "residuals" });
    }
    Ok(lin)
}

/// One damped step: returns dx, the rank of the reduced system, and writes y_b + dy_b
/// into each block's `y_trial`. Also returns the predicted reduction of the cost.
fn step<const N: usize, const M: usize>(
    lin: &Linearization<N>,
    ys: &[[f64; M]],
    scratch: &mut [BlockScratch<N, M>],
    mu: f64,
    tol: f64,
) -> ([f64; N], usize, f64) {
    let mut s = lin.u;
    let mut rhs = [0.0; N];
    for i in 0..N {
        s[i][i] += mu * lin.u[i][i];
        rhs[i] = -lin.gx[i];
    }
    for blk in scratch.iter() {
        let mut vd = blk.v;
        for k in 0..M {
            vd[k][k] += mu * blk.v[k][k];
        }
        let (vinv, _) = psd_inverse(&vd, tol);
        // wv = W V*^-1 (N x M)
        let mut wv = [[0.0; M]; N];
        for i in 0..N {
            for l in 0..M {
                wv[i][l] = (0..M).map(|k| blk.w[i][k] * vinv[k][l]).sum();
            }
        }
        for i in 0..N {
            for j in 0..N {
                s[i][j] -= (0..M).map(|k| wv[i][k] * blk.w[j][k]).sum::<f64>();
            }
            rhs[i] += (0..M).map(|k| wv[i][k] * blk.gy[k]).sum::<f64>();
        }
    }
    let (sinv, rank) = psd_inverse(&s, tol);
    let mut dx = [0.0; N];
    for i in 0..N {
        dx[i] = (0..N).map(|j| sinv[i][j] * rhs[j]).sum();
    }
    // pred = mu h^T diag(A) h - h^T g over the shared and all block parameters.
    let mut pred = 0.0;
    for i in 0..N {
        pred += mu * lin.u[i][i] * dx[i] * dx[i] - dx[i] * lin.gx[i];
    }
    for (y, blk) in ys.iter().zip(scratch.iter_mut()) {
        let mut vd = blk.v;
        for k in 0..M {
            vd[k][k] += mu * blk.v[k][k];
        }
        let (vinv, _) = psd_inverse(&vd, tol);
        let mut t = [0.0; M];
        for k in 0..M {
            t[k] = blk.gy[k] + (0..N).map(|i| blk.w[i][k] * dx[i]).sum::<f64>();
        }
        for k in 0..M {
            let dy: f64 = -(0..M).map(|l| vinv[k][l] * t[l]).sum::<f64>();
            blk.y_trial[k] = y[k] + dy;
            pred += mu * blk.v[k][k] * dy * dy - dy * blk.gy[k];
        }
    }
    (dx, rank, pred)
}

/// Minimises the sum of squared residuals of a block problem over the shared `x` (start
/// `x0`) and the per-block `y` (start and result, in place).
///
/// `scratch` needs [`solve_blocks_scratch`] elements (its content is overwritten).
/// Errors: non-finite start; `y.len()` not equal to the block count
/// ([`Error::InvalidArgument`]); scratch too small ([`Error::BufferTooSmall`]); the
/// problem's own error or non-finite residuals at the start; no residuals. Everything
/// after the start is reported through [`BlockReport::stop`].
///
/// Stack: about 6 N^2 + 4 M^2 + 3 N M numbers.
pub fn solve_blocks<const N: usize, const M: usize, P: BlockProblem<N, M>>(
    problem: &mut P,
    x0: [f64; N],
    y: &mut [[f64; M]],
    options: &Options,
    scratch: &mut [BlockScratch<N, M>],
) -> Result<BlockReport<N>> {
    all_finite(&x0, "starting point")?;
    let blocks = problem.block_count();
    if y.len() != blocks {
        return Err(Error::InvalidArgument { what: "y must hold one parameter vector per block" });
    }
    if scratch.len() < blocks {
        return Err(Error::BufferTooSmall { what: "block scratch", needed: blocks, got: scratch.len() });
    }
    if y.iter().any(|b| b.iter().any(|v| !v.is_finite())) {
        return Err(Error::NotFinite { what: "block starting values" });
    }
    let scratch =
        scratch.get_mut(..blocks).ok_or(Error::BufferTooSmall { what: "block scratch", needed: blocks, got: 0 })?;
    let unknowns = N + M * blocks;
    let tol = options.rank_tolerance;
    let mut x = x0;
    let mut lin = evaluate(problem, &x, y, scratch)?;
    if lin.rows == 0 {
        return Err(Error::TooFew { what: "residuals", needed: 1, got: 0 });
    }
    let initial_cost = lin.cost;
    let rows = lin.rows;
    let mut evaluations = 1usize;
    let mut iterations = 0usize;
    let mut mu = options.initial_damping;
    let mut nu = 2.0;
    let mut pending: Option<StopReason> = None;
    loop {
        let f = lin.cost;
        // The undamped reduced system: rank, and the covariance if we stop here.
        let (_, rank, _) = step(&lin, y, scratch, 0.0, tol);
        macro_rules! finish {
            ($stop:expr) => {{
                let mut s0 = lin.u;
                for blk in scratch.iter() {
                    let (vinv, _) = psd_inverse(&blk.v, tol);
                    for i in 0..N {
                        for j in 0..N {
                            let mut acc = 0.0;
                            for k in 0..M {
                                for l in 0..M {
                                    acc += blk.w[i][k] * vinv[k][l] * blk.w[j][l];
                                }
                            }
                            s0[i][j] -= acc;
                        }
                    }
                }
                let (mut cov, _) = psd_inverse(&s0, tol);
                let dof = rows.saturating_sub(unknowns);
                let sigma2 = if dof > 0 { f / dof as f64 } else { f };
                for row in cov.iter_mut() {
                    for c in row.iter_mut() {
                        *c *= sigma2;
                    }
                }
                return Ok(BlockReport {
                    x,
                    stop: $stop,
                    cost: f,
                    initial_cost,
                    iterations,
                    evaluations,
                    residuals: rows,
                    rank,
                    sigma2,
                    covariance: cov,
                });
            }};
        }
        if let Some(stop) = pending {
            finish!(stop);
        }
        if f == 0.0 {
            finish!(StopReason::CostTolerance);
        }
        if rank < N {
            finish!(StopReason::RankDeficient);
        }
        // Gradient test over every parameter: |g_j| / (||J e_j|| ||r||).
        let sf = libm::sqrt(f);
        let mut gnorm = 0.0f64;
        for i in 0..N {
            if lin.u[i][i] > 0.0 {
                gnorm = gnorm.max(lin.gx[i].abs() / (libm::sqrt(lin.u[i][i]) * sf));
            }
        }
        for blk in scratch.iter() {
            for k in 0..M {
                if blk.v[k][k] > 0.0 {
                    gnorm = gnorm.max(blk.gy[k].abs() / (libm::sqrt(blk.v[k][k]) * sf));
                }
            }
        }
        if gnorm <= options.gtol {
            finish!(StopReason::GradientTolerance);
        }
        loop {
            let (dx, _, pred) = step(&lin, y, scratch, mu, tol);
            let xnew: [f64; N] = core::array::from_fn(|i| x[i] + dx[i]);
            // Scaled norms of the step and of the parameters (scale: sqrt(diag(J^T J))).
            let (mut hn, mut xn) = (0.0, 0.0);
            for i in 0..N {
                let d = lin.u[i][i];
                hn += d * dx[i] * dx[i];
                xn += d * x[i] * x[i];
            }
            for (yb, blk) in y.iter().zip(scratch.iter()) {
                for k in 0..M {
                    let d = blk.v[k][k];
                    let dy = blk.y_trial[k] - yb[k];
                    hn += d * dy * dy;
                    xn += d * yb[k] * yb[k];
                }
            }
            let (hn, xn) = (libm::sqrt(hn), libm::sqrt(xn));
            evaluations += 1;
            let fnew = trial_cost(problem, &xnew, scratch);
            let actred = match fnew {
                Some(c) => f - c,
                None => -f,
            };
            let rho = if pred > 0.0 { actred / pred } else { -1.0 };
            let accepted = fnew.is_some() && rho > 1e-4 && actred > 0.0;
            let mut stop = None;
            if actred.abs() <= options.ftol * f && pred <= options.ftol * f && pred >= 0.0 {
                stop = Some(StopReason::CostTolerance);
            } else if hn <= options.xtol * (xn + options.xtol) {
                stop = Some(StopReason::StepTolerance);
            } else if evaluations >= options.max_evaluations {
                stop = Some(StopReason::MaxIterations);
            } else if !accepted && mu > 1e30 {
                stop = Some(StopReason::NoProgress);
            }
            if accepted {
                x = xnew;
                for (yb, blk) in y.iter_mut().zip(scratch.iter()) {
                    *yb = blk.y_trial;
                }
                let t = 2.0 * rho - 1.0;
                mu *= (1.0 - t * t * t).max(1.0 / 3.0);
                nu = 2.0;
                iterations += 1;
                if stop.is_none() && iterations >= options.max_iterations {
                    stop = Some(StopReason::MaxIterations);
                }
                pending = stop;
                break;
            }
            if let Some(s) = stop {
                finish!(s);
            }
            mu *= nu;
            nu *= 2.0;
        }
        lin = evaluate(problem, &x, y, scratch)?;
        evaluations += 1;
    }
}

/// Cost at the trial point (x, the blocks' `y_trial`), or `None` if refused or non-finite.
fn trial_cost<const N: usize, const M: usize, P: BlockProblem<N, M>>(
    problem: &mut P,
    x: &[f64; N],
    scratch: &[BlockScratch<N, M>],
) -> Option<f64> {
    struct Cost(f64);
    impl<const N: usize, const M: usize> BlockRowSink<N, M> for Cost {
        fn push(&mut self, r: f64, _: &[f64; N], _: &[f64; M]) {
            self.0 += r * r;
        }
    }
    let mut c = Cost(0.0);
    for (b, blk) in scratch.iter().enumerate() {
        if problem.eval_block(b, x, &blk.y_trial, false, &mut c).is_err() {
            return None;
        }
    }
    c.0.is_finite().then_some(c.0)
}
