//! Bundle adjustment (Eq. 24) of the model's numbers (the paper's 25, or any layout:
//! [`super::params::Layout`]), and the errors-in-variables estimator.
//!
//! **Paper** (default): minimise sum over all points of |observed - projected|^2 over
//! R (Rodrigues), T, kf_x, kf_y, (u0, v0), the a_i, treating each view's recorded stage
//! position Z_W and current E as exact. Solved by the dense LM of [`crate::lm::solve`]
//! (MINPACK column scaling makes the 12 orders of magnitude between the raw parameters
//! harmless: the step is computed in scaled variables). Its covariance accounts for the
//! errors of the recorded positions and currents it takes as exact
//! ([`BundleAdjustOptions::input_noise`], [`input_noise`]): the pixel noise alone made its
//! standard deviations 5-6.6 times too small.
//!
//! **Errors-in-variables** (beyond the paper): maximum likelihood under the full noise
//! model of docs/METHOD.md. Each view j gets a correction dZ_j of its stage position and dE_j of
//! its current, with Gaussian priors (10 um and 0.4 mA by default). Residuals are
//! normalised by their standard deviations:
//!
//! ```text
//! sum_j [ sum_i |obs_ij - proj(P_ij + dZ_j e_z, E_j + dE_j)|^2 / sigma_px^2
//!         + dZ_j^2 / sigma_Z^2 + dE_j^2 / sigma_E^2 ]
//! ```
//!
//! The per-view unknowns couple only to the shared numbers, so they are eliminated by
//! the Schur complement ([`crate::lm::solve_blocks`], storage from the caller). sigma_px,
//! unless given, is estimated: it starts at the residual standard deviation of the plain
//! solution (which the uncorrected stage and current errors inflate) and is re-estimated
//! from the errors-in-variables residuals, sum |e|^2 / (2 n - p) (p numbers), the solve repeated
//! until it moves by less than 0.1 % (at most 4 solves; not with a robust loss, whose
//! weights would need their own scale). The reported covariance is that of the shared
//! numbers with the corrections marginalised out, (U - sum_j W_j V_j^-1 W_j^T)^-1 of the
//! normalised rows, not rescaled by the residual variance: the priors are given, not
//! estimated (rescaling made the one-sigma intervals of kf cover the truth 56-62 % of the
//! time instead of 68 %, tests/uncertainty.rs of etl-calib).
//!
//! **Held numbers** ([`BundleAdjustOptions::hold`], a [`ParamMask`]): each is held at its
//! start value by a prior row of weight 1e8 per unit of its magnitude (relative change
//! ~1e-8 px-equivalents): its reported standard deviation is then ~0. Hold-A0 (kf0x, kf0y,
//! u0, v0: [`super::params::Layout::a0_mask`]) and OpenCV's flags (k3, p1, p2 held at the
//! zero the initialisation gives them: [`super::params::Layout::opencv_mask`]) are cases.
//!
//! **Robust loss** (Huber or Cauchy with threshold k px): iteratively reweighted least
//! squares. Each point's residual pair gets the weight w = rho'(s), s = |e|^2, evaluated at
//! a fixed reference estimate (the previous IRLS iterate), so every weighted solve has an
//! exact Jacobian; the weights are recomputed from the reference on the fly (no per-point
//! storage) and the loop stops when the estimate no longer moves (at most
//! [`IRLS_MAX_ROUNDS`] rounds).

pub mod free_views;
pub mod input_noise;
mod joint;
mod normal;
mod problems;
mod scratch;

pub use free_views::{FreeView, MIN_FREE_VIEW_POINTS};
pub use input_noise::{covariance_with_input_noise, InputNoise, InputNoiseCovariance};
pub use joint::{bundle_adjust_free_views, bundle_adjust_free_views_scratch};
pub use scratch::{JointScratch, ViewScratch, JOINT_BLOCK};

use self::problems::{projector, Eiv, Plain};
use self::scratch::Prepare;
use super::basis::Basis;
use super::dispatch::with_layout;
use super::jacobian::{from_params, to_params_n};
use super::observations::{distinct_currents, point_count, validate, View};
use super::params::{Layout, ParamMask, MAX_PARAMS};
use crate::error::{Error, Result};
use crate::lm::{self, Accumulation, BlockStorage, Options, StopReason};
use crate::model::CameraModel;

