//! The dense solver: streamed Givens QR of the Jacobian, Moré's trust-region step.
//!
//! Notation (Moré 1978, "The Levenberg-Marquardt algorithm: implementation and theory"):
//! J = Q R (R from the streamed rows), f = ||r||^2, D = diag(d_j) the scaling with
//! d_j = max over iterations of the column norms ||J e_j|| (MINPACK mode 1). The step p
//! minimises ||R p + Q^T r||^2 subject to ||D p|| <= Delta. With B = R D^-1 = U S V^T,
//! z = D p = -sum_k v_k s_k c_k / (s_k^2 + mu), c = U^T Q^T r, and mu >= 0 is found from
//! the secular equation ||z(mu)|| = Delta (mu = 0 when the Gauss-Newton step fits).
//! Directions with s_k below `rank_tolerance * s_max` are dropped: that is the rank
//! decision, reported in [`Report::rank`].

use super::options::{stop_reason, Accumulation, Options, StopReason, TrialOutcome};
use super::report::Report;
use super::{NormalEquations, Problem, RowSink};
use crate::error::{all_finite, Error, Result};
use crate::fit::GivensQr;
use crate::linalg::cholesky::normal_equations_factor;
use crate::linalg::svd::Svd;
use crate::linalg::triangular::certified_upper_inverse;

struct QrSink<const N: usize> {
    qr: GivensQr<N>,
    cost: f64,
    rows: usize,
    error: Option<Error>,
}

impl<const N: usize> RowSink<N> for QrSink<N> {
    fn push(&mut self, r: f64, jac: &[f64; N]) {
        self.rows += 1;
        self.cost += r * r;
        if self.error.is_none() {
            if let Err(e) = self.qr.add_row(jac, r, 1.0) {
                self.error = Some(e);
            }
        }
    }
}

struct CostSink {
    cost: f64,
    rows: usize,
}

impl<const N: usize> RowSink<N> for CostSink {
    fn push(&mut self, r: f64, _jac: &[f64; N]) {
        self.rows += 1;
        self.cost += r * r;
    }
}

/// The linearisation at one point: R, Q^T r, the cost and the row count.
struct Linearization<const N: usize> {
    r: [[f64; N]; N],
    qtf: [f64; N],
    cost: f64,
    rows: usize,
}

fn linearize<const N: usize, P: Problem<N>>(
    problem: &mut P,
    x: &[f64; N],
    accumulation: Accumulation,
) -> Result<Linearization<N>> {
    let (r, qtf, cost, rows) = match accumulation {
        Accumulation::Qr => {
            let mut sink = QrSink { qr: GivensQr::<N>::full(), cost: 0.0, rows: 0, error: None };
            problem.eval(x, true, &mut sink)?;
            if let Some(e) = sink.error {
                return Err(e);
            }
            (*sink.qr.r_factor(), *sink.qr.qty(), sink.cost, sink.rows)
        }
        Accumulation::NormalEquations => {
            let mut sink = NormalEquations::<N>::ZERO;
            if !problem.normal_equations(x, &mut sink)? {
                problem.eval(x, true, &mut sink)?;
            }
            let (r, qtf) = normal_equations_factor(&sink.a, &sink.g);
            (r, qtf, sink.cost, sink.rows)
        }
    };
    if !cost.is_finite() || r.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::NotFinite { what: "residuals or Jacobian" });
    }
    if rows == 0 {
        return Err(Error::TooFew { what: "residuals", needed: 1, got: 0 });
    }
    Ok(Linearization { r, qtf, cost, rows })
}

/// Cost at a trial point, or `None` when the problem refuses it or it is not finite.
fn trial_cost<const N: usize, P: Problem<N>>(problem: &mut P, x: &[f64; N], rows: usize) -> Option<f64> {
    let mut sink = CostSink { cost: 0.0, rows: 0 };
    match problem.eval(x, false, &mut sink) {
        Ok(()) if sink.cost.is_finite() && sink.rows == rows => Some(sink.cost),
        _ => None,
    }
}

