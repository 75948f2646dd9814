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

#![allow(clippy::needless_range_loop)] // small fixed-size linear algebra reads best indexed

use super::options::{Accumulation, Options, StopReason};
use super::report::Report;
use super::svd::Svd;
use super::{NormalEquations, Problem, RowSink};
use crate::error::{all_finite, Error, Result};
use crate::fit::GivensQr;

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
            let (r, qtf) = cholesky_factor(&sink.a, &sink.g);
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

/// R with R^T R = A (A = J^T J, upper triangle given) and Q^T r = R^-T J^T r, by a
/// Cholesky factorisation of the diagonally scaled A (unit diagonal), semidefinite: a pivot
/// below 1e-14 of its scaled diagonal ends its row at zero (that direction then carries no
/// information; the SVD of the step finds the rank).
fn cholesky_factor<const N: usize>(a: &[[f64; N]; N], g: &[f64; N]) -> ([[f64; N]; N], [f64; N]) {
    let d: [f64; N] = core::array::from_fn(|i| {
        let v = a[i][i];
        if v > 0.0 {
            libm::sqrt(v)
        } else {
            1.0
        }
    });
    let mut r = [[0.0; N]; N];
    for i in 0..N {
        let mut diag = a[i][i] / (d[i] * d[i]);
        for k in 0..i {
            diag -= r[k][i] * r[k][i];
        }
        if !(diag > 1e-14) {
            continue; // row i stays zero
        }
        let rii = libm::sqrt(diag);
        r[i][i] = rii;
        for j in (i + 1)..N {
            let mut v = a[i][j] / (d[i] * d[j]);
            for k in 0..i {
                v -= r[k][i] * r[k][j];
            }
            r[i][j] = v / rii;
        }
    }
    // Unscale: R_scaled = R D^-1 column-wise, so R = R_scaled D.
    let mut qtf = [0.0; N];
    for i in 0..N {
        let mut v = g[i] / d[i];
        for k in 0..i {
            v -= r[k][i] * qtf[k];
        }
        qtf[i] = if r[i][i] > 0.0 { v / r[i][i] } else { 0.0 };
    }
    for row in r.iter_mut() {
        for (rij, dj) in row.iter_mut().zip(d.iter()) {
            *rij *= dj;
        }
    }
    (r, qtf)
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

/// The inverse of the upper triangular `b` when it is certified to have full numerical
/// rank: s_min(B) >= 1 / ||B^-1||_F and s_max(B) <= ||B||_F, so
/// 1 / ||B^-1||_F > 100 `rank_tolerance` ||B||_F guarantees that every singular value
/// clears the rank threshold (the factor 100 leaves room for rounding). `None` otherwise
/// (the caller then decides the rank by the SVD).
fn full_rank_inverse<const N: usize>(b: &[[f64; N]; N], rank_tolerance: f64) -> Option<[[f64; N]; N]> {
    let mut inv = [[0.0; N]; N];
    // Column j of B^-1 by back substitution of B x = e_j (x_i = 0 for i > j).
    for j in 0..N {
        for i in (0..=j).rev() {
            let row = b.get(i)?;
            let bii = *row.get(i)?;
            if !(bii.abs() > 0.0) {
                return None;
            }
            let rhs = if i == j { 1.0 } else { 0.0 };
            let s: f64 = row
                .iter()
                .zip(inv.iter())
                .take(j + 1)
                .skip(i + 1)
                .map(|(bik, ik)| bik * ik.get(j).unwrap_or(&0.0))
                .sum();
            *inv.get_mut(i)?.get_mut(j)? = (rhs - s) / bii;
        }
    }
    let frob = |m: &[[f64; N]; N]| libm::sqrt(m.iter().flatten().map(|v| v * v).sum::<f64>());
    let (nb, ninv) = (frob(b), frob(&inv));
    (ninv.is_finite() && nb.is_finite() && 100.0 * rank_tolerance * nb * ninv < 1.0).then_some(inv)
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
    let mut x = x0;
    let mut lin = linearize(problem, &x, options.accumulation)?;
    let initial_cost = lin.cost;
    let rows = lin.rows;
    let mut evaluations = 1usize;
    let mut iterations = 0usize;
    let mut diag = [0.0; N];
    let mut delta = 0.0;
    let mut pending: Option<StopReason> = None;
    loop {
        let r = lin.r;
        let qtf = lin.qtf;
        let f = lin.cost;
        let mut colnorm = [0.0; N];
        for j in 0..N {
            colnorm[j] = libm::sqrt((0..N).map(|i| r[i][j] * r[i][j]).sum::<f64>());
        }
        for j in 0..N {
            let c = if colnorm[j] > 0.0 { colnorm[j] } else { 1.0 };
            diag[j] = if iterations == 0 && delta == 0.0 { c } else { diag[j].max(colnorm[j]) };
        }
        let xnorm = norm(&core::array::from_fn::<f64, N, _>(|j| diag[j] * x[j]));
        if delta == 0.0 {
            delta = if xnorm > 0.0 { options.step_factor * xnorm } else { options.step_factor };
        }
        // B = R D^-1 (upper triangular). Its SVD gives the rank and the damped steps; when
        // B is certified well inside full rank, the Gauss-Newton step comes from a
        // triangular solve and the SVD is computed only if the trust region binds (or for
        // the covariance at the end): the usual case near a solution.
        let mut b = [[0.0; N]; N];
        for (bi, ri) in b.iter_mut().zip(r.iter()) {
            for ((bij, rij), dj) in bi.iter_mut().zip(ri.iter()).zip(diag.iter()) {
                *bij = rij / dj;
            }
        }
        let b_inv = full_rank_inverse(&b, options.rank_tolerance);
        let z_gauss_newton = b_inv.as_ref().map(|b_inv| {
            let mut z = [0.0; N];
            for (zi, row) in z.iter_mut().zip(b_inv.iter()) {
                *zi = -row.iter().zip(qtf.iter()).map(|(a, q)| a * q).sum::<f64>();
            }
            z
        });
        let mut spectral: Option<Spectral<N>> = None;
        if z_gauss_newton.is_none() {
            spectral = Some(Spectral::of(&b, &qtf, options.rank_tolerance)?);
        }
        let rank = spectral.as_ref().map_or(N, |sp| sp.rank);
        let dof = rows.saturating_sub(rank);
        let sigma2 = if dof > 0 { f / dof as f64 } else { f };
        macro_rules! finish {
            ($stop:expr) => {{
                // A minimum where some direction is undetermined is reported as such.
                let stop = if rank < N && $stop.converged() { StopReason::RankDeficient } else { $stop };
                let covariance = match (&spectral, &b_inv) {
                    (Some(sp), _) => covariance_from_svd(&sp.svd, &sp.keep, &diag, sigma2),
                    (None, Some(b_inv)) => covariance_from_inverse(b_inv, &diag, sigma2),
                    (None, None) => {
                        let sp = Spectral::of(&b, &qtf, options.rank_tolerance)?;
                        covariance_from_svd(&sp.svd, &sp.keep, &diag, sigma2)
                    }
                };
                return Ok(Report {
                    x,
                    stop,
                    cost: f,
                    initial_cost,
                    iterations,
                    evaluations,
                    residuals: rows,
                    rank,
                    sigma2,
                    covariance,
                });
            }};
        }
        if let Some(stop) = pending {
            finish!(stop);
        }
        if f == 0.0 {
            finish!(StopReason::CostTolerance);
        }
        // Gradient test: the largest cosine between r and a column of J.
        let mut gnorm = 0.0f64;
        for j in 0..N {
            if colnorm[j] > 0.0 {
                let g: f64 = (0..N).map(|i| r[i][j] * qtf[i]).sum();
                gnorm = gnorm.max(g.abs() / (colnorm[j] * libm::sqrt(f)));
            }
        }
        if gnorm <= options.gtol {
            finish!(StopReason::GradientTolerance);
        }
        let qtf2: f64 = qtf.iter().map(|q| q * q).sum();
        // Inner loop: shrink the trust region until a step is accepted.
        loop {
            let (mu, z) = match z_gauss_newton {
                Some(z) if norm(&z) <= 1.1 * delta => (0.0, z),
                _ => {
                    let sp = match spectral.take() {
                        Some(sp) => sp,
                        None => Spectral::of(&b, &qtf, options.rank_tolerance)?,
                    };
                    let mu = secular_mu(&sp.svd, &sp.c, &sp.keep, delta);
                    let z = scaled_step(&sp.svd, &sp.c, &sp.keep, mu);
                    spectral = Some(sp);
                    (mu, z)
                }
            };
            let pnorm = norm(&z);
            if iterations == 0 && evaluations == 1 {
                delta = delta.min(pnorm);
            }
            let p: [f64; N] = core::array::from_fn(|j| z[j] / diag[j]);
            let xnew: [f64; N] = core::array::from_fn(|j| x[j] + p[j]);
            evaluations += 1;
            let fnew = trial_cost(problem, &xnew, rows);
            // Predicted reduction of the linear model: ||Q^T r||^2 - ||R p + Q^T r||^2.
            let mut model = 0.0;
            for (i, (ri, qi)) in r.iter().zip(qtf.iter()).enumerate() {
                // R is upper triangular: row i starts at column i.
                let rp: f64 = ri.iter().zip(p.iter()).skip(i).map(|(a, b)| a * b).sum();
                model += (rp + qi) * (rp + qi);
            }
            let pred = qtf2 - model;
            let actred = match fnew {
                Some(fnew) => f - fnew,
                None => -f,
            };
            let ratio = if pred > 0.0 { actred / pred } else { 0.0 };
            if ratio <= 0.25 {
                let shrink = if actred >= 0.0 && fnew.is_some() { 0.5 } else { 0.1 };
                delta = shrink * delta.min(pnorm / 0.1);
            } else if mu == 0.0 || ratio >= 0.75 {
                delta = pnorm / 0.5;
            }
            let accepted = ratio >= 1e-4 && fnew.is_some();
            let mut stop = None;
            let rel_act = actred / f;
            let rel_pred = pred / f;
            if rel_act.abs() <= options.ftol && rel_pred <= options.ftol && ratio <= 2.0 {
                stop = Some(StopReason::CostTolerance);
            } else if delta <= options.xtol * xnorm {
                stop = Some(StopReason::StepTolerance);
            } else if evaluations >= options.max_evaluations {
                stop = Some(StopReason::MaxIterations);
            } else if !accepted && (delta <= f64::EPSILON * xnorm || rel_pred <= f64::EPSILON) {
                stop = Some(StopReason::NoProgress);
            }
            if accepted {
                x = xnew;
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
        }
        lin = linearize(problem, &x, options.accumulation)?;
        evaluations += 1;
    }
}
