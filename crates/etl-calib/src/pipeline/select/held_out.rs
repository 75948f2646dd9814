//! A view held out: predicted by a candidate fitted to the other views, the error of the
//! prediction in the estimator's noise model, and how noisy a comparison of two
//! candidates' errors is.
//!
//! **The error** of a residual r (observed - predicted pixels of the view's scored
//! points) is sigma_px^2 r^T S^-1 r, px^2, with S = sigma_px^2 I + J_s Q J_s^T its covariance
//! under the estimator's noise model: J_s = d pixels / d (Z_W, E) and, with
//! errors-in-variables, Q = diag(sigma_z^2, sigma_e^2) the priors on the view's recorded
//! stage position and current (errors no model can predict); with the paper's estimator
//! Q = 0 and the error is |r|^2. By Woodbury, sigma_px^2 r^T S^-1 r = min over d = (dZ, dE)
//! of |r + J_s d|^2 + sigma_px^2 d^T Q^-1 d = |r|^2 - (J_s^T r)^T A^-1 (J_s^T r), with
//! A = J_s^T J_s + sigma_px^2 Q^-1 (2 x 2), linearised at the recorded values.
//!
//! **The noise of a comparison.** Let b's residual be r and m's be r + delta (delta: the
//! difference of their predictions). Then e_m - e_b = sigma_px^2 (delta^T S^-1 delta +
//! 2 delta^T S^-1 r): what is random in it is the cross term, whose variance, r having
//! the predictive covariance V = S + J_p C J_p^T (the view's own noise, and the
//! uncertainty C of b's numbers fitted to the other views, J_p = d pixels / d numbers),
//! is 4 sigma_px^4 y^T V y with y = S^-1 delta. The parameter term matters: a held-out end
//! view is an extrapolation, where the fitted focal polynomial is as uncertain as the
//! view itself (leverage about 2/3 on the paper's 15 currents).

use etl_core::calib::jacobian::Projector;
use etl_core::calib::params::MAX_PARAMS;
use etl_core::calib::{BundleAdjustReport, Estimator, View};
use rayon::prelude::*;

use super::Fitted;
use crate::pipeline::solve::solve_once;

/// The noise a held-out residual is judged by: pixel noise, and with errors-in-variables
/// the prior spreads (sigma_z mm, sigma_e mA) of a view's recorded stage position and
/// current (`None` with the paper's estimator: recorded values exact).
#[derive(Debug, Clone, Copy)]
struct Noise {
    sigma_px: f64,
    priors: Option<(f64, f64)>,
}

/// One view predicted by one candidate fitted to the other views, per scored point.
pub(super) struct HeldOut {
    /// Observed - predicted pixel (infinite where the projection failed).
    residuals: Vec<[f64; 2]>,
    /// d pixel / d (Z_W, E): rows u, v.
    shifts: Vec<[[f64; 2]; 2]>,
    /// d pixel / d numbers (the layout's, zero past its length): rows u, v.
    d_params: Vec<[[f64; MAX_PARAMS]; 2]>,
    /// The covariance of the numbers fitted to the other views.
    covariance: [[f64; MAX_PARAMS]; MAX_PARAMS],
    noise: Noise,
}

impl HeldOut {
    /// View `view` predicted by the fit `fold` (to the other views), over its `scored`
    /// points.
    fn predict(fold: &BundleAdjustReport, view: &View<'_>, scored: &[bool], noise: Noise) -> Self {
        let projector = Projector::new(&fold.model);
        let n = scored.iter().filter(|&&k| k).count();
        let mut out = HeldOut {
            residuals: Vec::with_capacity(n),
            shifts: Vec::with_capacity(n),
            d_params: Vec::with_capacity(n),
            covariance: fold.covariance,
            noise,
        };
        for (p, _) in view.points.iter().zip(scored).filter(|&(_, &k)| k) {
            let (r, s, d) = match projector.project(p.world_mm, view.e_com_ma, true) {
                Ok(q) => (
                    [p.pixel[0] - q.pixel[0], p.pixel[1] - q.pixel[1]],
                    [[q.d_z_w[0], q.d_e[0]], [q.d_z_w[1], q.d_e[1]]],
                    q.d_params,
                ),
                Err(_) => ([f64::INFINITY; 2], [[0.0; 2]; 2], [[0.0; MAX_PARAMS]; 2]),
            };
            out.residuals.push(r);
            out.shifts.push(s);
            out.d_params.push(d);
        }
        out
    }

    /// The view's held-out error, px^2, and its number of points (module docs).
    pub(super) fn error(&self) -> (f64, usize) {
        let r = &self.residuals;
        let rr: f64 = r.iter().map(|x| x[0] * x[0] + x[1] * x[1]).sum();
        if !rr.is_finite() {
            return (rr, r.len());
        }
        let (jtr, x) = self.profile(r);
        ((rr - jtr[0] * x[0] - jtr[1] * x[1]).max(0.0), r.len())
    }

