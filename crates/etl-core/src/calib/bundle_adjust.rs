//! Bundle adjustment (Eq. 24) of the 25 numbers, and the errors-in-variables estimator.
//!
//! **Paper** (default): minimise sum over all points of |observed - projected|^2 over
//! R (Rodrigues), T, kf_x, kf_y, (u0, v0), a1..a9, treating each view's recorded stage
//! position Z_W and current E as exact. Solved by the dense LM of [`crate::lm::solve`]
//! (MINPACK column scaling makes the 12 orders of magnitude between the raw parameters
//! harmless: the step is computed in scaled variables).
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
//! The per-view unknowns couple only to the 25 shared numbers, so they are eliminated by
//! the Schur complement ([`crate::lm::solve_blocks`], storage from the caller). sigma_px,
//! unless given, is estimated: it starts at the residual standard deviation of the plain
//! solution (which the uncorrected stage and current errors inflate) and is re-estimated
//! from the errors-in-variables residuals, sum |e|^2 / (2 n - 25), the solve repeated
//! until it moves by less than 0.1 % (at most 4 solves; not with a robust loss, whose
//! weights would need their own scale). The reported covariance is that of the 25 shared
//! numbers with the corrections marginalised out, (U - sum_j W_j V_j^-1 W_j^T)^-1 of the
//! normalised rows, not rescaled by the residual variance: the priors are given, not
//! estimated (rescaling made the one-sigma intervals of kf cover the truth 56-62 % of the
//! time instead of 68 %, tests/uncertainty.rs of etl-calib).
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

use super::basis::Basis;
use super::jacobian::{from_params, to_params, Projector};
use super::observations::{distinct_currents, point_count, validate, View};
use super::params::{A0_INDICES, PARAMS, REDUCED, R_DISTORTION, R_FX, R_FY, R_POSE, R_U0, R_V0};
use crate::error::{Error, Result};
use crate::lm::{
    self, Accumulation, BlockNormal, BlockProblem, BlockRowSink, BlockScratch, NormalEquations, Options, Problem,
    RowSink, StopReason,
};
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
            let p = proj.project_reduced(world_mm, e_ma, false)?;
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
    /// The refined model.
    pub model: CameraModel,
    /// One standard deviation of each of the 25 numbers (order of
    /// [`super::params::PARAM_NAMES`]).
    pub std: [f64; PARAMS],
    /// Covariance of the 25 numbers.
    pub covariance: [[f64; PARAMS]; PARAMS],
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
    /// Pixel noise standard deviation used (errors-in-variables) or estimated (paper).
    pub sigma_px: f64,
}

/// One view's storage of [`bundle_adjust`]: the view's correction (dZ_j mm, dE_j mA: the
/// block parameters of the errors-in-variables solve, zeros for the paper's estimator)
/// and the block solver's working state. Read the correction with
/// [`ViewCorrection::from`].
pub type ViewScratch = BlockScratch<PARAMS, 2>;

impl From<&ViewScratch> for ViewCorrection {
    fn from(scratch: &ViewScratch) -> Self {
        let [dz_mm, de_ma] = *scratch.y();
        ViewCorrection { dz_mm, de_ma }
    }
}

/// Number of [`ViewScratch`] elements [`bundle_adjust`] needs for `views` views: one per
/// view, whatever the estimator (each holds the view's correction on return).
pub const fn bundle_adjust_scratch(views: usize) -> usize {
    lm::solve_blocks_scratch::<PARAMS, 2>(views)
}

const HOLD_WEIGHT: f64 = 1e8;