/// The scaled step z(mu) = D p for damping `mu` over the retained directions.
fn scaled_step<const N: usize>(svd: &Svd<N>, c: &[f64; N], keep: &[bool; N], mu: f64) -> [f64; N] {
    let mut z = [0.0; N];
    for k in 0..N {
        if !keep[k] {
            continue;
        }
        let s = svd.s[k];
        let w = s * c[k] / (s * s + mu);
        for i in 0..N {
            z[i] -= w * svd.v[k][i];
        }
    }
    z
}

fn norm<const N: usize>(z: &[f64; N]) -> f64 {
    libm::sqrt(z.iter().map(|x| x * x).sum::<f64>())
}

/// Solves ||z(mu)|| = delta for mu >= 0 (safeguarded Newton on 1/||z||, Moré's choice
/// because 1/||z(mu)|| is nearly linear in mu), to 10 % as MINPACK does.
fn secular_mu<const N: usize>(svd: &Svd<N>, c: &[f64; N], keep: &[bool; N], delta: f64) -> f64 {
    let znorm = |mu: f64| -> (f64, f64) {
        let (mut n2, mut d) = (0.0, 0.0);
        for k in 0..N {
            if keep[k] {
                let s = svd.s[k];
                let den = s * s + mu;
                let w = s * c[k] / den;
                n2 += w * w;
                d -= w * w / den;
            }
        }
        let n = libm::sqrt(n2);
        (n, if n > 0.0 { d / n } else { 0.0 })
    };
    let (n0, _) = znorm(0.0);
    if n0 <= 1.1 * delta {
        return 0.0;
    }
    let mut hi = 0.0f64;
    for k in 0..N {
        if keep[k] {
            hi += (svd.s[k] * c[k]) * (svd.s[k] * c[k]);
        }
    }
    hi = libm::sqrt(hi) / delta;
    let mut lo = 0.0;
    let mut mu = 0.0;
    for _ in 0..60 {
        let (n, dn) = znorm(mu);
        if (n - delta).abs() <= 0.1 * delta {
            break;
        }
        if n > delta {
            lo = mu;
        } else {
            hi = mu;
        }
        let newton = if dn < 0.0 { mu - n * (n - delta) / (delta * dn) } else { f64::NAN };
        mu = if newton > lo && newton < hi { newton } else { libm::sqrt(lo * hi).max(1e-3 * hi) };
    }
    mu
}

/// (J^T J)^+ sigma2 = D^-1 V S^-2 V^T D^-1 sigma2 over the retained directions.
fn covariance_from_svd<const N: usize>(svd: &Svd<N>, keep: &[bool; N], diag: &[f64; N], sigma2: f64) -> [[f64; N]; N] {
    let mut cov = [[0.0; N]; N];
    for k in 0..N {
        if keep[k] {
            let w = sigma2 / (svd.s[k] * svd.s[k]);
            for i in 0..N {
                for j in 0..N {
                    cov[i][j] += w * svd.v[k][i] * svd.v[k][j] / (diag[i] * diag[j]);
                }
            }
        }
    }
    cov
}

/// The SVD of the scaled factor B = U S V^T with the rank decision and c = U^T Q^T r.
struct Spectral<const N: usize> {
    svd: Svd<N>,
    keep: [bool; N],
    rank: usize,
    c: [f64; N],
}

impl<const N: usize> Spectral<N> {
    /// `b` row-major (upper triangular), `qtf` = Q^T r.
    fn of(b: &[[f64; N]; N], qtf: &[f64; N], rank_tolerance: f64) -> Result<Self> {
        let svd = Svd::of_rows(b);
        let smax = svd.max_singular_value();
        if !smax.is_finite() {
            return Err(Error::NotFinite { what: "Jacobian" });
        }
        let mut keep = [false; N];
        let mut rank = 0;
        for k in 0..N {
            keep[k] = svd.s[k] > rank_tolerance * smax && svd.s[k] > 0.0;
            rank += keep[k] as usize;
        }
        let c = core::array::from_fn(|k| (0..N).map(|i| svd.u[k][i] * qtf[i]).sum());
        Ok(Spectral { svd, keep, rank, c })
    }
}