    /// The variance of (`other`'s error - this error), this being the reference whose
    /// residual carries the noise, px^4 (module docs).
    pub(super) fn difference_variance(&self, other: &HeldOut) -> f64 {
        let delta: Vec<[f64; 2]> =
            other.residuals.iter().zip(&self.residuals).map(|(m, b)| [m[0] - b[0], m[1] - b[1]]).collect();
        let s2 = self.noise.sigma_px * self.noise.sigma_px;
        let (_, x) = self.profile(&delta);
        // y = S^-1 delta = (delta - J_s x) / s2; y^T V y = s2 |y|^2 + y^T J_s Q J_s^T y
        // + g^T C g (g = J_p^T y), and s2 |y|^2 + y^T J_s Q J_s^T y = y^T S y = delta^T y.
        let mut delta_y = 0.0;
        let mut g = [0.0; MAX_PARAMS];
        for ((d, j), dp) in delta.iter().zip(&self.shifts).zip(&self.d_params) {
            for row in 0..2 {
                let y = (d[row] - j[row][0] * x[0] - j[row][1] * x[1]) / s2;
                delta_y += d[row] * y;
                g.iter_mut().zip(&dp[row]).for_each(|(gk, &dk)| *gk += dk * y);
            }
        }
        let gcg: f64 = g.iter().zip(&self.covariance).map(|(ga, row)| ga * dot(row, &g)).sum();
        let variance = 4.0 * s2 * s2 * (delta_y + gcg.max(0.0));
        if variance.is_finite() {
            variance
        } else {
            f64::INFINITY
        }
    }

    /// J_s^T v and A^-1 J_s^T v (module docs; A's second term only with priors): the
    /// stage and current shift that best explain `v` under the priors.
    fn profile(&self, v: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
        let (mut jtj, mut jtv) = ([[0.0; 2]; 2], [0.0; 2]);
        for (v, j) in v.iter().zip(&self.shifts) {
            for row in 0..2 {
                for a in 0..2 {
                    jtv[a] += j[row][a] * v[row];
                    for b in 0..2 {
                        jtj[a][b] += j[row][a] * j[row][b];
                    }
                }
            }
        }
        let Noise { sigma_px, priors: Some((sigma_z_mm, sigma_e_ma)) } = self.noise else {
            return (jtv, [0.0; 2]);
        };
        let s2 = sigma_px * sigma_px;
        let a = [
            [jtj[0][0] + s2 / (sigma_z_mm * sigma_z_mm), jtj[0][1]],
            [jtj[1][0], jtj[1][1] + s2 / (sigma_e_ma * sigma_e_ma)],
        ];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if !(det > 0.0 && s2 > 0.0) {
            return (jtv, [0.0; 2]);
        }
        (jtv, [(a[1][1] * jtv[0] - a[0][1] * jtv[1]) / det, (a[0][0] * jtv[1] - a[1][0] * jtv[0]) / det])
    }
}