fn hold_rows(
    x: &[f64; PARAMS],
    x0: &[f64; PARAMS],
    dxdz: &[[f64; PARAMS]; PARAMS],
    mut push: impl FnMut(f64, &[f64; PARAMS]),
) {
    for i in A0_INDICES {
        let (Some(&xi), Some(&x0i), Some(row)) = (x.get(i), x0.get(i), dxdz.get(i)) else { continue };
        let w = HOLD_WEIGHT / x0i.abs().max(1.0);
        let j: [f64; PARAMS] = core::array::from_fn(|k| w * row.get(k).copied().unwrap_or(0.0));
        push((xi - x0i) * w, &j);
    }
}

/// A gradient row with respect to x as one with respect to z: j_z = j_x dx/dz.
fn row_in(dxdz: &[[f64; PARAMS]; PARAMS], jx: &[f64; PARAMS]) -> [f64; PARAMS] {
    let mut jz = [0.0; PARAMS];
    for (&ji, di) in jx.iter().zip(dxdz.iter()) {
        if ji != 0.0 {
            for (jzk, &dik) in jz.iter_mut().zip(di.iter()) {
                *jzk += ji * dik;
            }
        }
    }
    jz
}

/// cov_x = dx/dz cov_z (dx/dz)^T.
fn covariance_in_params(dxdz: &[[f64; PARAMS]; PARAMS], cov_z: &[[f64; PARAMS]; PARAMS]) -> [[f64; PARAMS]; PARAMS] {
    let mut t = [[0.0; PARAMS]; PARAMS];
    for (ti, di) in t.iter_mut().zip(dxdz.iter()) {
        for (dik, ck) in di.iter().zip(cov_z.iter()) {
            if *dik != 0.0 {
                for (tij, &ckj) in ti.iter_mut().zip(ck.iter()) {
                    *tij += dik * ckj;
                }
            }
        }
    }
    let mut out = [[0.0; PARAMS]; PARAMS];
    for (oi, ti) in out.iter_mut().zip(t.iter()) {
        for (oij, dj) in oi.iter_mut().zip(dxdz.iter()) {
            *oij = ti.iter().zip(dj.iter()).map(|(a, b)| a * b).sum();
        }
    }
    out
}

/// The paper's problem over the internal parameters z ([`Basis`]).
struct Plain<'a, 'b> {
    views: &'a [View<'b>],
    x0: [f64; PARAMS],
    options: &'a BundleAdjustOptions,
    reference: Option<Projector>,
    /// The solver's parameters: x = to_params(z), dx/dz evaluated at z (basis.rs).
    basis: &'a Basis,
}

impl Problem<PARAMS> for Plain<'_, '_> {
    fn eval(&mut self, z: &[f64; PARAMS], jacobian: bool, sink: &mut dyn RowSink<PARAMS>) -> Result<()> {
        let x = &self.basis.to_params(z);
        let proj = Projector::new(x);
        let dxdz = self.basis.params_jacobian(z);
        for view in self.views {
            for p in view.points {
                let f = robust_scale(self.options.robust, self.reference.as_ref(), p.world_mm, view.e_com_ma, p.pixel)?;
                if !jacobian {
                    // Trial points need only the cost: skip the 2 x 25 rows altogether.
                    let pr = proj.project_reduced(p.world_mm, view.e_com_ma, false)?;
                    sink.push(f * (pr.pixel[0] - p.pixel[0]), &[0.0; PARAMS]);
                    sink.push(f * (pr.pixel[1] - p.pixel[1]), &[0.0; PARAMS]);
                    continue;
                }
                let pr = proj.project(p.world_mm, view.e_com_ma, jacobian)?;
                let e = [pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]];
                for row in 0..2 {
                    let mut j = row_in(&dxdz, &pr.d_params[row]);
                    if f != 1.0 {
                        j.iter_mut().for_each(|v| *v *= f);
                    }
                    sink.push(f * e[row], &j);
                }
            }
        }
        if self.options.hold_a0 {
            hold_rows(x, &self.x0, &dxdz, |r, j| sink.push(r, j));
        }
        Ok(())
    }

    /// The same rows as [`Plain::eval`], folded view by view through the 13 per-view
    /// variables: J_view = J_reduced C_view, so J_view^T J_view = C^T (J_reduced^T
    /// J_reduced) C costs 13 x 13 per point instead of 25 x 25.
    fn normal_equations(&mut self, z: &[f64; PARAMS], out: &mut NormalEquations<PARAMS>) -> Result<bool> {
        let x = &self.basis.to_params(z);
        let proj = Projector::new(x);
        let dxdz = self.basis.params_jacobian(z);
        for view in self.views {
            let mut normal = ViewNormal::ZERO;
            for p in view.points {
                let pr = proj.project_reduced(p.world_mm, view.e_com_ma, true)?;
                let f = robust_scale(self.options.robust, self.reference.as_ref(), p.world_mm, view.e_com_ma, p.pixel)?;
                let r = [f * (pr.pixel[0] - p.pixel[0]), f * (pr.pixel[1] - p.pixel[1])];
                out.cost += r[0] * r[0] + r[1] * r[1];
                out.rows += 2;
                normal.add_point(&pr.d_reduced, f, r);
            }
            let (a, g) = normal.expand();
            fold_view(&a, &g, &proj.chain_in(view.e_com_ma, &dxdz)?, &mut out.a, &mut out.g);
        }
        if self.options.hold_a0 {
            hold_rows(x, &self.x0, &dxdz, |r, j| out.push(r, j));
        }
        Ok(true)
    }
}

