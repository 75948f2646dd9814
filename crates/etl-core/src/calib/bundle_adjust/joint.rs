//! [`bundle_adjust_free_views`]: the bundle adjustment of the stage views together with
//! free-pose views (equations and covariance: [`super::free_views`]).

use super::free_views::{prepare_joint, reduced_normal, validate_free, FreeView, Joint, Priors};
use super::input_noise::{product, symmetric};
use super::normal::fold_block;
use super::scratch::{Prepare, JOINT_BLOCK};
use super::{report_of, unscaled, BundleAdjustOptions, BundleAdjustReport, Estimator, InputNoise, JointScratch};
use super::{SIGMA_ROUNDS, SIGMA_RTOL};
use crate::calib::basis::Basis;
use crate::calib::dispatch::with_layout;
use crate::calib::jacobian::to_params_n;
use crate::calib::observations::{distinct_currents, point_count, validate, View};
use crate::calib::params::R_POSE;
use crate::error::{Error, Result};
use crate::linalg::cholesky::psd_inverse;
use crate::lm::{self, BlockStorage};
use crate::model::CameraModel;

/// Number of [`JointScratch`] elements [`bundle_adjust_free_views`] needs: one per view,
/// stage and free.
pub const fn bundle_adjust_free_views_scratch(stage_views: usize, free_views: usize) -> usize {
    stage_views + free_views
}

