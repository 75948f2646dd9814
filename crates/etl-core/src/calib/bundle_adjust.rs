//! Bundle adjustment (Eq. 24) of the 25 numbers, and the errors-in-variables estimator.
//!
//! **Paper** (default): minimise sum over all points of |observed - projected|^2 over
//! R (Rodrigues), T, kf_x, kf_y, (u0, v0), a1..a9, treating each view's recorded stage
//! position Z_W and current E as exact. Solved by the dense LM of [`crate::lm::solve`]
//! (MINPACK column scaling makes the 12 orders of magnitude between the raw parameters
//! harmless: the step is computed in scaled variables).
//!
//! **Errors-in-variables** (beyond the paper): maximum likelihood under the full noise
//! model of NOTES.md. Each view j gets a correction dZ_j of its stage position and dE_j of
//! its current, with Gaussian priors (10 um and 0.4 mA by default). Residuals are
//! normalised by their standard deviations:
//!
//! ```text
//! sum_j [ sum_i |obs_ij - proj(P_ij + dZ_j e_z, E_j + dE_j)|^2 / sigma_px^2
//!         + dZ_j^2 / sigma_Z^2 + dE_j^2 / sigma_E^2 ]
//! ```
//!
//! The per-view unknowns couple only to the 25 shared numbers, so they are eliminated by
//! the Schur complement ([`crate::lm::solve_blocks`], storage from the caller). sigma_px
//! defaults to the residual standard deviation of the plain solution.
//!
//! **Hold A0**: kf0x, kf0y, u0, v0 are held at their start values by prior rows of weight
//! 1e8 per unit of their magnitude (relative change ~1e-8 px-equivalents): their
//! reported standard deviation is then ~0.
//!
//! **Robust loss** (Huber or Cauchy with threshold k px): iteratively reweighted least
//! squares. Each point's residual pair gets the weight w = rho'(s), s = |e|^2, evaluated at
//! a fixed reference estimate (the previous IRLS iterate), so every weighted solve has an
//! exact Jacobian; the weights are recomputed from the reference on the fly (no per-point
//! storage) and the loop stops when the estimate no longer moves (at most
//! [`IRLS_MAX_ROUNDS`] rounds).

use super::jacobian::{from_params, to_params, Projector, KF0X, PARAMS, U0};
use super::observations::{distinct_currents, point_count, validate, View};
use crate::error::{Error, Result};
use crate::lm::{self, Accumulation, BlockProblem, BlockRowSink, BlockScratch, Options, Problem, RowSink, StopReason};
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

/// sqrt of the IRLS weight of a point, from its error at the reference estimate.
fn robust_scale(
    robust: Option<RobustLoss>,
    reference: Option<&Projector>,
    world_mm: [f64; 3],
    e_ma: f64,
    pixel: [f64; 2],
) -> Result<f64> {
    match (robust, reference) {
        (Some(loss), Some(proj)) => {
            let p = proj.project(world_mm, e_ma, false)?;
            let (du, dv) = (p.pixel[0] - pixel[0], p.pixel[1] - pixel[1]);
            Ok(libm::sqrt(loss.weight(du * du + dv * dv)))
        }
        _ => Ok(1.0),
    }
}

/// Options of [`bundle_adjust`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleAdjustOptions {
    /// The estimator (default: the paper's).
    pub estimator: Estimator,
    /// Hold kf0x, kf0y, u0, v0 at their start values (default: refine all 25).
    pub hold_a0: bool,
    /// Robust loss (default: none, least squares).
    pub robust: Option<RobustLoss>,
    /// Solver options.
    pub lm: Options,
}