/// Row length of the per-view normal equations of the 11 variables other than (u0, v0):
/// padded to a multiple of 4 so that the accumulation vectorises.
const PADDED: usize = 12;

/// The 11 per-view variables other than u0, v0 (whose columns are the constants (1, 0)
/// and (0, 1) and are accumulated as plain sums).
const OTHER: [usize; 11] = [
    R_POSE.at(0),
    R_POSE.at(1),
    R_POSE.at(2),
    R_POSE.at(3),
    R_POSE.at(4),
    R_POSE.at(5),
    R_FX,
    R_FY,
    R_DISTORTION.at(0),
    R_DISTORTION.at(1),
    R_DISTORTION.at(2),
];

/// A view's reduced normal equations: the 11 x 11 block of the variables in [`OTHER`]
/// (upper triangle: row i holds columns i.., padded), their cross terms with u0 and v0 (column sums of the two rows),
/// and the right-hand sides.
struct ViewNormal {
    a: [[f64; PADDED]; 11],
    g: [f64; PADDED],
    /// sum f j_u and sum f j_v over the points (the u0 and v0 columns' cross terms).
    sum: [[f64; PADDED]; 2],
    /// sum f^2 (the u0-u0 and v0-v0 terms, equal) and sum f r_u, sum f r_v.
    f2: f64,
    r_sum: [f64; 2],
}

impl ViewNormal {
    const ZERO: Self =
        ViewNormal { a: [[0.0; PADDED]; 11], g: [0.0; PADDED], sum: [[0.0; PADDED]; 2], f2: 0.0, r_sum: [0.0; 2] };

    /// Adds a point's two rows f j (u and v) with residuals r.
    fn add_point(&mut self, j: &[[f64; REDUCED]; 2], f: f64, r: [f64; 2]) {
        let fj: [[f64; PADDED]; 2] = core::array::from_fn(|row| {
            let mut v = [0.0; PADDED];
            for (vk, &o) in v.iter_mut().zip(OTHER.iter()) {
                *vk = f * j[row][o];
            }
            v
        });
        // The upper triangle only: the rank-2 update is the hot loop of the bundle
        // adjustment (half its instructions with the full square).
        for (i, (ai, (&u, &v))) in self.a.iter_mut().zip(fj[0].iter().zip(fj[1].iter())).enumerate() {
            let (Some(ai), Some(uk), Some(vk)) = (ai.get_mut(i..), fj[0].get(i..), fj[1].get(i..)) else { continue };
            for ((aik, &uk), &vk) in ai.iter_mut().zip(uk.iter()).zip(vk.iter()) {
                *aik += u * uk + v * vk;
            }
        }
        for row in 0..2 {
            for ((gk, sk), &jk) in self.g.iter_mut().zip(self.sum[row].iter_mut()).zip(fj[row].iter()) {
                *gk += jk * r[row];
                *sk += f * jk;
            }
            self.r_sum[row] += f * r[row];
        }
        self.f2 += f * f;
    }