/// Which estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Estimator {
    /// The paper's Eq. 24: recorded stage positions and currents are exact.
    Paper,
    /// Errors-in-variables: per-view corrections with Gaussian priors.
    Eiv {
        /// Prior standard deviation of the stage position, mm (paper: 0.010).
        sigma_z_mm: f64,
        /// Prior standard deviation of the current, mA (paper: 0.4).
        sigma_e_ma: f64,
        /// Pixel noise standard deviation; `None`: estimated by a plain solution first.
        sigma_px: Option<f64>,
    },
}

impl Estimator {
    /// The errors-in-variables estimator with the paper's noise levels.
    pub const EIV_PAPER: Estimator = Estimator::Eiv { sigma_z_mm: 0.010, sigma_e_ma: 0.4, sigma_px: None };
}

/// A robust loss on the reprojection error of a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RobustLoss {
    /// Huber: quadratic up to `k_px`, linear beyond.
    Huber {
        /// Threshold, px.
        k_px: f64,
    },
    /// Cauchy: k^2 ln(1 + s / k^2).
    Cauchy {
        /// Scale, px.
        k_px: f64,
    },
}

impl RobustLoss {
    /// The IRLS weight rho'(s) of a point with squared error s = |e|^2 (px^2).
    fn weight(&self, s: f64) -> f64 {
        match *self {
            RobustLoss::Huber { k_px } => {
                if s <= k_px * k_px {
                    1.0
                } else {
                    k_px / libm::sqrt(s)
                }
            }
            RobustLoss::Cauchy { k_px } => 1.0 / (1.0 + s / (k_px * k_px)),
        }
    }
}

/// Rounds of reweighting of the robust loss.
pub const IRLS_MAX_ROUNDS: usize = 20;

/// Options of [`bundle_adjust`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleAdjustOptions {
    /// The estimator (default: the paper's).
    pub estimator: Estimator,
    /// The numbers held at their start values, as indices into the start model's
    /// parameter vector (default: none, refine all). Hold-A0 is
    /// [`Layout::a0_mask`]; OpenCV's fix-k3 and zero-tangent flags are
    /// [`Layout::opencv_mask`] (with a start whose held a_i are zero, as
    /// [`super::initialise_model`] gives it).
    pub hold: ParamMask,
    /// Robust loss (default: none, least squares).
    pub robust: Option<RobustLoss>,
    /// What the paper estimator's covariance accounts for besides the pixel noise: the
    /// spread of the recorded stage positions and currents (default: the paper's,
    /// [`InputNoise::PAPER`], the errors-in-variables priors' defaults). `None`: the pixel
    /// noise alone, as if the recorded values were exact (an underestimate whenever they
    /// are not). The errors-in-variables estimator models these errors itself, from the
    /// priors of [`Estimator::Eiv`], and does not read this.
    pub input_noise: Option<InputNoise>,
    /// Solver options.
    pub lm: Options,
}

impl Default for BundleAdjustOptions {
    fn default() -> Self {
        BundleAdjustOptions {
            estimator: Estimator::Paper,
            hold: ParamMask::NONE,
            robust: None,
            input_noise: Some(InputNoise::PAPER),
            lm: Options {
                max_iterations: 100,
                ftol: 1e-10,
                xtol: 1e-10,
                gtol: 1e-10,
                accumulation: Accumulation::NormalEquations,
                // The errors-in-variables stage starts from the converged plain solution,
                // where a Gauss-Newton-like step is right: Marquardt's usual 1e-3 holds
                // back the flat directions (stage and current corrections against kf and
                // T) for ~10 extra iterations. Nielsen's update raises it if a step fails.
                initial_damping: 1e-8,
                ..Options::default()
            },
        }
    }
}

/// Per-view result of the errors-in-variables estimator (zeros for the paper's).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ViewCorrection {
    /// Estimated correction of the recorded stage position, mm.
    pub dz_mm: f64,
    /// Estimated correction of the recorded current, mA.
    pub de_ma: f64,
}