impl Default for BundleAdjustOptions {
    fn default() -> Self {
        BundleAdjustOptions {
            estimator: Estimator::Paper,
            hold_a0: false,
            robust: None,
            lm: Options {
                max_iterations: 100,
                ftol: 1e-10,
                xtol: 1e-10,
                gtol: 1e-10,
                accumulation: Accumulation::NormalEquations,
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
    /// The refined model.
    pub model: CameraModel,
    /// One standard deviation of each of the 25 numbers (order of
    /// [`super::jacobian::PARAM_NAMES`]).
    pub std: [f64; PARAMS],
    /// Covariance of the 25 numbers.
    pub covariance: [[f64; PARAMS]; PARAMS],
    /// RMS reprojection error before, px: sqrt(sum |e|^2 / points).
    pub initial_rms_px: f64,
    /// RMS reprojection error after, px (with the view corrections applied).
    pub rms_px: f64,
    /// LM iterations (of the final estimator).
    pub iterations: usize,
    /// Why the LM stopped.
    pub stop: StopReason,
    /// Pixel noise standard deviation used (errors-in-variables) or estimated (paper).
    pub sigma_px: f64,
}

/// Storage [`bundle_adjust`] needs in `scratch` for `views` views: one element per view for
/// the errors-in-variables estimator, none for the paper's.
pub const fn bundle_adjust_scratch(views: usize, estimator: &Estimator) -> usize {
    match estimator {
        Estimator::Paper => 0,
        Estimator::Eiv { .. } => views,
    }
}

const HOLD_WEIGHT: f64 = 1e8;

fn hold_rows(x: &[f64; PARAMS], x0: &[f64; PARAMS], mut push: impl FnMut(f64, &[f64; PARAMS])) {
    for i in [KF0X, KF0X + 4, U0, U0 + 1] {
        let (Some(&xi), Some(&x0i)) = (x.get(i), x0.get(i)) else { continue };
        let w = HOLD_WEIGHT / x0i.abs().max(1.0);
        let mut j = [0.0; PARAMS];
        if let Some(ji) = j.get_mut(i) {
            *ji = w;
        }
        push((xi - x0i) * w, &j);
    }
}

struct Plain<'a, 'b> {
    views: &'a [View<'b>],
    x0: [f64; PARAMS],
    options: &'a BundleAdjustOptions,
    reference: Option<Projector>,
}

impl Problem<PARAMS> for Plain<'_, '_> {
    fn eval(&mut self, x: &[f64; PARAMS], jacobian: bool, sink: &mut dyn RowSink<PARAMS>) -> Result<()> {
        let proj = Projector::new(x);
        for view in self.views {
            for p in view.points {
                let pr = proj.project(p.world_mm, view.e_com_ma, jacobian)?;
                let e = [pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]];
                let f = robust_scale(self.options.robust, self.reference.as_ref(), p.world_mm, view.e_com_ma, p.pixel)?;
                for row in 0..2 {
                    let mut j = pr.d_params[row];
                    if f != 1.0 {
                        j.iter_mut().for_each(|v| *v *= f);
                    }
                    sink.push(f * e[row], &j);
                }
            }
        }
        if self.options.hold_a0 {
            hold_rows(x, &self.x0, |r, j| sink.push(r, j));
        }
        Ok(())
    }
}

struct Eiv<'a, 'b> {
    views: &'a [View<'b>],
    x0: [f64; PARAMS],
    options: &'a BundleAdjustOptions,
    sigma_px: f64,
    sigma_z_mm: f64,
    sigma_e_ma: f64,
    reference: Option<Projector>,
}

impl BlockProblem<PARAMS, 2> for Eiv<'_, '_> {
    fn block_count(&self) -> usize {
        self.views.len()
    }

    fn eval_block(
        &mut self,
        block: usize,
        x: &[f64; PARAMS],
        y: &[f64; 2],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<PARAMS, 2>,
    ) -> Result<()> {
        let view = self.views.get(block).ok_or(Error::InvalidArgument { what: "block index out of range" })?;
        let proj = Projector::new(x);
        let is = 1.0 / self.sigma_px;
        let e_ma = view.e_com_ma + y[1];
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + y[0]];
            let pr = proj.project(w, e_ma, jacobian)?;
            let e = [pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]];
            let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
            for row in 0..2 {
                let mut j = pr.d_params[row];
                j.iter_mut().for_each(|v| *v *= f);
                sink.push(f * e[row], &j, &[f * pr.d_z_w[row], f * pr.d_e[row]]);
            }
        }
        let zero = [0.0; PARAMS];
        sink.push(y[0] / self.sigma_z_mm, &zero, &[1.0 / self.sigma_z_mm, 0.0]);
        sink.push(y[1] / self.sigma_e_ma, &zero, &[0.0, 1.0 / self.sigma_e_ma]);
        if self.options.hold_a0 && block == 0 {
            hold_rows(x, &self.x0, |r, j| sink.push(r, j, &[0.0, 0.0]));
        }
        Ok(())
    }
}

/// RMS reprojection error of `model` over the views (with per-view corrections).
fn rms(views: &[View<'_>], x: &[f64; PARAMS], corrections: Option<&[[f64; 2]]>) -> Result<f64> {
    let proj = Projector::new(x);
    let (mut s, mut n) = (0.0, 0usize);
    for (j, view) in views.iter().enumerate() {
        let c = corrections.and_then(|c| c.get(j)).copied().unwrap_or([0.0; 2]);
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + c[0]];
            let pr = proj.project(w, view.e_com_ma + c[1], false)?;
            s += (pr.pixel[0] - p.pixel[0]) * (pr.pixel[0] - p.pixel[0])
                + (pr.pixel[1] - p.pixel[1]) * (pr.pixel[1] - p.pixel[1]);
            n += 1;
        }
    }
    Ok(if n > 0 { libm::sqrt(s / n as f64) } else { 0.0 })
}