    /// The 13 x 13 normal equations (order of the per-view variables).
    fn expand(&self) -> ([[f64; REDUCED]; REDUCED], [f64; REDUCED]) {
        let (iu, iv) = (R_U0, R_V0);
        let mut a = [[0.0; REDUCED]; REDUCED];
        let mut g = [0.0; REDUCED];
        for (p, &op) in OTHER.iter().enumerate() {
            for (q, &oq) in OTHER.iter().enumerate() {
                // Stored: the upper triangle (q >= p).
                let w =
                    if q >= p { self.a.get(p).and_then(|r| r.get(q)) } else { self.a.get(q).and_then(|r| r.get(p)) };
                if let (Some(v), Some(&w)) = (a.get_mut(op).and_then(|r| r.get_mut(oq)), w) {
                    *v = w;
                }
            }
            if let (Some(v), Some(&w)) = (g.get_mut(op), self.g.get(p)) {
                *v = w;
            }
            for (row, &i) in [iu, iv].iter().enumerate() {
                let w = self.sum[row].get(p).copied().unwrap_or(0.0);
                if let Some(v) = a.get_mut(op).and_then(|r| r.get_mut(i)) {
                    *v = w;
                }
                if let Some(v) = a.get_mut(i).and_then(|r| r.get_mut(op)) {
                    *v = w;
                }
            }
        }
        a[iu][iu] = self.f2;
        a[iv][iv] = self.f2;
        g[iu] = self.r_sum[0];
        g[iv] = self.r_sum[1];
        (a, g)
    }
}

/// out_a += C^T a C (upper triangle), out_g += C^T g, for a view's reduced normal
/// equations (a: the full square) and its chain matrix C (13 x 25).
fn fold_view(
    a: &[[f64; REDUCED]; REDUCED],
    g: &[f64; REDUCED],
    c: &[[f64; PARAMS]; REDUCED],
    out_a: &mut [[f64; PARAMS]; PARAMS],
    out_g: &mut [f64; PARAMS],
) {
    // t = a_sym C, row by row.
    let mut t = [[0.0; PARAMS]; REDUCED];
    for (r, tr) in t.iter_mut().enumerate() {
        for (s, cs) in c.iter().enumerate() {
            let ars = a[r][s];
            if ars != 0.0 {
                for (trq, &csq) in tr.iter_mut().zip(cs.iter()) {
                    *trq += ars * csq;
                }
            }
        }
    }
    for (r, (cr, tr)) in c.iter().zip(t.iter()).enumerate() {
        for (p, ((&crp, outp), gp)) in cr.iter().zip(out_a.iter_mut()).zip(out_g.iter_mut()).enumerate() {
            if crp != 0.0 {
                *gp += crp * g[r];
                for (apq, &trq) in outp.iter_mut().zip(tr.iter()).skip(p) {
                    *apq += crp * trq;
                }
            }
        }
    }
}