/// (J^T J)^-1 sigma2 = D^-1 B^-1 B^-T D^-1 sigma2 for a certified full-rank B.
fn covariance_from_inverse<const N: usize>(b_inv: &[[f64; N]; N], diag: &[f64; N], sigma2: f64) -> [[f64; N]; N] {
    let mut cov = [[0.0; N]; N];
    for ((ci, bi), di) in cov.iter_mut().zip(b_inv.iter()).zip(diag.iter()) {
        for ((cij, bj), dj) in ci.iter_mut().zip(b_inv.iter()).zip(diag.iter()) {
            let s: f64 = bi.iter().zip(bj.iter()).map(|(a, b)| a * b).sum();
            *cij = sigma2 * s / (di * dj);
        }
    }
    cov
}

/// The scaled factor B = R D^-1 of one linearisation and what the steps need of it: the
/// certified inverse (Gauss-Newton step by a triangular solve) or the SVD (rank decision,
/// damped steps), computed lazily.
struct Scaled<const N: usize> {
    b: [[f64; N]; N],
    b_inv: Option<[[f64; N]; N]>,
    z_gauss_newton: Option<[f64; N]>,
    spectral: Option<Spectral<N>>,
    /// The rank decided at the linearisation (N when B is certified).
    rank: usize,
}

impl<const N: usize> Scaled<N> {
    /// B = R D^-1 (upper triangular). When B is certified well inside full rank, the
    /// Gauss-Newton step comes from a triangular solve and the SVD is computed only if the
    /// trust region binds (or for the covariance at the end): the usual case near a
    /// solution.
    fn of(lin: &Linearization<N>, diag: &[f64; N], rank_tolerance: f64) -> Result<Self> {
        let mut b = [[0.0; N]; N];
        for (bi, ri) in b.iter_mut().zip(lin.r.iter()) {
            for ((bij, rij), dj) in bi.iter_mut().zip(ri.iter()).zip(diag.iter()) {
                *bij = rij / dj;
            }
        }
        let b_inv = certified_upper_inverse(&b, rank_tolerance);
        let z_gauss_newton = b_inv.as_ref().map(|b_inv| {
            let mut z = [0.0; N];
            for (zi, row) in z.iter_mut().zip(b_inv.iter()) {
                *zi = -row.iter().zip(lin.qtf.iter()).map(|(a, q)| a * q).sum::<f64>();
            }
            z
        });
        let spectral = match z_gauss_newton {
            Some(_) => None,
            None => Some(Spectral::of(&b, &lin.qtf, rank_tolerance)?),
        };
        let rank = spectral.as_ref().map_or(N, |sp| sp.rank);
        Ok(Scaled { b, b_inv, z_gauss_newton, spectral, rank })
    }

    /// The scaled step z = D p and its damping mu for the trust radius `delta`: the
    /// Gauss-Newton step when it fits, else Moré's damped step from the SVD.
    fn step(&mut self, qtf: &[f64; N], delta: f64, rank_tolerance: f64) -> Result<(f64, [f64; N])> {
        if let Some(z) = self.z_gauss_newton {
            if norm(&z) <= 1.1 * delta {
                return Ok((0.0, z));
            }
        }
        let sp = match self.spectral.take() {
            Some(sp) => sp,
            None => Spectral::of(&self.b, qtf, rank_tolerance)?,
        };
        let mu = secular_mu(&sp.svd, &sp.c, &sp.keep, delta);
        let z = scaled_step(&sp.svd, &sp.c, &sp.keep, mu);
        self.spectral = Some(sp);
        Ok((mu, z))
    }

    /// (J^T J)^+ sigma2 from whichever factorisation is at hand.
    fn covariance(&self, qtf: &[f64; N], diag: &[f64; N], sigma2: f64, rank_tolerance: f64) -> Result<[[f64; N]; N]> {
        Ok(match (&self.spectral, &self.b_inv) {
            (Some(sp), _) => covariance_from_svd(&sp.svd, &sp.keep, diag, sigma2),
            (None, Some(b_inv)) => covariance_from_inverse(b_inv, diag, sigma2),
            (None, None) => {
                let sp = Spectral::of(&self.b, qtf, rank_tolerance)?;
                covariance_from_svd(&sp.svd, &sp.keep, diag, sigma2)
            }
        })
    }
}