/// Points of the free views.
fn free_point_count(free: &[FreeView<'_>]) -> usize {
    free.iter().map(|f| f.points.len()).sum()
}

/// The preconditions of [`bundle_adjust_free_views`].
fn check_joint_input(
    stage: &[View<'_>],
    free: &[FreeView<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &[JointScratch],
) -> Result<()> {
    validate(stage)?;
    validate_free(free)?;
    init.validate()?;
    let nc = distinct_currents(stage);
    if nc < 3 {
        return Err(Error::TooFew { what: "distinct currents (Appendix I)", needed: 3, got: nc });
    }
    if options.robust.is_some() {
        return Err(Error::InvalidArgument { what: "a robust loss with free-pose views (not supported)" });
    }
    let params = init.layout().len() + R_POSE.len * free.len();
    let n = point_count(stage) + free_point_count(free);
    if 2 * n < params + 1 {
        return Err(Error::TooFew { what: "points for bundle adjustment", needed: params / 2 + 1, got: n });
    }
    if !options.hold.fits(init.layout().len()) {
        return Err(Error::InvalidArgument { what: "hold mask names a number past the model's layout" });
    }
    let needed = bundle_adjust_free_views_scratch(stage.len(), free.len());
    if scratch.len() < needed {
        return Err(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: scratch.len() });
    }
    Ok(())
}

/// Refines `init` over the stage views and the free-pose views together (Eq. 24c, or
/// errors-in-variables Eq. 24d; [`super::free_views`]), in `init`'s layout. The model's
/// numbers (a moving centre's dz1, dz2, u1, v1 among them) are shared by all views; each
/// free view's board pose is its own unknown, started at its [`FreeView`] pose.
///
/// `scratch` needs [`bundle_adjust_free_views_scratch`] elements: on return, element j <
/// `stage.len()` holds stage view j's correction ([`JointScratch::correction`], zeros for
/// the paper's estimator), element `stage.len() + f` free view f's pose and current
/// correction ([`JointScratch::board_pose`]). The report's covariance is that of the
/// model's numbers with the poses and corrections marginalised (Eq. 24e for the paper's
/// estimator); its `rms_px` is over the points of all views.
///
/// Preconditions (typed errors): those of [`super::bundle_adjust`] on the stage views
/// (3 distinct currents among them); the free views' ([`super::free_views`]); no robust
/// loss; more residuals than unknowns (the numbers and 6 per free view).
pub fn bundle_adjust_free_views(
    stage: &[View<'_>],
    free: &[FreeView<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &mut [JointScratch],
) -> Result<BundleAdjustReport> {
    check_joint_input(stage, free, init, options, scratch)?;
    let layout = init.layout();
    with_layout!(layout, N, O, P, joint_n::<N, O, P>(stage, free, init, options, scratch))
}

/// [`bundle_adjust_free_views`] for a layout of `N` numbers.
fn joint_n<const N: usize, const O: usize, const P: usize>(
    stage: &[View<'_>],
    free: &[FreeView<'_>],
    init: &CameraModel,
    options: &BundleAdjustOptions,
    scratch: &mut [JointScratch],
) -> Result<BundleAdjustReport>
where
    JointScratch: BlockStorage<N, JOINT_BLOCK> + Prepare<N>,
{
    let needed = bundle_adjust_free_views_scratch(stage.len(), free.len());
    let scratch =
        scratch.get_mut(..needed).ok_or(Error::BufferTooSmall { what: "bundle adjustment scratch", needed, got: 0 })?;
    prepare_joint::<N>(free, scratch)?;
    let layout = init.layout();
    let x0 = to_params_n::<N>(init)?;
    let basis = &Basis::for_views(stage, layout);
    let z0 = basis.to_internal(&x0);
    let mut problem = Joint::<N, O, P> { stage, free, basis, x0, options, priors: None, at: None };
    let initial_rms_px = joint_rms(&mut problem, &z0, scratch)?;
    let plain = lm::solve_blocks(&mut problem, z0, &options.lm, &mut *scratch)?;
    let sigma_plain = libm::sqrt(plain.sigma2);
    let (sigma_z_mm, sigma_e_ma, sigma_px) = match options.estimator {
        Estimator::Paper => return paper_joint_report(&mut problem, &plain, initial_rms_px, scratch),
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px } => {
            (sigma_z_mm, sigma_e_ma, sigma_px.unwrap_or(sigma_plain))
        }
    };
    if !(sigma_z_mm > 0.0 && sigma_e_ma > 0.0 && sigma_px > 0.0) {
        return Err(Error::InvalidArgument { what: "errors-in-variables standard deviations must be positive" });
    }
    let estimate_sigma = matches!(options.estimator, Estimator::Eiv { sigma_px: None, .. });
    let (mut sigma_px, mut start, mut round) = (sigma_px, plain.x, 0);
    let solved = loop {
        problem.priors = Some(Priors { sigma_px, sigma_z_mm, sigma_e_ma });
        let solved = lm::solve_blocks(&mut problem, start, &options.lm, &mut *scratch)?;
        round += 1;
        if !estimate_sigma || round >= SIGMA_ROUNDS {
            break solved;
        }
        let rms = joint_rms(&mut problem, &solved.x, scratch)?;
        let next = libm::sqrt(rms * rms * joint_points(&problem) as f64 / joint_dof(&problem) as f64);
        if !(next > 0.0) || (next / sigma_px - 1.0).abs() <= SIGMA_RTOL {
            break solved;
        }
        (sigma_px, start) = (next, solved.x);
    };
    let mut report = report_of(stage, basis, &unscaled(solved), initial_rms_px, sigma_px, None)?;
    report.rms_px = joint_rms(&mut problem, &solved.x, scratch)?;
    Ok(report)
}

/// Points of all views of the problem.
fn joint_points<const N: usize, const O: usize, const P: usize>(problem: &Joint<'_, '_, N, O, P>) -> usize {
    point_count(problem.stage) + free_point_count(problem.free)
}

/// Degrees of freedom of the residuals: 2 n - N - 6 F (the corrections, mostly fixed by
/// their priors, not counted, as in [`super::bundle_adjust`]), at least 1.
fn joint_dof<const N: usize, const O: usize, const P: usize>(problem: &Joint<'_, '_, N, O, P>) -> usize {
    (2 * joint_points(problem)).saturating_sub(N + R_POSE.len * problem.free.len()).max(1)
}

/// RMS reprojection error, px, over every view's points at the internal parameters `z`
/// and the block parameters of `scratch` (corrections and poses).
fn joint_rms<const N: usize, const O: usize, const P: usize>(
    problem: &mut Joint<'_, '_, N, O, P>,
    z: &[f64; N],
    scratch: &[JointScratch],
) -> Result<f64>
where
    JointScratch: BlockStorage<N, JOINT_BLOCK>,
{
    problem.refresh(z);
    let (mut s, mut n) = (0.0, 0usize);
    for (b, blk) in scratch.iter().enumerate() {
        let y = BlockStorage::<N, JOINT_BLOCK>::block(blk).map_or([0.0; JOINT_BLOCK], |k| *k.y());
        let setup = problem.setup(b, &y, false)?;
        for p in setup.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + setup.dz_mm];
            let pr = setup.proj.project_reduced(w, setup.e_ma, false)?;
            s += (pr.pixel[0] - p.pixel[0]) * (pr.pixel[0] - p.pixel[0])
                + (pr.pixel[1] - p.pixel[1]) * (pr.pixel[1] - p.pixel[1]);
            n += 1;
        }
    }
    Ok(if n > 0 { libm::sqrt(s / n as f64) } else { 0.0 })
}

/// The paper estimator's report of the joint solve `plain`: its covariance under
/// [`BundleAdjustOptions::input_noise`] (Eq. 24e), or the pixel noise's alone.
fn paper_joint_report<const N: usize, const O: usize, const P: usize>(
    problem: &mut Joint<'_, '_, N, O, P>,
    plain: &lm::Report<N>,
    initial_rms_px: f64,
    scratch: &[JointScratch],
) -> Result<BundleAdjustReport>
where
    JointScratch: BlockStorage<N, JOINT_BLOCK>,
{
    let mut solved = *plain;
    let mut sigma_px = libm::sqrt(plain.sigma2);
    if let Some(noise) = &problem.options.input_noise {
        (solved.covariance, sigma_px) = joint_input_noise(problem, plain, scratch, noise)?;
    }
    let mut report = report_of(problem.stage, problem.basis, &solved, initial_rms_px, sigma_px, None)?;
    report.rms_px = joint_rms(problem, &plain.x, scratch)?;
    Ok(report)
}

/// Eq. 24e in the internal parameters z: the covariance of the paper estimator's joint
/// solve `solved` under the input noise `noise`, and the pixel noise it assumes.
fn joint_input_noise<const N: usize, const O: usize, const P: usize>(
    problem: &mut Joint<'_, '_, N, O, P>,
    solved: &lm::Report<N>,
    scratch: &[JointScratch],
    noise: &InputNoise,
) -> Result<([[f64; N]; N], f64)>
where
    JointScratch: BlockStorage<N, JOINT_BLOCK>,
{
    let spreads = [noise.sigma_z_mm, noise.sigma_e_ma];
    if !spreads.iter().chain(noise.sigma_px.as_ref()).all(|s| s.is_finite() && *s > 0.0) {
        return Err(Error::InvalidArgument { what: "input noise standard deviations must be positive and finite" });
    }
    let s2 = solved.sigma2;
    if !(s2 > 0.0 && s2.is_finite()) {
        return Ok((solved.covariance, 0.0));
    }
    let s_inv = solved.covariance.map(|row| row.map(|c| c / s2));
    let q = [spreads[0] * spreads[0], spreads[1] * spreads[1]];
    let mut acc = NoiseTerms { m: [[0.0; N]; N], rss: 0.0, input_share: 0.0, pose_share: 0.0 };
    problem.refresh(&solved.x);
    for (b, blk) in scratch.iter().enumerate() {
        let y = BlockStorage::<N, JOINT_BLOCK>::block(blk).map_or([0.0; JOINT_BLOCK], |k| *k.y());
        add_view_noise::<N, O, P>(problem, b, &y, q, problem.options.lm.rank_tolerance, &mut acc)?;
    }
    let hm = product(&s_inv, &acc.m);
    let trace: f64 = hm.iter().enumerate().filter_map(|(i, row)| row.get(i)).sum();
    let explained = acc.input_share - trace - acc.pose_share;
    let sigma2_px = match noise.sigma_px {
        Some(s) => s * s,
        None => ((acc.rss - explained) / joint_dof(problem) as f64).max(0.0),
    };
    let mut covariance = product(&hm, &s_inv);
    for (c_row, h_row) in covariance.iter_mut().zip(s_inv.iter()) {
        for (c, &h) in c_row.iter_mut().zip(h_row.iter()) {
            *c += sigma2_px * h;
        }
    }
    // The solver's factor sigma2 is undone: the caller maps the covariance as it is.
    Ok((symmetric(covariance), libm::sqrt(sigma2_px)))
}

/// The sums of Eq. 24e over the views: M, |r|^2, sum tr(Q B^T B) and the free poses'
/// share sum_f sigma_E^2 d_f^T V_f^-1 d_f of the hat matrix's trace.
struct NoiseTerms<const N: usize> {
    m: [[f64; N]; N],
    rss: f64,
    input_share: f64,
    pose_share: f64,
}

/// Adds view `block`'s terms of Eq. 24e (block parameters `y`, variances `q` of Z_W and
/// E) to `acc`.
fn add_view_noise<const N: usize, const O: usize, const P: usize>(
    problem: &Joint<'_, '_, N, O, P>,
    block: usize,
    y: &[f64; JOINT_BLOCK],
    q: [f64; 2],
    tol: f64,
    acc: &mut NoiseTerms<N>,
) -> Result<()> {
    let setup = problem.setup(block, y, true)?;
    let (a, g, cost) = reduced_normal::<N, O, P>(&setup)?;
    acc.rss += cost;
    let shift = setup.proj.shift_chain(setup.e_ma);
    if block < problem.stage.len() {
        // W_j = C^T a S (the Z_W and E columns), diag(S^T a S) = diag(B_j^T B_j).
        let (mut w, mut v, mut gy) = ([[0.0; 2]; N], [[0.0; 2]; 2], [0.0; 2]);
        fold_block(&a, &g, &setup.c, &shift, &mut w, &mut v, &mut gy);
        acc.input_share += q[0] * v[0][0] + q[1] * v[1][1];
        for (k, &qk) in q.iter().enumerate() {
            add_outer(&mut acc.m, qk, |i| w[i][k]);
        }
        return Ok(());
    }
    // The pose columns and the E column: W = [W_f | J_x^T b], V = [[V_f, d], [d^T, b^T b]].
    let mut cy = setup.cy;
    for (cyr, s) in cy.iter_mut().zip(shift.iter()) {
        cyr[6] = s[1];
    }
    let (mut w, mut v, mut gy) = ([[0.0; JOINT_BLOCK]; N], [[0.0; JOINT_BLOCK]; JOINT_BLOCK], [0.0; JOINT_BLOCK]);
    fold_block(&a, &g, &setup.c, &cy, &mut w, &mut v, &mut gy);
    let vf: [[f64; 6]; 6] = core::array::from_fn(|i| core::array::from_fn(|j| v[i][j]));
    let d: [f64; 6] = core::array::from_fn(|i| v[i][6]);
    let (vf_inv, _) = psd_inverse(&vf, tol);
    let vd: [f64; 6] = core::array::from_fn(|i| (0..6).map(|j| vf_inv[i][j] * d[j]).sum());
    acc.input_share += q[1] * v[6][6];
    acc.pose_share += q[1] * d.iter().zip(vd.iter()).map(|(a, b)| a * b).sum::<f64>();
    let m_f: [f64; N] = core::array::from_fn(|i| w[i][6] - (0..6).map(|k| w[i][k] * vd[k]).sum::<f64>());
    add_outer(&mut acc.m, q[1], |i| m_f[i]);
    Ok(())
}

/// m += q c c^T for the vector c(i).
fn add_outer<const N: usize>(m: &mut [[f64; N]; N], q: f64, c: impl Fn(usize) -> f64) {
    for (i, mi) in m.iter_mut().enumerate() {
        let ci = c(i);
        if ci != 0.0 {
            for (j, mij) in mi.iter_mut().enumerate() {
                *mij += q * ci * c(j);
            }
        }
    }
}