struct Eiv<'a, 'b> {
    views: &'a [View<'b>],
    /// The solver's parameters: x = to_params(z), dx/dz evaluated at z (basis.rs).
    basis: &'a Basis,
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
        let dxdz = self.basis.params_jacobian(x);
        let x = &self.basis.to_params(x);
        let proj = Projector::new(x);
        let is = 1.0 / self.sigma_px;
        let e_ma = view.e_com_ma + y[1];
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + y[0]];
            let pr = proj.project(w, e_ma, jacobian)?;
            let e = [pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]];
            let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
            for row in 0..2 {
                let mut j = row_in(&dxdz, &pr.d_params[row]);
                j.iter_mut().for_each(|v| *v *= f);
                sink.push(f * e[row], &j, &[f * pr.d_z_w[row], f * pr.d_e[row]]);
            }
        }
        self.prior_rows(block, x, &dxdz, y, sink);
        Ok(())
    }

    /// The same rows as [`Eiv::eval_block`], folded through the 13 per-view variables:
    /// J_x = J_reduced C and J_y = J_reduced C_y ([`Projector::shift_chain`]), so U, W_b,
    /// V_b all come from one 13 x 13 accumulation per view.
    fn block_normal_equations(
        &mut self,
        block: usize,
        x: &[f64; PARAMS],
        y: &[f64; 2],
        out: &mut BlockNormal<'_, PARAMS, 2>,
    ) -> Result<bool> {
        let view = self.views.get(block).ok_or(Error::InvalidArgument { what: "block index out of range" })?;
        let dxdz = self.basis.params_jacobian(x);
        let x = &self.basis.to_params(x);
        let proj = Projector::new(x);
        let is = 1.0 / self.sigma_px;
        let e_ma = view.e_com_ma + y[1];
        let mut normal = ViewNormal::ZERO;
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + y[0]];
            let pr = proj.project_reduced(w, e_ma, true)?;
            let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
            let r = [f * (pr.pixel[0] - p.pixel[0]), f * (pr.pixel[1] - p.pixel[1])];
            out.cost += r[0] * r[0] + r[1] * r[1];
            out.rows += 2;
            normal.add_point(&pr.d_reduced, f, r);
        }
        let (a, g) = normal.expand();
        let c = proj.chain_in(e_ma, &dxdz)?;
        fold_view(&a, &g, &c, out.u, out.gx);
        // W = C^T a C_y, V = C_y^T a C_y, g_y = C_y^T g.
        let cy = proj.shift_chain(e_ma);
        let mut acy = [[0.0; 2]; REDUCED];
        for (ar, acyr) in a.iter().zip(acy.iter_mut()) {
            for (&ars, cys) in ar.iter().zip(cy.iter()) {
                acyr[0] += ars * cys[0];
                acyr[1] += ars * cys[1];
            }
        }
        for (cr, acyr) in c.iter().zip(acy.iter()) {
            for (&crp, wp) in cr.iter().zip(out.w.iter_mut()) {
                wp[0] += crp * acyr[0];
                wp[1] += crp * acyr[1];
            }
        }
        for (cyr, (acyr, &gr)) in cy.iter().zip(acy.iter().zip(g.iter())) {
            for k in 0..2 {
                out.gy[k] += cyr[k] * gr;
                for l in 0..2 {
                    out.v[k][l] += cyr[k] * acyr[l];
                }
            }
        }
        self.prior_rows(block, x, &dxdz, y, out);
        Ok(true)
    }
}

impl Eiv<'_, '_> {
    /// The rows of the priors on the view's corrections, and (once) the hold-A0 rows.
    fn prior_rows(
        &self,
        block: usize,
        x: &[f64; PARAMS],
        dxdz: &[[f64; PARAMS]; PARAMS],
        y: &[f64; 2],
        sink: &mut dyn BlockRowSink<PARAMS, 2>,
    ) {
        let zero = [0.0; PARAMS];
        sink.push(y[0] / self.sigma_z_mm, &zero, &[1.0 / self.sigma_z_mm, 0.0]);
        sink.push(y[1] / self.sigma_e_ma, &zero, &[0.0, 1.0 / self.sigma_e_ma]);
        if self.options.hold_a0 && block == 0 {
            hold_rows(x, &self.x0, dxdz, |r, j| sink.push(r, j, &[0.0, 0.0]));
        }
    }
}