/// The iterate and the solver's running state.
struct State<const N: usize> {
    x: [f64; N],
    /// MINPACK's scaling D (the largest column norms seen).
    diag: [f64; N],
    /// Trust radius in the scaled variables (0 before the first iteration).
    delta: f64,
    evaluations: usize,
    iterations: usize,
}

impl<const N: usize> State<N> {
    /// Updates D from the column norms of R (returned) and sets the first trust radius;
    /// returns the column norms and ||D x||.
    fn rescale(&mut self, r: &[[f64; N]; N], step_factor: f64) -> ([f64; N], f64) {
        let mut colnorm = [0.0; N];
        for j in 0..N {
            colnorm[j] = libm::sqrt((0..N).map(|i| r[i][j] * r[i][j]).sum::<f64>());
        }
        for j in 0..N {
            let c = if colnorm[j] > 0.0 { colnorm[j] } else { 1.0 };
            self.diag[j] = if self.iterations == 0 && self.delta == 0.0 { c } else { self.diag[j].max(colnorm[j]) };
        }
        let xnorm = norm(&core::array::from_fn::<f64, N, _>(|j| self.diag[j] * self.x[j]));
        if self.delta == 0.0 {
            self.delta = if xnorm > 0.0 { step_factor * xnorm } else { step_factor };
        }
        (colnorm, xnorm)
    }
}

/// The largest cosine between r and a column of J: max_j |(J^T r)_j| / (||J e_j|| ||r||).
fn gradient_cosine<const N: usize>(lin: &Linearization<N>, colnorm: &[f64; N]) -> f64 {
    let mut gnorm = 0.0f64;
    for j in 0..N {
        if colnorm[j] > 0.0 {
            let g: f64 = (0..N).map(|i| lin.r[i][j] * lin.qtf[i]).sum();
            gnorm = gnorm.max(g.abs() / (colnorm[j] * libm::sqrt(lin.cost)));
        }
    }
    gnorm
}

/// ||Q^T r||^2 - ||R p + Q^T r||^2: the reduction of the cost the linear model predicts.
fn predicted_reduction<const N: usize>(lin: &Linearization<N>, p: &[f64; N]) -> f64 {
    let qtf2: f64 = lin.qtf.iter().map(|q| q * q).sum();
    let mut model = 0.0;
    for (i, (ri, qi)) in lin.r.iter().zip(lin.qtf.iter()).enumerate() {
        // R is upper triangular: row i starts at column i.
        let rp: f64 = ri.iter().zip(p.iter()).skip(i).map(|(a, b)| a * b).sum();
        model += (rp + qi) * (rp + qi);
    }
    qtf2 - model
}

/// How the inner loop of one iteration ended.
enum Inner {
    /// A step was accepted (the state holds the new x); a stop may be pending.
    Accepted(Option<StopReason>),
    /// The solver stops at the current x.
    Stopped(StopReason),
}

/// The inner loop: shrink the trust region until a step is accepted (Moré's update of
/// Delta from the gain ratio actual / predicted reduction) or a stop test fires.
fn inner_loop<const N: usize, P: Problem<N>>(
    problem: &mut P,
    state: &mut State<N>,
    lin: &Linearization<N>,
    scaled: &mut Scaled<N>,
    xnorm: f64,
    options: &Options,
) -> Result<Inner> {
    let f = lin.cost;
    loop {
        let (mu, z) = scaled.step(&lin.qtf, state.delta, options.rank_tolerance)?;
        let pnorm = norm(&z);
        if state.iterations == 0 && state.evaluations == 1 {
            state.delta = state.delta.min(pnorm);
        }
        let p: [f64; N] = core::array::from_fn(|j| z[j] / state.diag[j]);
        let xnew: [f64; N] = core::array::from_fn(|j| state.x[j] + p[j]);
        state.evaluations += 1;
        let fnew = trial_cost(problem, &xnew, lin.rows);
        let pred = predicted_reduction(lin, &p);
        let actred = match fnew {
            Some(fnew) => f - fnew,
            None => -f,
        };
        let ratio = if pred > 0.0 { actred / pred } else { 0.0 };
        if ratio <= 0.25 {
            let shrink = if actred >= 0.0 && fnew.is_some() { 0.5 } else { 0.1 };
            state.delta = shrink * state.delta.min(pnorm / 0.1);
        } else if mu == 0.0 || ratio >= 0.75 {
            state.delta = pnorm / 0.5;
        }
        let accepted = ratio >= 1e-4 && fnew.is_some();
        let (rel_act, rel_pred) = (actred / f, pred / f);
        let trial = TrialOutcome {
            cost_converged: rel_act.abs() <= options.ftol && rel_pred <= options.ftol && ratio <= 2.0,
            step_converged: state.delta <= options.xtol * xnorm,
            stalled: state.delta <= f64::EPSILON * xnorm || rel_pred <= f64::EPSILON,
            accepted,
        };
        if accepted {
            state.x = xnew;
            state.iterations += 1;
        }
        let stop = stop_reason(&trial, state.evaluations, state.iterations, options);
        if accepted {
            return Ok(Inner::Accepted(stop));
        }
        if let Some(s) = stop {
            return Ok(Inner::Stopped(s));
        }
    }
}