/// What [`bundle_adjust`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleAdjustReport {
    /// The refined model (the start's layout).
    pub model: CameraModel,
    /// One standard deviation of each number, in the order of the model's layout
    /// ([`Layout::names`]); zero past its length.
    pub std: [f64; MAX_PARAMS],
    /// Covariance of the numbers (the layout's length square; zero past it).
    pub covariance: [[f64; MAX_PARAMS]; MAX_PARAMS],
    /// RMS reprojection error before, px: sqrt(sum |e|^2 / points).
    pub initial_rms_px: f64,
    /// RMS reprojection error after, px (with the view corrections applied).
    pub rms_px: f64,
    /// LM iterations (of the final estimator).
    pub iterations: usize,
    /// Residual evaluations of the final estimator's LM (linearisations and trial steps;
    /// 2 iterations + 1 when every trial step was accepted).
    pub evaluations: usize,
    /// Why the LM stopped.
    pub stop: StopReason,
    /// Pixel noise standard deviation used (errors-in-variables) or estimated (paper:
    /// with [`BundleAdjustOptions::input_noise`], the residuals' share of the input errors
    /// taken out; without, the plain residual standard deviation).
    pub sigma_px: f64,
}

impl BundleAdjustReport {
    /// The layout of [`Self::model`]'s numbers (that of [`Self::std`] and
    /// [`Self::covariance`]).
    pub fn layout(&self) -> Layout {
        self.model.layout()
    }

    /// The standard deviations, the layout's length of them.
    pub fn std_params(&self) -> &[f64] {
        self.std.get(..self.layout().len()).unwrap_or(&self.std)
    }
}

/// Number of [`ViewScratch`] elements [`bundle_adjust`] needs for `views` views: one per
/// view, whatever the estimator and the layout (each holds the view's correction on
/// return).
pub const fn bundle_adjust_scratch(views: usize) -> usize {
    views
}

/// cov_x = dx/dz cov_z (dx/dz)^T.
fn covariance_in_params<const N: usize>(dxdz: &[[f64; N]; N], cov_z: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut t = [[0.0; N]; N];
    for (ti, di) in t.iter_mut().zip(dxdz.iter()) {
        for (dik, ck) in di.iter().zip(cov_z.iter()) {
            if *dik != 0.0 {
                for (tij, &ckj) in ti.iter_mut().zip(ck.iter()) {
                    *tij += dik * ckj;
                }
            }
        }
    }
    let mut out = [[0.0; N]; N];
    for (oi, ti) in out.iter_mut().zip(t.iter()) {
        for (oij, dj) in oi.iter_mut().zip(dxdz.iter()) {
            *oij = ti.iter().zip(dj.iter()).map(|(a, b)| a * b).sum();
        }
    }
    out
}

/// RMS reprojection error of the parameters `x` of `layout` over the views (with the
/// per-view corrections of `corrections`, if any).
fn rms<const N: usize>(
    views: &[View<'_>],
    layout: &Layout,
    x: &[f64; N],
    corrections: Option<&[ViewScratch]>,
) -> Result<f64> {
    let proj = projector(layout, x);
    let (mut s, mut n) = (0.0, 0usize);
    for (j, view) in views.iter().enumerate() {
        let c = corrections.and_then(|c| c.get(j)).map_or([0.0; 2], |s| s.y());
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + c[0]];
            let pr = proj.project_reduced(w, view.e_com_ma + c[1], false)?;
            s += (pr.pixel[0] - p.pixel[0]) * (pr.pixel[0] - p.pixel[0])
                + (pr.pixel[1] - p.pixel[1]) * (pr.pixel[1] - p.pixel[1]);
            n += 1;
        }
    }
    Ok(if n > 0 { libm::sqrt(s / n as f64) } else { 0.0 })
}

/// The preconditions of [`bundle_adjust`] on its input and storage.
fn check_input(
    views: &[View<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &[ViewScratch],
) -> Result<()> {
    validate(views)?;
    init.validate()?;
    let nc = distinct_currents(views);
    if nc < 3 {
        return Err(Error::TooFew { what: "distinct currents (Appendix I)", needed: 3, got: nc });
    }
    let params = init.layout().len();
    let n = point_count(views);
    if 2 * n < params + 1 {
        return Err(Error::TooFew { what: "points for bundle adjustment", needed: params / 2 + 1, got: n });
    }
    if !options.hold.fits(params) {
        return Err(Error::InvalidArgument { what: "hold mask names a number past the model's layout" });
    }
    let needed = bundle_adjust_scratch(views.len());
    if scratch.len() < needed {
        return Err(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: scratch.len() });
    }
    Ok(())
}