/// RMS reprojection error of `model` over the views (with per-view corrections).
fn rms(views: &[View<'_>], x: &[f64; PARAMS], corrections: Option<&[ViewScratch]>) -> Result<f64> {
    let proj = Projector::new(x);
    let (mut s, mut n) = (0.0, 0usize);
    for (j, view) in views.iter().enumerate() {
        let c = corrections.and_then(|c| c.get(j)).map_or([0.0; 2], |s| *s.y());
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

fn std_of(cov: &[[f64; PARAMS]; PARAMS]) -> [f64; PARAMS] {
    core::array::from_fn(|i| libm::sqrt(cov[i][i].max(0.0)))
}

/// The preconditions of [`bundle_adjust`] on its input and storage.
fn check_input(views: &[View<'_>], init: &CameraModel, scratch: &[ViewScratch]) -> Result<()> {
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
    let needed = bundle_adjust_scratch(views.len());
    if scratch.len() < needed {
        return Err(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: scratch.len() });
    }
    Ok(())
}

/// The paper's estimator from z0, with the IRLS rounds of a robust loss: reweight around
/// the latest estimate until it stops moving.
fn solve_plain(
    views: &[View<'_>],
    x0: [f64; PARAMS],
    options: &BundleAdjustOptions,
    basis: &Basis,
) -> Result<lm::Report<PARAMS>> {
    let z0 = basis.to_internal(&x0);
    let mut plain = lm::solve(&mut Plain { views, x0, options, reference: None, basis }, z0, &options.lm)?;
    if options.robust.is_some() {
        for _ in 0..IRLS_MAX_ROUNDS {
            let reference = Some(Projector::new(&basis.to_params(&plain.x)));
            let next = lm::solve(&mut Plain { views, x0, options, reference, basis }, plain.x, &options.lm)?;
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
/// to the 25 numbers, the RMS with the view corrections of `scratch` (if any).
fn report_of(
    views: &[View<'_>],
    basis: &Basis,
    solved: &lm::Report<PARAMS>,
    initial_rms_px: f64,
    sigma_px: f64,
    corrections: Option<&[ViewScratch]>,
) -> Result<BundleAdjustReport> {
    let x = basis.to_params(&solved.x);
    let covariance = covariance_in_params(&basis.params_jacobian(&solved.x), &solved.covariance);
    Ok(BundleAdjustReport {
        model: from_params(&x),
        std: std_of(&covariance),
        covariance,
        initial_rms_px,
        rms_px: rms(views, &x, corrections)?,
        iterations: solved.iterations,
        evaluations: solved.evaluations,
        stop: solved.stop,
        sigma_px,
    })
}

/// Refines `init` over the views (Eq. 24, or errors-in-variables; see the module docs).
///
/// `scratch` needs [`bundle_adjust_scratch`] elements; on return its element j holds view
/// j's correction (dZ_j mm, dE_j mA), read with [`ViewCorrection::from`] (zeros for the
/// paper's estimator).
///
/// Preconditions (typed errors): finite input and no empty view; at least 3 distinct
/// currents; at least 25 residual pairs' worth of points (13 points); positive prior
/// standard deviations for errors-in-variables; storage of the right size.
pub fn bundle_adjust(
    views: &[View<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &mut [ViewScratch],
) -> Result<BundleAdjustReport> {
    check_input(views, init, scratch)?;
    let needed = views.len();
    let scratch =
        scratch.get_mut(..needed).ok_or(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: 0 })?;
    // The corrections start at zero (and stay there for the paper's estimator).
    scratch.iter_mut().for_each(|s| s.set_y([0.0; 2]));
    let x0 = to_params(init);
    let initial_rms_px = rms(views, &x0, None)?;
    // The solver works in the well-conditioned internal parameters z (basis.rs).
    let basis = &Basis::for_views(views);
    let plain = solve_plain(views, x0, options, basis)?;
    let sigma_plain = libm::sqrt(plain.sigma2);
    let (sigma_z_mm, sigma_e_ma, sigma_px) = match options.estimator {
        Estimator::Paper => return report_of(views, basis, &plain, initial_rms_px, sigma_plain, None),
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px } => {
            (sigma_z_mm, sigma_e_ma, sigma_px.unwrap_or(sigma_plain))
        }
    };
    if !(sigma_z_mm > 0.0 && sigma_e_ma > 0.0 && sigma_px > 0.0) {
        return Err(Error::InvalidArgument { what: "errors-in-variables standard deviations must be positive" });
    }
    let reference = options.robust.map(|_| Projector::new(&basis.to_params(&plain.x)));
    // sigma_px re-estimated from the errors-in-variables residuals (least squares only).
    let estimate_sigma = matches!(options.estimator, Estimator::Eiv { sigma_px: None, .. }) && options.robust.is_none();
    let (mut sigma_px, mut start) = (sigma_px, plain.x);
    let mut round = 0;
    let solved = loop {
        let mut problem = Eiv { views, basis, x0, options, sigma_px, sigma_z_mm, sigma_e_ma, reference };
        let solved = lm::solve_blocks(&mut problem, start, &options.lm, scratch)?;
        round += 1;
        if !estimate_sigma || round >= SIGMA_ROUNDS {
            break solved;
        }
        let next = residual_sigma_px(views, &basis.to_params(&solved.x), scratch)?;
        if !(next > 0.0) || (next / sigma_px - 1.0).abs() <= SIGMA_RTOL {
            break solved;
        }
        (sigma_px, start) = (next, solved.x);
    };
    report_of(views, basis, &unscaled(solved), initial_rms_px, sigma_px, Some(scratch))
}

/// Rounds of the errors-in-variables solve with sigma_px re-estimated (module docs).
const SIGMA_ROUNDS: usize = 4;
/// Relative change of sigma_px below which it is taken as converged.
const SIGMA_RTOL: f64 = 1e-3;

/// The pixel noise the errors-in-variables residuals show: sigma^2 = sum |e|^2 / (2 n -
/// 25) over the n points with the view corrections applied (the 2 per view are mostly
/// fixed by their priors; counting them would change sigma by < 1 % at the paper rig).
fn residual_sigma_px(views: &[View<'_>], x: &[f64; PARAMS], corrections: &[ViewScratch]) -> Result<f64> {
    let n = point_count(views);
    let rms = rms(views, x, Some(corrections))?;
    let dof = (2 * n).saturating_sub(PARAMS).max(1);
    Ok(libm::sqrt(rms * rms * n as f64 / dof as f64))
}

/// The errors-in-variables covariance without the solver's residual-variance factor:
/// the rows are already normalised by their standard deviations (sigma_px estimated, the
/// priors given), so the inverse Fisher information (U - sum W V^-1 W^T)^-1 is the
/// covariance; rescaling it by cost / dof would shrink the prior-driven directions with
/// the pixel noise's estimate.
fn unscaled(mut solved: lm::Report<PARAMS>) -> lm::Report<PARAMS> {
    if solved.sigma2 > 0.0 && solved.sigma2.is_finite() {
        let f = 1.0 / solved.sigma2;
        solved.covariance.iter_mut().flatten().for_each(|c| *c *= f);
    }
    solved
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::observations::Point;

    fn three_views() -> ([[Point; 12]; 3], [f64; 3]) {
        let truth = CameraModel::paper_rig();
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

    fn close(a: f64, b: f64, scale: f64, what: &str) {
        assert!((a - b).abs() <= 1e-10 * scale.max(1e-9), "{what}: {a} vs {b}");
    }

    /// The per-view folded normal equations equal those of the streamed rows, with the
    /// robust weights and the hold-A0 rows in play.
    #[test]
    fn folded_normal_equations_equal_the_streamed_ones() {
        let truth = CameraModel::paper_rig();
        let (pts, currents) = three_views();
        let views: [View; 3] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &pts[k] });
        let mut x = to_params(&truth);
        x[0] += 1e-3;
        x[7] *= 1.01;
        x[20] += 0.1;
        let options =
            BundleAdjustOptions { hold_a0: true, robust: Some(RobustLoss::Huber { k_px: 1.0 }), ..Default::default() };
        let x0 = to_params(&truth);
        let basis = Basis::for_views(&views);
        let mut plain =
            Plain { views: &views, x0, options: &options, reference: Some(Projector::new(&x0)), basis: &basis };
        let x = basis.to_internal(&x);
        let mut folded = NormalEquations::<PARAMS>::ZERO;
        assert!(plain.normal_equations(&x, &mut folded).unwrap());
        let mut streamed = NormalEquations::<PARAMS>::ZERO;
        plain.eval(&x, true, &mut streamed).unwrap();
        assert_eq!(folded.rows, streamed.rows);
        assert!((folded.cost - streamed.cost).abs() <= 1e-12 * streamed.cost);
        for i in 0..PARAMS {
            let gi = streamed.g[i];
            assert!((folded.g[i] - gi).abs() <= 1e-9 * gi.abs().max(1e-9), "g[{i}]: {} vs {gi}", folded.g[i]);
            for j in i..PARAMS {
                let aij = streamed.a[i][j];
                let scale = libm::sqrt(streamed.a[i][i] * streamed.a[j][j]);
                assert!((folded.a[i][j] - aij).abs() <= 1e-11 * scale, "a[{i}][{j}]: {} vs {aij}", folded.a[i][j]);
            }
        }
    }

    /// The same for the errors-in-variables blocks: U, g_x, W, V, g_y.
    #[test]
    fn folded_block_normal_equations_equal_the_streamed_ones() {
        let truth = CameraModel::paper_rig();
        let (pts, currents) = three_views();
        let views: [View; 3] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &pts[k] });
        let mut x = to_params(&truth);
        x[4] += 0.01;
        x[11] *= 0.99;
        let options =
            BundleAdjustOptions { hold_a0: true, robust: Some(RobustLoss::Cauchy { k_px: 1.0 }), ..Default::default() };
        let x0 = to_params(&truth);
        let basis = Basis::for_views(&views);
        let x = basis.to_internal(&x);
        let mut eiv = Eiv {
            views: &views,
            basis: &basis,
            x0,
            options: &options,
            sigma_px: 0.3,
            sigma_z_mm: 0.01,
            sigma_e_ma: 0.4,
            reference: Some(Projector::new(&x0)),
        };
        let y = [0.004, -0.3];
        for block in 0..3 {
            let mut s = ([[0.0; PARAMS]; PARAMS], [0.0; PARAMS], [[0.0; 2]; PARAMS], [[0.0; 2]; 2], [0.0; 2]);
            let mut f = s;
            let mut streamed =
                BlockNormal { u: &mut s.0, gx: &mut s.1, w: &mut s.2, v: &mut s.3, gy: &mut s.4, cost: 0.0, rows: 0 };
            eiv.eval_block(block, &x, &y, true, &mut streamed).unwrap();
            let (sc, sr) = (streamed.cost, streamed.rows);
            let mut folded =
                BlockNormal { u: &mut f.0, gx: &mut f.1, w: &mut f.2, v: &mut f.3, gy: &mut f.4, cost: 0.0, rows: 0 };
            assert!(eiv.block_normal_equations(block, &x, &y, &mut folded).unwrap());
            assert_eq!(folded.rows, sr);
            close(folded.cost, sc, sc, "cost");
            for i in 0..PARAMS {
                close(f.1[i], s.1[i], libm::sqrt(s.0[i][i] * sc), "g_x");
                for j in i..PARAMS {
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
}
