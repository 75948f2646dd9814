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

use super::options::{stop_reason, Options, StopReason, TrialOutcome};
use super::report::BlockReport;
use crate::error::{all_finite, Error, Result};
use crate::linalg::cholesky::psd_inverse;

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

/// Per-block storage of [`solve_blocks`]: the block's parameters y_b (start and result)
/// and the solver's working state of the block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockScratch<const N: usize, const M: usize> {
    y: [f64; M],
    w: [[f64; M]; N],
    v: [[f64; M]; M],
    gy: [f64; M],
    y_trial: [f64; M],
}

impl<const N: usize, const M: usize> BlockScratch<N, M> {
    /// Zeroed storage: y_b starts at 0 (the working state's content does not matter:
    /// [`solve_blocks`] overwrites it).
    pub const ZERO: Self = Self::starting_at([0.0; M]);

    /// Storage whose block parameters start at `y`.
    pub const fn starting_at(y: [f64; M]) -> Self {
        BlockScratch { y, w: [[0.0; M]; N], v: [[0.0; M]; M], gy: [0.0; M], y_trial: [0.0; M] }
    }

    /// The block's parameters: the start before [`solve_blocks`], the estimate after it.
    pub const fn y(&self) -> &[f64; M] {
        &self.y
    }

    /// Sets the block's starting parameters.
    pub fn set_y(&mut self, y: [f64; M]) {
        self.y = y;
    }
}

/// Where a block's [`BlockScratch`] lives: the scratch itself, or a caller's type that
/// holds one of several sizes (the bundle adjustment's per-view storage serves every
/// parameter layout). [`solve_blocks`] refuses storage that holds none of size `N`.
pub trait BlockStorage<const N: usize, const M: usize> {
    /// The block's scratch of size `N`, if this storage holds one.
    fn block(&self) -> Option<&BlockScratch<N, M>>;
    /// The same, mutable.
    fn block_mut(&mut self) -> Option<&mut BlockScratch<N, M>>;
}