fn dot(a: &[f64; MAX_PARAMS], b: &[f64; MAX_PARAMS]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Each view held out in turn and predicted by the candidate `fit` refitted to the
/// others (from its fit to all views, its outliers set aside), over the `scored` points.
pub(super) fn cross_validate(
    views: &[View<'_>],
    fit: &Fitted,
    scored: &[Vec<bool>],
) -> std::result::Result<Vec<HeldOut>, String> {
    let mut ba = fit.options.bundle_adjust().map_err(|e| e.to_string())?;
    // The pixel noise is the data's, not the fold's: the full fit's estimate, held (it
    // spares the folds the errors-in-variables rounds that re-estimate it).
    if let Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: None } = ba.estimator {
        ba.estimator = Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: Some(fit.solved.report.sigma_px) };
    }
    let priors = match ba.estimator {
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, .. } => Some((sigma_z_mm, sigma_e_ma)),
        _ => None,
    };
    (0..views.len())
        .into_par_iter()
        .map(|j| {
            let rest: Vec<View<'_>> = views.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, v)| *v).collect();
            let used: Vec<Vec<bool>> =
                fit.solved.used.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, u)| u.clone()).collect();
            let (fold, _) = solve_once(&rest, &used, &fit.solved.report.model, &ba)
                .map_err(|e| format!("with view {j} held out: {e}"))?;
            Ok(HeldOut::predict(&fold, &views[j], &scored[j], Noise { sigma_px: fold.sigma_px, priors }))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    const S_PX: f64 = 0.3;
    const PRIORS: (f64, f64) = (0.01, 0.4);
    /// Three points, the numbers' covariance diagonal (its square roots `C_STD`).
    const C_STD: [f64; 3] = [0.05, 0.02, 0.1];

    fn view(residuals: Vec<[f64; 2]>, priors: Option<(f64, f64)>) -> HeldOut {
        let shifts = vec![[[1.5, 3.0], [-0.5, 2.0]], [[0.7, -1.0], [2.5, 0.5]], [[-1.2, 0.3], [0.4, -2.2]]];
        let mut d_params = vec![[[0.0; MAX_PARAMS]; 2]; 3];
        for (i, d) in d_params.iter_mut().enumerate() {
            for k in 0..3 {
                d[0][k] = 1.0 + (i + k) as f64;
                d[1][k] = (i as f64 - k as f64) * 0.7;
            }
        }
        let mut covariance = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        (0..3).for_each(|k| covariance[k][k] = C_STD[k] * C_STD[k]);
        HeldOut { residuals, shifts, d_params, covariance, noise: Noise { sigma_px: S_PX, priors } }
    }

    /// x solving a x = b by Gaussian elimination with partial pivoting (a small, dense,
    /// well-conditioned test system).
    fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for c in 0..n {
            let p = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap();
            a.swap(c, p);
            b.swap(c, p);
            for r in c + 1..n {
                let f = a[r][c] / a[c][c];
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
        let mut x = vec![0.0; n];
        for r in (0..n).rev() {
            x[r] = (b[r] - (r + 1..n).map(|k| a[r][k] * x[k]).sum::<f64>()) / a[r][r];
        }
        x
    }

    #[test]
    fn the_error_is_the_residual_judged_by_its_covariance() {
        let r = vec![[0.4, -0.2], [0.1, 0.5], [-0.3, 0.25]];
        let h = view(r.clone(), Some(PRIORS));
        // S = s^2 I + J_s Q J_s^T, dense, rows (point, axis).
        let rows: Vec<[f64; 2]> = h.shifts.iter().flat_map(|s| [s[0], s[1]]).collect();
        let q = [PRIORS.0 * PRIORS.0, PRIORS.1 * PRIORS.1];
        let s: Vec<Vec<f64>> = (0..6)
            .map(|i| {
                (0..6)
                    .map(|j| {
                        rows[i][0] * q[0] * rows[j][0]
                            + rows[i][1] * q[1] * rows[j][1]
                            + if i == j { S_PX * S_PX } else { 0.0 }
                    })
                    .collect()
            })
            .collect();
        let flat: Vec<f64> = r.iter().flat_map(|x| *x).collect();
        let y = solve(s, flat.clone());
        let want = S_PX * S_PX * flat.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
        let (got, n) = h.error();
        assert_eq!(n, 3);
        assert!((got - want).abs() < 1e-12 * want, "{got} {want}");
        // Without priors (the paper's estimator): the plain sum of squares.
        let plain = view(r, None).error().0;
        assert!((plain - flat.iter().map(|x| x * x).sum::<f64>()).abs() < 1e-15);
        assert!(got < plain, "the stage and current explain part of the residual");
    }

    /// Ground truth by simulation: residuals drawn from the predictive covariance
    /// V = s^2 I + J_s Q J_s^T + J_p C J_p^T; the variance of (error of r + delta) - (error
    /// of r) over the draws against `difference_variance`.
    #[test]
    fn the_difference_variance_is_that_of_simulated_residuals() {
        let delta = [[0.3, -0.1], [0.05, 0.2], [-0.15, 0.1]];
        for priors in [Some(PRIORS), None] {
            let b = view(vec![[0.0; 2]; 3], priors);
            let m = view(delta.to_vec(), priors);
            let want = b.difference_variance(&m);
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
            let draws = 40_000;
            let diffs: Vec<f64> = (0..draws)
                .map(|_| {
                    let (zs, zp) = ([g() * PRIORS.0, g() * PRIORS.1], [g() * C_STD[0], g() * C_STD[1], g() * C_STD[2]]);
                    let r: Vec<[f64; 2]> = (0..3)
                        .map(|i| {
                            core::array::from_fn(|a| {
                                let shift = if priors.is_some() {
                                    b.shifts[i][a][0] * zs[0] + b.shifts[i][a][1] * zs[1]
                                } else {
                                    0.0
                                };
                                let params: f64 = (0..3).map(|k| b.d_params[i][a][k] * zp[k]).sum();
                                g() * S_PX + shift + params
                            })
                        })
                        .collect();
                    let rm: Vec<[f64; 2]> = r.iter().zip(&delta).map(|(x, d)| [x[0] + d[0], x[1] + d[1]]).collect();
                    view(rm, priors).error().0 - view(r, priors).error().0
                })
                .collect();
            let mean = diffs.iter().sum::<f64>() / draws as f64;
            let var = diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (draws - 1) as f64;
            // The sample variance of 40 000 near-Gaussian draws is within 3 % (4 sigma).
            assert!((var / want - 1.0).abs() < 0.03, "{priors:?}: simulated {var}, predicted {want}");
            // The mean is the non-random part, delta's own error.
            let own = view(delta.to_vec(), priors).error().0;
            assert!((mean - own).abs() < 4.0 * (want / draws as f64).sqrt(), "{mean} {own}");
        }
    }
}