/// The report at the current iterate; a minimum where some direction is undetermined is
/// reported as [`StopReason::RankDeficient`].
fn finish<const N: usize>(
    state: &State<N>,
    lin: &Linearization<N>,
    scaled: &Scaled<N>,
    stop: StopReason,
    initial_cost: f64,
    options: &Options,
) -> Result<Report<N>> {
    let rank = scaled.rank;
    let dof = lin.rows.saturating_sub(rank);
    let sigma2 = if dof > 0 { lin.cost / dof as f64 } else { lin.cost };
    let stop = if rank < N && stop.converged() { StopReason::RankDeficient } else { stop };
    let covariance = scaled.covariance(&lin.qtf, &state.diag, sigma2, options.rank_tolerance)?;
    Ok(Report {
        x: state.x,
        stop,
        cost: lin.cost,
        initial_cost,
        iterations: state.iterations,
        evaluations: state.evaluations,
        residuals: lin.rows,
        rank,
        sigma2,
        covariance,
    })
}

/// Minimises sum_i r_i(x)^2 from `x0` (see the module documentation for the method).
///
/// Errors: a non-finite start ([`Error::NotFinite`]); the problem's own error or
/// non-finite residuals at the start; no residuals ([`Error::TooFew`]). Everything after
/// the start is reported through [`Report::stop`], never as an error: a rank-deficient
/// Jacobian stops with [`StopReason::RankDeficient`].
///
/// Stack: about 6 N^2 + O(N) numbers.
pub fn solve<const N: usize, P: Problem<N>>(problem: &mut P, x0: [f64; N], options: &Options) -> Result<Report<N>> {
    all_finite(&x0, "starting point")?;
    if N == 0 {
        return Err(Error::InvalidArgument { what: "a problem needs at least one parameter" });
    }
    let mut state = State { x: x0, diag: [0.0; N], delta: 0.0, evaluations: 1, iterations: 0 };
    let mut lin = linearize(problem, &state.x, options.accumulation)?;
    let initial_cost = lin.cost;
    let mut pending: Option<StopReason> = None;
    loop {
        let (colnorm, xnorm) = state.rescale(&lin.r, options.step_factor);
        let mut scaled = Scaled::of(&lin, &state.diag, options.rank_tolerance)?;
        if let Some(stop) = pending {
            return finish(&state, &lin, &scaled, stop, initial_cost, options);
        }
        if lin.cost == 0.0 {
            return finish(&state, &lin, &scaled, StopReason::CostTolerance, initial_cost, options);
        }
        if gradient_cosine(&lin, &colnorm) <= options.gtol {
            return finish(&state, &lin, &scaled, StopReason::GradientTolerance, initial_cost, options);
        }
        match inner_loop(problem, &mut state, &lin, &mut scaled, xnorm, options)? {
            Inner::Accepted(stop) => pending = stop,
            Inner::Stopped(stop) => return finish(&state, &lin, &scaled, stop, initial_cost, options),
        }
        lin = linearize(problem, &state.x, options.accumulation)?;
        state.evaluations += 1;
    }
}