impl<const N: usize, const M: usize> BlockStorage<N, M> for BlockScratch<N, M> {
    fn block(&self) -> Option<&BlockScratch<N, M>> {
        Some(self)
    }
    fn block_mut(&mut self) -> Option<&mut BlockScratch<N, M>> {
        Some(self)
    }
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

fn evaluate<const N: usize, const M: usize, P: BlockProblem<N, M>, S: BlockStorage<N, M>>(
    problem: &mut P,
    x: &[f64; N],
    scratch: &mut [S],
) -> Result<Linearization<N>> {
    let mut lin = Linearization { u: [[0.0; N]; N], gx: [0.0; N], cost: 0.0, rows: 0 };
    for (b, blk) in scratch.iter_mut().filter_map(S::block_mut).enumerate() {
        let y = &{ blk.y };
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
fn step<const N: usize, const M: usize, S: BlockStorage<N, M>>(
    lin: &Linearization<N>,
    scratch: &mut [S],
    mu: f64,
    tol: f64,
) -> ([f64; N], usize, f64) {
    let mut s = lin.u;
    let mut rhs = [0.0; N];
    for i in 0..N {
        s[i][i] += mu * lin.u[i][i];
        rhs[i] = -lin.gx[i];
    }
    for blk in scratch.iter().filter_map(S::block) {
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
    for blk in scratch.iter_mut().filter_map(S::block_mut) {
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
            blk.y_trial[k] = blk.y[k] + dy;
            pred += mu * blk.v[k][k] * dy * dy - dy * blk.gy[k];
        }
    }
    (dx, rank, pred)
}

/// The report at (x, y): rank of the undamped reduced system, and the covariance of the
/// shared parameters marginalised over the blocks, (U - sum_b W_b V_b^-1 W_b^T)^-1 sigma2
/// with sigma2 = cost / (residuals - unknowns).
fn finish<const N: usize, const M: usize, S: BlockStorage<N, M>>(
    state: &State<N>,
    lin: &Linearization<N>,
    scratch: &[S],
    stop: StopReason,
    rank: usize,
    tol: f64,
) -> BlockReport<N> {
    let mut s0 = lin.u;
    for blk in scratch.iter().filter_map(S::block) {
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
    let unknowns = N + M * scratch.len();
    let dof = state.rows.saturating_sub(unknowns);
    let f = lin.cost;
    let sigma2 = if dof > 0 { f / dof as f64 } else { f };
    for row in cov.iter_mut() {
        for c in row.iter_mut() {
            *c *= sigma2;
        }
    }
    BlockReport {
        x: state.x,
        stop,
        cost: f,
        initial_cost: state.initial_cost,
        iterations: state.iterations,
        evaluations: state.evaluations,
        residuals: state.rows,
        rank,
        sigma2,
        covariance: cov,
    }
}

/// The largest cosine between r and a column of J over every parameter:
/// |g_j| / (||J e_j|| ||r||).
fn gradient_cosine<const N: usize, const M: usize, S: BlockStorage<N, M>>(
    lin: &Linearization<N>,
    scratch: &[S],
) -> f64 {
    let sf = libm::sqrt(lin.cost);
    let mut gnorm = 0.0f64;
    for i in 0..N {
        if lin.u[i][i] > 0.0 {
            gnorm = gnorm.max(lin.gx[i].abs() / (libm::sqrt(lin.u[i][i]) * sf));
        }
    }
    for blk in scratch.iter().filter_map(S::block) {
        for k in 0..M {
            if blk.v[k][k] > 0.0 {
                gnorm = gnorm.max(blk.gy[k].abs() / (libm::sqrt(blk.v[k][k]) * sf));
            }
        }
    }
    gnorm
}

/// Scaled norms of the step (dx, the blocks' y_trial - y) and of the parameters, the scale
/// being sqrt(diag(J^T J)).
fn scaled_norms<const N: usize, const M: usize, S: BlockStorage<N, M>>(
    lin: &Linearization<N>,
    x: &[f64; N],
    dx: &[f64; N],
    scratch: &[S],
) -> (f64, f64) {
    let (mut hn, mut xn) = (0.0, 0.0);
    for i in 0..N {
        let d = lin.u[i][i];
        hn += d * dx[i] * dx[i];
        xn += d * x[i] * x[i];
    }
    for blk in scratch.iter().filter_map(S::block) {
        for k in 0..M {
            let d = blk.v[k][k];
            let dy = blk.y_trial[k] - blk.y[k];
            hn += d * dy * dy;
            xn += d * blk.y[k] * blk.y[k];
        }
    }
    (libm::sqrt(hn), libm::sqrt(xn))
}

/// The shared iterate, Nielsen's damping state and the counters.
struct State<const N: usize> {
    x: [f64; N],
    mu: f64,
    nu: f64,
    initial_cost: f64,
    rows: usize,
    evaluations: usize,
    iterations: usize,
}

/// How the inner loop of one iteration ended.
enum Inner {
    /// A step was accepted (the state and the blocks' y hold it); a stop may be pending.
    Accepted(Option<StopReason>),
    /// The solver stops at the current (x, y).
    Stopped(StopReason),
}

/// The inner loop: raise the damping until a step is accepted (Nielsen's update) or a
/// stop test fires.
fn inner_loop<const N: usize, const M: usize, P: BlockProblem<N, M>, S: BlockStorage<N, M>>(
    problem: &mut P,
    state: &mut State<N>,
    lin: &Linearization<N>,
    scratch: &mut [S],
    options: &Options,
) -> Inner {
    let f = lin.cost;
    loop {
        let (dx, _, pred) = step(lin, scratch, state.mu, options.rank_tolerance);
        let xnew: [f64; N] = core::array::from_fn(|i| state.x[i] + dx[i]);
        let (hn, xn) = scaled_norms(lin, &state.x, &dx, scratch);
        state.evaluations += 1;
        let fnew = trial_cost(problem, &xnew, scratch);
        let actred = match fnew {
            Some(c) => f - c,
            None => -f,
        };
        let rho = if pred > 0.0 { actred / pred } else { -1.0 };
        let accepted = fnew.is_some() && rho > 1e-4 && actred > 0.0;
        let trial = TrialOutcome {
            cost_converged: actred.abs() <= options.ftol * f && pred <= options.ftol * f && pred >= 0.0,
            step_converged: hn <= options.xtol * (xn + options.xtol),
            stalled: state.mu > 1e30,
            accepted,
        };
        if accepted {
            state.x = xnew;
            for blk in scratch.iter_mut().filter_map(S::block_mut) {
                blk.y = blk.y_trial;
            }
            let t = 2.0 * rho - 1.0;
            state.mu *= (1.0 - t * t * t).max(1.0 / 3.0);
            state.nu = 2.0;
            state.iterations += 1;
        }
        let stop = stop_reason(&trial, state.evaluations, state.iterations, options);
        if accepted {
            return Inner::Accepted(stop);
        }
        if let Some(s) = stop {
            return Inner::Stopped(s);
        }
        state.mu *= state.nu;
        state.nu *= 2.0;
    }
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
pub fn solve_blocks<const N: usize, const M: usize, P: BlockProblem<N, M>, S: BlockStorage<N, M>>(
    problem: &mut P,
    x0: [f64; N],
    options: &Options,
    blocks: &mut [S],
) -> Result<BlockReport<N>> {
    all_finite(&x0, "starting point")?;
    let count = problem.block_count();
    if blocks.len() < count {
        return Err(Error::BufferTooSmall { what: "block scratch", needed: count, got: blocks.len() });
    }
    let scratch =
        blocks.get_mut(..count).ok_or(Error::BufferTooSmall { what: "block scratch", needed: count, got: 0 })?;
    if scratch.iter().any(|b| b.block().is_none()) {
        return Err(Error::InvalidArgument { what: "block storage does not hold this problem's size" });
    }
    if scratch.iter().filter_map(S::block).any(|b| b.y.iter().any(|v| !v.is_finite())) {
        return Err(Error::NotFinite { what: "block starting values" });
    }
    let tol = options.rank_tolerance;
    let mut lin = evaluate(problem, &x0, scratch)?;
    if lin.rows == 0 {
        return Err(Error::TooFew { what: "residuals", needed: 1, got: 0 });
    }
    let mut state = State {
        x: x0,
        mu: options.initial_damping,
        nu: 2.0,
        initial_cost: lin.cost,
        rows: lin.rows,
        evaluations: 1,
        iterations: 0,
    };
    let mut pending: Option<StopReason> = None;
    loop {
        // The undamped reduced system: rank, and the covariance if we stop here.
        let (_, rank, _) = step(&lin, scratch, 0.0, tol);
        let stop = if let Some(stop) = pending {
            Some(stop)
        } else if lin.cost == 0.0 {
            Some(StopReason::CostTolerance)
        } else if rank < N {
            Some(StopReason::RankDeficient)
        } else if gradient_cosine(&lin, scratch) <= options.gtol {
            Some(StopReason::GradientTolerance)
        } else {
            match inner_loop(problem, &mut state, &lin, scratch, options) {
                Inner::Accepted(stop) => {
                    pending = stop;
                    None
                }
                Inner::Stopped(stop) => Some(stop),
            }
        };
        if let Some(stop) = stop {
            return Ok(finish(&state, &lin, scratch, stop, rank, tol));
        }
        lin = evaluate(problem, &state.x, scratch)?;
        state.evaluations += 1;
    }
}

/// Cost at the trial point (x, the blocks' `y_trial`), or `None` if refused or non-finite.
fn trial_cost<const N: usize, const M: usize, P: BlockProblem<N, M>, S: BlockStorage<N, M>>(
    problem: &mut P,
    x: &[f64; N],
    scratch: &[S],
) -> Option<f64> {
    struct Cost(f64);
    impl<const N: usize, const M: usize> BlockRowSink<N, M> for Cost {
        fn push(&mut self, r: f64, _: &[f64; N], _: &[f64; M]) {
            self.0 += r * r;
        }
    }
    let mut c = Cost(0.0);
    for (b, blk) in scratch.iter().filter_map(S::block).enumerate() {
        if problem.eval_block(b, x, &blk.y_trial, false, &mut c).is_err() {
            return None;
        }
    }
    c.0.is_finite().then_some(c.0)
}