fn std_of(cov: &[[f64; PARAMS]; PARAMS]) -> [f64; PARAMS] {
    core::array::from_fn(|i| libm::sqrt(cov[i][i].max(0.0)))
}

/// Refines `init` over the views (Eq. 24, or errors-in-variables; see the module docs).
///
/// `corrections` receives each view's (dZ_j mm, dE_j mA) (zeros for the paper's estimator);
/// it must hold one entry per view. `scratch` needs [`bundle_adjust_scratch`] elements.
///
/// Preconditions (typed errors): finite input and no empty view; at least 3 distinct
/// currents; at least 25 residual pairs' worth of points (13 points); positive prior
/// standard deviations for errors-in-variables; storage of the right size.
pub fn bundle_adjust(
    views: &[View<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    corrections: &mut [ViewCorrection],
    scratch: &mut [BlockScratch<PARAMS, 2>],
) -> Result<BundleAdjustReport> {
    validate(views)?;
    init.validate()?;
    let nc = distinct_currents(views);
    if nc < 3 {
        return Err(Error::TooFew { what: "distinct currents (Appendix I)", needed: 3, got: nc });
    }
    let n = point_count(views);
    if 2 * n < PARAMS + 1 {
        return Err(Error::TooFew { what: "points for bundle adjustment", needed: PARAMS / 2 + 1, got: n });
    }
    if corrections.len() != views.len() {
        return Err(Error::BufferTooSmall { what: "corrections", needed: views.len(), got: corrections.len() });
    }
    let x0 = to_params(init);
    let initial_rms_px = rms(views, &x0, None)?;
    let mut plain = lm::solve(&mut Plain { views, x0, options, reference: None }, x0, &options.lm)?;
    if options.robust.is_some() {
        // IRLS: reweight around the latest estimate until it stops moving.
        for _ in 0..IRLS_MAX_ROUNDS {
            let reference = Some(Projector::new(&plain.x));
            let next = lm::solve(&mut Plain { views, x0, options, reference }, plain.x, &options.lm)?;
            let moved = next.x.iter().zip(plain.x.iter()).any(|(a, b)| (a - b).abs() > 1e-9 * b.abs().max(1e-12));
            plain = next;
            if !moved {
                break;
            }
        }
    }
    corrections.iter_mut().for_each(|c| *c = ViewCorrection::default());
    let sigma_plain = libm::sqrt(plain.sigma2);
    let (sigma_z_mm, sigma_e_ma, sigma_px) = match options.estimator {
        Estimator::Paper => {
            return Ok(BundleAdjustReport {
                model: from_params(&plain.x),
                std: std_of(&plain.covariance),
                covariance: plain.covariance,
                initial_rms_px,
                rms_px: rms(views, &plain.x, None)?,
                iterations: plain.iterations,
                stop: plain.stop,
                sigma_px: sigma_plain,
            });
        }
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px } => {
            (sigma_z_mm, sigma_e_ma, sigma_px.unwrap_or(sigma_plain))
        }
    };
    if !(sigma_z_mm > 0.0 && sigma_e_ma > 0.0 && sigma_px > 0.0) {
        return Err(Error::InvalidArgument { what: "errors-in-variables standard deviations must be positive" });
    }
    if scratch.len() < views.len() {
        return Err(Error::BufferTooSmall {
            what: "bundle adjustment scratch",
            needed: views.len(),
            got: scratch.len(),
        });
    }
    // The view corrections live in the caller's `corrections`, viewed as [dZ, dE] pairs
    // through a small copy per solve (the caller's type stays self-describing).
    let mut y = [[0.0f64; 2]; MAX_EIV_VIEWS];
    let y = y.get_mut(..views.len()).ok_or(Error::TooFew {
        what: "capacity for errors-in-variables views (MAX_EIV_VIEWS)",
        needed: views.len(),
        got: MAX_EIV_VIEWS,
    })?;
    let reference = options.robust.map(|_| Projector::new(&plain.x));
    let mut problem = Eiv { views, x0, options, sigma_px, sigma_z_mm, sigma_e_ma, reference };
    let r = lm::solve_blocks(&mut problem, plain.x, y, &options.lm, scratch)?;
    for (c, yj) in corrections.iter_mut().zip(y.iter()) {
        *c = ViewCorrection { dz_mm: yj[0], de_ma: yj[1] };
    }
    Ok(BundleAdjustReport {
        model: from_params(&r.x),
        std: std_of(&r.covariance),
        covariance: r.covariance,
        initial_rms_px,
        rms_px: rms(views, &r.x, Some(y))?,
        iterations: r.iterations,
        stop: r.stop,
        sigma_px,
    })
}

/// Largest number of views the errors-in-variables estimator takes (its per-view
/// corrections are held on the stack: 16 bytes each).
pub const MAX_EIV_VIEWS: usize = 256;