/// The paper's estimator from x0, with the IRLS rounds of a robust loss: reweight around
/// the latest estimate until it stops moving.
fn solve_plain<const N: usize, const O: usize, const P: usize>(
    views: &[View<'_>],
    x0: [f64; N],
    options: &BundleAdjustOptions,
    basis: &Basis,
) -> Result<lm::Report<N>> {
    let layout = basis.layout();
    let z0 = basis.to_internal(&x0);
    let mut plain = lm::solve(&mut Plain::<N, O, P> { views, x0, options, reference: None, basis }, z0, &options.lm)?;
    if options.robust.is_some() {
        for _ in 0..IRLS_MAX_ROUNDS {
            let reference = Some(projector(&layout, &basis.to_params(&plain.x)));
            let next = lm::solve(&mut Plain::<N, O, P> { views, x0, options, reference, basis }, plain.x, &options.lm)?;
            let moved = next.x.iter().zip(plain.x.iter()).any(|(a, b)| (a - b).abs() > 1e-9 * b.abs().max(1e-12));
            plain = next;
            if !moved {
                break;
            }
        }
    }
    Ok(plain)
}

/// The report of a solve in the internal parameters z: the model, the covariance mapped
/// to the model's numbers, the RMS with the view corrections of `scratch` (if any).
fn report_of<const N: usize>(
    views: &[View<'_>],
    basis: &Basis,
    solved: &lm::Report<N>,
    initial_rms_px: f64,
    sigma_px: f64,
    corrections: Option<&[ViewScratch]>,
) -> Result<BundleAdjustReport> {
    let layout = basis.layout();
    let x = basis.to_params(&solved.x);
    let cov = covariance_in_params(&basis.params_jacobian(&solved.x), &solved.covariance);
    let mut covariance = [[0.0; MAX_PARAMS]; MAX_PARAMS];
    for (out, row) in covariance.iter_mut().zip(cov.iter()) {
        for (o, &v) in out.iter_mut().zip(row.iter()) {
            *o = v;
        }
    }
    let std = core::array::from_fn(|i| libm::sqrt(covariance[i][i].max(0.0)));
    Ok(BundleAdjustReport {
        model: from_params(&layout, &x),
        std,
        covariance,
        initial_rms_px,
        rms_px: rms(views, &layout, &x, corrections)?,
        iterations: solved.iterations,
        evaluations: solved.evaluations,
        stop: solved.stop,
        sigma_px,
    })
}

/// Refines `init` over the views (Eq. 24, or errors-in-variables; see the module docs),
/// in `init`'s layout (distortion family and focal degree).
///
/// `scratch` needs [`bundle_adjust_scratch`] elements; on return its element j holds view
/// j's correction (dZ_j mm, dE_j mA), read with [`ViewCorrection::from`] (zeros for the
/// paper's estimator).
///
/// Preconditions (typed errors): finite input and no empty view; at least 3 distinct
/// currents; more residuals than numbers (13 points for the paper's 25); positive prior
/// standard deviations for errors-in-variables; a hold mask inside the layout; storage of
/// the right size.
pub fn bundle_adjust(
    views: &[View<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &mut [ViewScratch],
) -> Result<BundleAdjustReport> {
    check_input(views, init, options, scratch)?;
    let layout = init.layout();
    with_layout!(layout, N, O, P, bundle_adjust_n::<N, O, P>(views, init, options, scratch))
}

/// [`bundle_adjust`] for a layout of `N` numbers with `O` per-view variables other than
/// u0, v0, whose rows pad to `P`.
fn bundle_adjust_n<const N: usize, const O: usize, const P: usize>(
    views: &[View<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &mut [ViewScratch],
) -> Result<BundleAdjustReport>
where
    ViewScratch: BlockStorage<N, 2> + Prepare<N>,
{
    let needed = views.len();
    let scratch =
        scratch.get_mut(..needed).ok_or(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: 0 })?;
    // The corrections start at zero (and stay there for the paper's estimator).
    scratch.iter_mut().for_each(<ViewScratch as Prepare<N>>::prepare);
    let layout = init.layout();
    let x0 = to_params_n::<N>(init)?;
    let initial_rms_px = rms(views, &layout, &x0, None)?;
    // The solver works in the well-conditioned internal parameters z (basis.rs).
    let basis = &Basis::for_views(views, layout);
    let plain = solve_plain::<N, O, P>(views, x0, options, basis)?;
    let sigma_plain = libm::sqrt(plain.sigma2);
    let (sigma_z_mm, sigma_e_ma, sigma_px) = match options.estimator {
        Estimator::Paper => return paper_report(views, basis, &plain, initial_rms_px, options),
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px } => {
            (sigma_z_mm, sigma_e_ma, sigma_px.unwrap_or(sigma_plain))
        }
    };
    if !(sigma_z_mm > 0.0 && sigma_e_ma > 0.0 && sigma_px > 0.0) {
        return Err(Error::InvalidArgument { what: "errors-in-variables standard deviations must be positive" });
    }
    let reference = options.robust.map(|_| projector(&layout, &basis.to_params(&plain.x)));
    // sigma_px re-estimated from the errors-in-variables residuals (least squares only).
    let estimate_sigma = matches!(options.estimator, Estimator::Eiv { sigma_px: None, .. }) && options.robust.is_none();
    let (mut sigma_px, mut start) = (sigma_px, plain.x);
    let mut round = 0;
    let solved = loop {
        let mut problem =
            Eiv::<N, O, P> { views, basis, x0, options, sigma_px, sigma_z_mm, sigma_e_ma, reference, at: None };
        let solved = lm::solve_blocks(&mut problem, start, &options.lm, &mut *scratch)?;
        round += 1;
        if !estimate_sigma || round >= SIGMA_ROUNDS {
            break solved;
        }
        let next = residual_sigma_px(views, &layout, &basis.to_params(&solved.x), scratch)?;
        if !(next > 0.0) || (next / sigma_px - 1.0).abs() <= SIGMA_RTOL {
            break solved;
        }
        (sigma_px, start) = (next, solved.x);
    };
    report_of(views, basis, &unscaled(solved), initial_rms_px, sigma_px, Some(scratch))
}

/// The paper estimator's report, its covariance under [`BundleAdjustOptions::input_noise`].
fn paper_report<const N: usize>(
    views: &[View<'_>],
    basis: &Basis,
    plain: &lm::Report<N>,
    initial_rms_px: f64,
    options: &BundleAdjustOptions,
) -> Result<BundleAdjustReport> {
    let mut report = report_of(views, basis, plain, initial_rms_px, libm::sqrt(plain.sigma2), None)?;
    if let Some(noise) = &options.input_noise {
        let honest = covariance_with_input_noise(views, &report, options.robust, noise)?;
        report.covariance = honest.covariance;
        for (i, (s, row)) in report.std.iter_mut().zip(report.covariance.iter()).enumerate() {
            *s = libm::sqrt(row.get(i).copied().unwrap_or(0.0).max(0.0));
        }
        report.sigma_px = honest.sigma_px;
    }
    Ok(report)
}

/// Rounds of the errors-in-variables solve with sigma_px re-estimated (module docs).
const SIGMA_ROUNDS: usize = 4;
/// Relative change of sigma_px below which it is taken as converged.
const SIGMA_RTOL: f64 = 1e-3;

/// The pixel noise the errors-in-variables residuals show: sigma^2 = sum |e|^2 / (2 n -
/// p) over the n points with the view corrections applied, p numbers (the 2 per view are
/// mostly fixed by their priors; counting them would change sigma by < 1 % at the paper
/// rig).
fn residual_sigma_px<const N: usize>(
    views: &[View<'_>],
    layout: &Layout,
    x: &[f64; N],
    corrections: &[ViewScratch],
) -> Result<f64> {
    let n = point_count(views);
    let rms = rms(views, layout, x, Some(corrections))?;
    let dof = (2 * n).saturating_sub(N).max(1);
    Ok(libm::sqrt(rms * rms * n as f64 / dof as f64))
}

/// The errors-in-variables covariance without the solver's residual-variance factor:
/// the rows are already normalised by their standard deviations (sigma_px estimated, the
/// priors given), so the inverse Fisher information (U - sum W V^-1 W^T)^-1 is the
/// covariance; rescaling it by cost / dof would shrink the prior-driven directions with
/// the pixel noise's estimate.
fn unscaled<const N: usize>(mut solved: lm::Report<N>) -> lm::Report<N> {
    if solved.sigma2 > 0.0 && solved.sigma2.is_finite() {
        let f = 1.0 / solved.sigma2;
        solved.covariance.iter_mut().flatten().for_each(|c| *c *= f);
    }
    solved
}

#[cfg(test)]
mod tests {
    use super::problems::Plain;
    use super::*;
    use crate::calib::jacobian::Projector;
    use crate::calib::observations::Point;
    use crate::lm::{BlockNormal, BlockProblem, NormalEquations, Problem};

    fn three_views(truth: &CameraModel) -> ([[Point; 12]; 3], [f64; 3]) {
        let mut pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 3];
        let currents = [90.0, 150.0, 225.0];
        for (k, view) in pts.iter_mut().enumerate() {
            for (i, p) in view.iter_mut().enumerate() {
                let w = [1.5 * (i % 4) as f64 + 3.0, 1.5 * (i / 4) as f64 + 2.0, 40.0 - 15.0 * k as f64];
                let q = truth.project(w, currents[k]).unwrap();
                // Deterministic "noise", large on one point so the robust weights bite.
                let d = if i == 5 { 4.0 } else { 0.3 * ((i * 7 + k * 3) % 5) as f64 - 0.6 };
                *p = Point { world_mm: w, pixel: [q[0] + d, q[1] - 0.5 * d] };
            }
        }
        (pts, currents)
    }

    /// The paper rig's camera in the opencv family (its distortion refitted roughly, plus
    /// k2, k3 terms) with quintic focal polynomials: every part of the folded equations of
    /// the largest layout is exercised.
    fn opencv_quintic() -> CameraModel {
        let mut m = CameraModel::paper_rig();
        m.kf_x = crate::model::FocalPoly::new(&[5380.0, -7.0, 0.02, -3e-5, 1e-9, -2e-12]).unwrap();
        m.kf_y = crate::model::FocalPoly::new(&[5430.0, -7.0, 0.02, -3e-5, 1e-9, -2e-12]).unwrap();
        m.distortion_a = crate::model::DistortionA::opencv([
            -2.0e5, 40.0, -0.1, 1e6, -300.0, 0.5, 3.0, -1e-3, 2e-4, -2.0, 4e-4, -1e-4, 1e6, -100.0, 0.02,
        ]);
        m
    }

    fn close(a: f64, b: f64, scale: f64, what: &str) {
        assert!((a - b).abs() <= 1e-10 * scale.max(1e-9), "{what}: {a} vs {b}");
    }

    fn perturbed<const N: usize>(truth: &CameraModel) -> ([f64; N], [f64; N]) {
        let x0 = to_params_n::<N>(truth).unwrap();
        let mut x = x0;
        x[0] += 1e-3;
        x[4] += 0.01;
        x[7] *= 1.01;
        x[N - 4] += 0.1 * x[N - 4].abs().max(1e-6);
        (x0, x)
    }

    /// Runs `check(views, basis, x0, x)` on three views of `truth` with deterministic
    /// noise, a start `x0` and a perturbed `x` (internal), the A0 numbers held and the
    /// robust loss `robust`: the setting of both folding tests.
    fn with_three_views<const N: usize>(
        truth: &CameraModel,
        robust: RobustLoss,
        check: impl FnOnce(&[View<'_>], &Basis, [f64; N], [f64; N], &BundleAdjustOptions),
    ) {
        let (pts, currents) = three_views(truth);
        let views: [View; 3] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &pts[k] });
        let layout = truth.layout();
        let (x0, x) = perturbed::<N>(truth);
        let options = BundleAdjustOptions { hold: layout.a0_mask(), robust: Some(robust), ..Default::default() };
        let basis = Basis::for_views(&views, layout);
        check(&views, &basis, x0, basis.to_internal(&x), &options);
    }

    /// The per-view folded normal equations equal those of the streamed rows, with the
    /// robust weights and hold rows in play.
    fn folded_equals_streamed<const N: usize, const O: usize, const P: usize>(truth: &CameraModel) {
        with_three_views::<N>(truth, RobustLoss::Huber { k_px: 1.0 }, |views, basis, x0, x, options| {
            let reference = Some(Projector::new(truth));
            let mut plain = Plain::<N, O, P> { views, x0, options, reference, basis };
            check_folded_normal_equations(&mut plain, &x);
        });
    }

    /// The per-view folded normal equations of `plain` at `x` against its streamed rows.
    fn check_folded_normal_equations<const N: usize, const O: usize, const P: usize>(
        plain: &mut Plain<'_, '_, N, O, P>,
        x: &[f64; N],
    ) {
        let mut folded = NormalEquations::<N>::ZERO;
        assert!(plain.normal_equations(x, &mut folded).unwrap());
        let mut streamed = NormalEquations::<N>::ZERO;
        plain.eval(x, true, &mut streamed).unwrap();
        assert_eq!(folded.rows, streamed.rows);
        assert!((folded.cost - streamed.cost).abs() <= 1e-12 * streamed.cost);
        for i in 0..N {
            let gi = streamed.g[i];
            assert!((folded.g[i] - gi).abs() <= 1e-9 * gi.abs().max(1e-9), "g[{i}]: {} vs {gi}", folded.g[i]);
            for j in i..N {
                let aij = streamed.a[i][j];
                let scale = libm::sqrt(streamed.a[i][i] * streamed.a[j][j]);
                assert!((folded.a[i][j] - aij).abs() <= 1e-11 * scale, "a[{i}][{j}]: {} vs {aij}", folded.a[i][j]);
            }
        }
    }

    #[test]
    fn folded_normal_equations_equal_the_streamed_ones() {
        folded_equals_streamed::<25, 11, 12>(&CameraModel::paper_rig());
        folded_equals_streamed::<35, 13, 16>(&opencv_quintic());
    }

    /// The same for the errors-in-variables blocks: U, g_x, W, V, g_y.
    fn folded_blocks_equal_streamed<const N: usize, const O: usize, const P: usize>(truth: &CameraModel) {
        with_three_views::<N>(truth, RobustLoss::Cauchy { k_px: 1.0 }, |views, basis, x0, x, options| {
            let (sigma_px, sigma_z_mm, sigma_e_ma) = (0.3, 0.01, 0.4);
            let reference = Some(Projector::new(truth));
            let mut eiv =
                Eiv::<N, O, P> { views, basis, x0, options, sigma_px, sigma_z_mm, sigma_e_ma, reference, at: None };
            check_folded_blocks(&mut eiv, &x);
        });
    }

    /// The folded errors-in-variables blocks of `eiv` at `x` against its streamed rows.
    fn check_folded_blocks<const N: usize, const O: usize, const P: usize>(
        eiv: &mut Eiv<'_, '_, N, O, P>,
        x: &[f64; N],
    ) {
        let y = [0.004, -0.3];
        for block in 0..3 {
            let mut s = ([[0.0; N]; N], [0.0; N], [[0.0; 2]; N], [[0.0; 2]; 2], [0.0; 2]);
            let mut f = s;
            let mut streamed =
                BlockNormal { u: &mut s.0, gx: &mut s.1, w: &mut s.2, v: &mut s.3, gy: &mut s.4, cost: 0.0, rows: 0 };
            eiv.eval_block(block, x, &y, true, &mut streamed).unwrap();
            let (sc, sr) = (streamed.cost, streamed.rows);
            let mut folded =
                BlockNormal { u: &mut f.0, gx: &mut f.1, w: &mut f.2, v: &mut f.3, gy: &mut f.4, cost: 0.0, rows: 0 };
            assert!(eiv.block_normal_equations(block, x, &y, &mut folded).unwrap());
            assert_eq!(folded.rows, sr);
            close(folded.cost, sc, sc, "cost");
            for i in 0..N {
                close(f.1[i], s.1[i], libm::sqrt(s.0[i][i] * sc), "g_x");
                for j in i..N {
                    close(f.0[i][j], s.0[i][j], libm::sqrt(s.0[i][i] * s.0[j][j]), "U");
                }
                for k in 0..2 {
                    close(f.2[i][k], s.2[i][k], libm::sqrt(s.0[i][i] * s.3[k][k]), "W");
                }
            }
            for k in 0..2 {
                close(f.4[k], s.4[k], libm::sqrt(s.3[k][k] * sc), "g_y");
                close(f.3[k][1], s.3[k][1], libm::sqrt(s.3[k][k] * s.3[1][1]), "V");
            }
        }
    }

    #[test]
    fn folded_block_normal_equations_equal_the_streamed_ones() {
        folded_blocks_equal_streamed::<25, 11, 12>(&CameraModel::paper_rig());
        folded_blocks_equal_streamed::<35, 13, 16>(&opencv_quintic());
    }
}
