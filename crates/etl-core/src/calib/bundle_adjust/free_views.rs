//! The bundle adjustment with free-pose views besides the stage views (Eq. 24b-24d of
//! docs/METHOD.md, "Free-pose views").
//!
//! A stage view j is a board at the stage position Z_W of the view, seen through the one
//! camera pose (R, T) of the model. A free-pose view f is a planar board (its points
//! P_fi = (X, Y, 0) in its own frame) seen at current E_f in a pose of its own,
//! omega_f (Rodrigues) and t_f (mm, board -> camera): the camera point is
//!
//! ```text
//! (24b)  p_c = R(omega_f) P_fi + t_f - dz(E_f) e_z,    dz(E) = dz1 E + dz2 E^2 (moving centre)
//! ```
//!
//! and the pixel the model's intrinsics at E_f (fx(E_f), fy(E_f), u0(E_f), v0(E_f), the
//! distortion of Eq. 18). The model's numbers x are shared by all views; each free view's
//! six pose numbers are its own. The paper's estimator minimises
//!
//! ```text
//! (24c)  sum_j sum_i |obs_ji - proj(x; P_ji, E_j)|^2 + sum_f sum_i |obs_fi - proj(x, omega_f, t_f; P_fi, E_f)|^2
//! ```
//!
//! and the errors-in-variables estimator, with the stage views' corrections (dZ_j, dE_j)
//! as in [`super`] and a current correction dE_f per free view (its stage position is
//! not used: the pose is free),
//!
//! ```text
//! (24d)  sum_j [ sum_i |obs_ji - proj(x; P_ji + dZ_j e_z, E_j + dE_j)|^2 / sigma_px^2 + dZ_j^2 / sigma_Z^2 + dE_j^2 / sigma_E^2 ]
//!      + sum_f [ sum_i |obs_fi - proj(x, omega_f, t_f; P_fi, E_f + dE_f)|^2 / sigma_px^2 + dE_f^2 / sigma_E^2 ]
//! ```
//!
//! Each view's unknowns couple only to x, so they are one block of the block solver
//! ([`crate::lm::solve_blocks`]) and eliminated by the Schur complement:
//! y_j = (dZ_j, dE_j, 0, 0, 0, 0, 0) for a stage view, y_f = (omega_f, t_f, dE_f) for a free
//! one ([`JOINT_BLOCK`] = 7 numbers each). The numbers a view does not have (the stage
//! view's last five; every correction under the paper's estimator) are held at zero by
//! unit prior rows y_k = 0: their gradient and their coupling to x are zero, so they never
//! move, and each adds one row and one unknown, which leaves the degrees of freedom as
//! they are. The covariance of x is that of the free poses (and corrections) marginalised,
//! (U - sum_b W_b V_b^-1 W_b^T)^-1:
//!
//! - errors-in-variables: of the normalised rows, unscaled (as in [`super`]);
//! - paper, with [`super::BundleAdjustOptions::input_noise`]: the first-order covariance
//!   of the whole noise model ([`super::input_noise`]) with the free poses eliminated.
//!   With S the Schur complement, B the pixels' derivatives with respect to the recorded
//!   inputs (a stage view's Z_W and E, a free view's E) and Q their variances,
//!
//! ```text
//! (24e)  C = sigma_px^2 S^-1 + S^-1 M S^-1,
//!        M = sum_j W_j Q W_j^T + sum_f sigma_E^2 m_f m_f^T,   W_j = J_xj^T B_j,
//!        m_f = J_xf^T b_f - W_f V_f^-1 J_pf^T b_f              (W_f = J_xf^T J_pf, V_f = J_pf^T J_pf)
//! ```
//!
//!   and sigma_px^2 = (|r|^2 - sum tr(Q B^T B) + tr(S^-1 M) + sum_f sigma_E^2 d_f^T V_f^-1
//!   d_f) / (2 n - p - 6 F), d_f = J_pf^T b_f (the residuals' share of the input errors
//!   taken out, the hat matrix now that of x and the poses together).
//!
//! Preconditions beyond [`super::bundle_adjust`]'s: every free view with at least
//! [`MIN_FREE_VIEW_POINTS`] points, all on Z = 0 of its board frame, finite; no robust
//! loss (its weights would need a reference pose per view).

use super::normal::{fold_block, fold_view, ViewNormal};
use super::problems::{hold_rows, AtZ};
use super::scratch::{Prepare, JOINT_BLOCK};
#[cfg(test)]
use super::Estimator;
use super::{BundleAdjustOptions, JointScratch};
use crate::calib::basis::Basis;
use crate::calib::jacobian::Projector;
use crate::calib::observations::{Point, View};
use crate::calib::params::{MAX_REDUCED, R_POSE};
use crate::error::{all_finite, Error, Result};
use crate::lm::{BlockNormal, BlockProblem, BlockRowSink, BlockStorage};

/// A planar board seen at one current in a pose of its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeView<'a> {
    /// Compensated lens current E_com, mA.
    pub e_com_ma: f64,
    /// The view's points: `world_mm` in the board's own frame, Z = 0.
    pub points: &'a [Point],
    /// Start of the board pose: Rodrigues vector, board -> camera (e.g. from
    /// [`crate::pnp::solve_pnp`] with the start model at `e_com_ma`).
    pub rotation_rodrigues: [f64; 3],
    /// Start of the board pose: translation board -> camera, mm (the model's T before the
    /// moving centre's shift, as [`crate::pnp::BoardPose`]).
    pub translation_mm: [f64; 3],
}

/// Fewest points a free-pose view needs (its 6 pose numbers, and a planar PnP start).
pub const MIN_FREE_VIEW_POINTS: usize = 4;

/// Checks the free views' own preconditions (module docs).
pub(super) fn validate_free(free: &[FreeView<'_>]) -> Result<()> {
    for f in free {
        if !f.e_com_ma.is_finite() {
            return Err(Error::NotFinite { what: "free view current e_com_ma" });
        }
        all_finite(&f.rotation_rodrigues, "free view rotation")?;
        all_finite(&f.translation_mm, "free view translation")?;
        if f.points.len() < MIN_FREE_VIEW_POINTS {
            return Err(Error::TooFew {
                what: "points of a free-pose view",
                needed: MIN_FREE_VIEW_POINTS,
                got: f.points.len(),
            });
        }
        for p in f.points {
            all_finite(&p.world_mm, "world_mm of a point")?;
            all_finite(&p.pixel, "pixel of a point")?;
            if p.world_mm[2] != 0.0 {
                return Err(Error::InvalidArgument { what: "free view points must lie on Z = 0 of the board frame" });
            }
        }
    }
    Ok(())
}

/// The errors-in-variables weights of [`Joint`]: pixel noise and priors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Priors {
    pub sigma_px: f64,
    pub sigma_z_mm: f64,
    pub sigma_e_ma: f64,
}

/// Problem (24c) (`priors` `None`) or (24d) over the internal parameters z.
pub(super) struct Joint<'a, 'b, const N: usize, const O: usize, const P: usize> {
    pub stage: &'a [View<'b>],
    pub free: &'a [FreeView<'b>],
    pub basis: &'a Basis,
    pub x0: [f64; N],
    pub options: &'a BundleAdjustOptions,
    pub priors: Option<Priors>,
    /// The quantities at the last z evaluated; `None` to start with.
    pub at: Option<AtZ<N>>,
}

/// What a block's rows need at (z, y): the projector (a free view's with its pose), the
/// points, how a point moves (a stage view's dZ), the current, the chain matrices of x and
/// of the block's parameters, and the rows' weight 1 / sigma_px.
pub(super) struct BlockSetup<'p, const N: usize> {
    pub proj: Projector,
    pub points: &'p [Point],
    pub dz_mm: f64,
    pub e_ma: f64,
    pub c: [[f64; N]; MAX_REDUCED],
    pub cy: [[f64; JOINT_BLOCK]; MAX_REDUCED],
    pub weight: f64,
    /// Which of the block's numbers are real unknowns (the rest held by unit rows), and
    /// the prior standard deviation of each real one (infinite: no prior).
    pub prior_sigma: [Option<f64>; JOINT_BLOCK],
}

impl<'b, const N: usize, const O: usize, const P: usize> Joint<'_, 'b, N, O, P> {
    /// Makes [`Joint::at`] the quantities at the internal parameters `z`.
    pub(super) fn refresh(&mut self, z: &[f64; N]) {
        if !self.at.as_ref().is_some_and(|at| at.is_at(z)) {
            self.at = Some(AtZ::new(self.basis, z));
        }
    }

    /// The setup of block `block` at y (after [`Joint::refresh`]); `chains` also computes
    /// the chain matrices (not needed for a trial cost).
    pub(super) fn setup(&self, block: usize, y: &[f64; JOINT_BLOCK], chains: bool) -> Result<BlockSetup<'b, N>> {
        let at = self.at.as_ref().ok_or(Error::InvalidArgument { what: "joint rows before refresh" })?;
        let weight = self.priors.map_or(1.0, |p| 1.0 / p.sigma_px);
        let mut prior_sigma = [None; JOINT_BLOCK];
        let mut cy = [[0.0; JOINT_BLOCK]; MAX_REDUCED];
        if let Some(view) = self.stage.get(block) {
            let (dz_mm, de_ma) = if self.priors.is_some() { (y[0], y[1]) } else { (0.0, 0.0) };
            let e_ma = view.e_com_ma + de_ma;
            if let Some(p) = self.priors {
                prior_sigma[0] = Some(p.sigma_z_mm);
                prior_sigma[1] = Some(p.sigma_e_ma);
                for (cyr, s) in cy.iter_mut().zip(at.proj.shift_chain(e_ma).iter()) {
                    cyr[0] = s[0];
                    cyr[1] = s[1];
                }
            }
            let c = if chains { at.proj.chain_in(e_ma, &at.dxdz)? } else { [[0.0; N]; MAX_REDUCED] };
            return Ok(BlockSetup { proj: at.proj, points: view.points, dz_mm, e_ma, c, cy, weight, prior_sigma });
        }
        let f = self
            .free
            .get(block.wrapping_sub(self.stage.len()))
            .ok_or(Error::InvalidArgument { what: "block index out of range" })?;
        let mut model = *at.proj.model();
        model.rotation_rodrigues = [y[0], y[1], y[2]];
        model.translation_mm = [y[3], y[4], y[5]];
        let proj = Projector::new(&model);
        let de_ma = if self.priors.is_some() { y[6] } else { 0.0 };
        let e_ma = f.e_com_ma + de_ma;
        for (k, s) in prior_sigma.iter_mut().enumerate().take(R_POSE.len) {
            *s = Some(f64::INFINITY);
            if let Some(row) = cy.get_mut(R_POSE.at(k)).and_then(|r| r.get_mut(k)) {
                *row = 1.0;
            }
        }
        if let Some(p) = self.priors {
            prior_sigma[6] = Some(p.sigma_e_ma);
            for (cyr, s) in cy.iter_mut().zip(proj.shift_chain(e_ma).iter()) {
                cyr[6] = s[1];
            }
        }
        let c = if chains { proj.board_chain_in(e_ma, &at.dxdz)? } else { [[0.0; N]; MAX_REDUCED] };
        Ok(BlockSetup { proj, points: f.points, dz_mm: 0.0, e_ma, c, cy, weight, prior_sigma })
    }

    /// The prior rows of a block: y_k / sigma_k for its real unknowns with a prior, y_k for
    /// the unused ones; and (once) the hold rows.
    fn prior_rows(
        &self,
        block: usize,
        setup: &BlockSetup<'_, N>,
        y: &[f64; JOINT_BLOCK],
        sink: &mut dyn BlockRowSink<N, JOINT_BLOCK>,
    ) -> Result<()> {
        let zero = [0.0; N];
        for (k, (&yk, sigma)) in y.iter().zip(setup.prior_sigma.iter()).enumerate() {
            let w = match sigma {
                Some(s) if s.is_finite() => 1.0 / s,
                Some(_) => continue,
                None => 1.0,
            };
            let mut jy = [0.0; JOINT_BLOCK];
            if let Some(slot) = jy.get_mut(k) {
                *slot = w;
            }
            sink.push(yk * w, &zero, &jy);
        }
        if block == 0 {
            let at = self.at.as_ref().ok_or(Error::InvalidArgument { what: "joint rows before refresh" })?;
            hold_rows(self.options.hold, &at.x, &self.x0, &at.dxdz, |r, j| sink.push(r, j, &[0.0; JOINT_BLOCK]));
        }
        Ok(())
    }
}

/// The start of every block's parameters in `scratch` (stage views first: zero; then the
/// free views' poses and a zero current correction), sized for `N` shared numbers.
pub(super) fn prepare_joint<const N: usize>(free: &[FreeView<'_>], scratch: &mut [JointScratch]) -> Result<()>
where
    JointScratch: BlockStorage<N, JOINT_BLOCK> + Prepare<N>,
{
    let stage = scratch.len().saturating_sub(free.len());
    for (b, s) in scratch.iter_mut().enumerate() {
        <JointScratch as Prepare<N>>::prepare(s);
        let blk = BlockStorage::<N, JOINT_BLOCK>::block_mut(s)
            .ok_or(Error::InvalidArgument { what: "joint scratch does not hold the layout's size" })?;
        if let Some(f) = b.checked_sub(stage).and_then(|k| free.get(k)) {
            let [r0, r1, r2] = f.rotation_rodrigues;
            let [t0, t1, t2] = f.translation_mm;
            blk.set_y([r0, r1, r2, t0, t1, t2, 0.0]);
        }
    }
    Ok(())
}

/// A point's world position under a block's setup (a stage view's dZ applied).
fn shifted(p: &Point, dz_mm: f64) -> [f64; 3] {
    [p.world_mm[0], p.world_mm[1], p.world_mm[2] + dz_mm]
}

impl<const N: usize, const O: usize, const P: usize> BlockProblem<N, JOINT_BLOCK> for Joint<'_, '_, N, O, P> {
    fn block_count(&self) -> usize {
        self.stage.len() + self.free.len()
    }

    fn eval_block(
        &mut self,
        block: usize,
        z: &[f64; N],
        y: &[f64; JOINT_BLOCK],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<N, JOINT_BLOCK>,
    ) -> Result<()> {
        self.refresh(z);
        let s = self.setup(block, y, jacobian)?;
        for p in s.points {
            let pr = s.proj.project_reduced(shifted(p, s.dz_mm), s.e_ma, jacobian)?;
            for row in 0..2 {
                let r = s.weight * (pr.pixel[row] - p.pixel[row]);
                let (mut jx, mut jy) = ([0.0; N], [0.0; JOINT_BLOCK]);
                if jacobian {
                    for ((&d, cr), cyr) in pr.d_reduced[row].iter().zip(s.c.iter()).zip(s.cy.iter()) {
                        jx.iter_mut().zip(cr.iter()).for_each(|(j, &c)| *j += s.weight * d * c);
                        jy.iter_mut().zip(cyr.iter()).for_each(|(j, &c)| *j += s.weight * d * c);
                    }
                }
                sink.push(r, &jx, &jy);
            }
        }
        self.prior_rows(block, &s, y, sink)
    }

    /// The rows of [`Joint::eval_block`] folded through the per-view variables:
    /// J_x = J_reduced C, J_y = J_reduced C_y (as [`super::problems`] does for the
    /// errors-in-variables blocks).
    fn block_normal_equations(
        &mut self,
        block: usize,
        z: &[f64; N],
        y: &[f64; JOINT_BLOCK],
        out: &mut BlockNormal<'_, N, JOINT_BLOCK>,
    ) -> Result<bool> {
        self.refresh(z);
        let s = self.setup(block, y, true)?;
        let (a, g, cost) = reduced_normal::<N, O, P>(&s)?;
        out.cost += cost;
        out.rows += 2 * s.points.len();
        fold_view(O + 2, &a, &g, &s.c, out.u, out.gx);
        fold_block(&a, &g, &s.c, &s.cy, out.w, out.v, out.gy);
        self.prior_rows(block, &s, y, out)?;
        Ok(true)
    }
}

/// A block's reduced normal equations (a, g) over its points, weighted, and its cost.
pub(super) fn reduced_normal<const N: usize, const O: usize, const P: usize>(
    s: &BlockSetup<'_, N>,
) -> Result<([[f64; MAX_REDUCED]; MAX_REDUCED], [f64; MAX_REDUCED], f64)> {
    let mut normal = ViewNormal::<O, P>::new();
    let mut cost = 0.0;
    for p in s.points {
        let projected = s.proj.project_reduced(shifted(p, s.dz_mm), s.e_ma, true);
        let pr = projected.as_ref().map_err(|e| *e)?;
        let r = [s.weight * (pr.pixel[0] - p.pixel[0]), s.weight * (pr.pixel[1] - p.pixel[1])];
        cost += r[0] * r[0] + r[1] * r[1];
        normal.add_point(&pr.d_reduced, s.weight, r);
    }
    let (a, g) = normal.expand();
    Ok((a, g, cost))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::params::Layout;
    use crate::model::{CameraModel, MovingCentre};

    /// The paper rig with a moving centre, three stage views and two tilted free views,
    /// with deterministic pixel offsets.
    fn scene(truth: &CameraModel) -> ([[Point; 12]; 3], [[Point; 12]; 2]) {
        let mut stage = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 3];
        let mut free = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 2];
        let currents = [90.0, 150.0, 225.0];
        for (k, view) in stage.iter_mut().enumerate() {
            for (i, p) in view.iter_mut().enumerate() {
                let w = [1.5 * (i % 4) as f64 + 3.0, 1.5 * (i / 4) as f64 + 2.0, 40.0 - 15.0 * k as f64];
                let q = truth.project(w, currents[k]).unwrap();
                let d = 0.3 * ((i * 7 + k * 3) % 5) as f64 - 0.6;
                *p = Point { world_mm: w, pixel: [q[0] + d, q[1] - 0.5 * d] };
            }
        }
        for (f, view) in free.iter_mut().enumerate() {
            let mut m = *truth;
            m.rotation_rodrigues = FREE_POSES[f].0;
            m.translation_mm = FREE_POSES[f].1;
            for (i, p) in view.iter_mut().enumerate() {
                let b = [1.5 * (i % 4) as f64, 1.5 * (i / 4) as f64, 0.0];
                let q = m.project(b, FREE_CURRENTS[f]).unwrap();
                let d = 0.2 * ((i * 5 + f) % 3) as f64 - 0.2;
                *p = Point { world_mm: b, pixel: [q[0] - d, q[1] + d] };
            }
        }
        (stage, free)
    }

    const FREE_POSES: [([f64; 3], [f64; 3]); 2] =
        [([0.2, -0.1, 0.05], [-3.0, -2.0, 80.0]), ([-0.15, 0.2, 0.0], [-2.0, -3.0, 70.0])];
    const FREE_CURRENTS: [f64; 2] = [100.0, 200.0];

    fn moving_truth() -> CameraModel {
        let mut m = CameraModel::paper_rig();
        m.centre = Some(MovingCentre { dz_mm: [0.01, -2e-5], principal_point_slope_px: [0.02, -0.01] });
        m
    }

    /// The folded blocks of the joint problem equal its streamed rows, for the paper's
    /// rows and the errors-in-variables ones, stage and free blocks.
    fn folded_equals_streamed<const N: usize, const O: usize, const P: usize>(truth: &CameraModel) {
        let (stage_pts, free_pts) = scene(truth);
        let stage: [View; 3] =
            core::array::from_fn(|k| View { e_com_ma: [90.0, 150.0, 225.0][k], points: &stage_pts[k] });
        let free: [FreeView; 2] = core::array::from_fn(|f| FreeView {
            e_com_ma: FREE_CURRENTS[f],
            points: &free_pts[f],
            rotation_rodrigues: FREE_POSES[f].0,
            translation_mm: FREE_POSES[f].1,
        });
        let layout = truth.layout();
        let options = BundleAdjustOptions { hold: layout.a0_mask(), ..Default::default() };
        let basis = Basis::for_views(&stage, layout);
        let mut x = crate::calib::jacobian::to_params_n::<N>(truth).unwrap();
        x[7] *= 1.01;
        let z = basis.to_internal(&x);
        let priors = Priors { sigma_px: 0.3, sigma_z_mm: 0.01, sigma_e_ma: 0.4 };
        for priors in [None, Some(priors)] {
            let mut joint = Joint::<N, O, P> {
                stage: &stage,
                free: &free,
                basis: &basis,
                x0: x,
                options: &options,
                priors,
                at: None,
            };
            for block in 0..5 {
                let y = if block < 3 {
                    [0.004, -0.3, 0.0, 0.0, 0.0, 0.0, 0.0]
                } else {
                    let (r, t) = FREE_POSES[block - 3];
                    [r[0] + 1e-3, r[1], r[2], t[0], t[1] + 0.1, t[2], 0.2]
                };
                let mut s = ([[0.0; N]; N], [0.0; N], [[0.0; 7]; N], [[0.0; 7]; 7], [0.0; 7]);
                let mut f = s;
                let mut streamed = BlockNormal {
                    u: &mut s.0,
                    gx: &mut s.1,
                    w: &mut s.2,
                    v: &mut s.3,
                    gy: &mut s.4,
                    cost: 0.0,
                    rows: 0,
                };
                joint.eval_block(block, &z, &y, true, &mut streamed).unwrap();
                let (sc, sr) = (streamed.cost, streamed.rows);
                let mut folded = BlockNormal {
                    u: &mut f.0,
                    gx: &mut f.1,
                    w: &mut f.2,
                    v: &mut f.3,
                    gy: &mut f.4,
                    cost: 0.0,
                    rows: 0,
                };
                assert!(joint.block_normal_equations(block, &z, &y, &mut folded).unwrap());
                assert_eq!(folded.rows, sr);
                let close = |a: f64, b: f64, scale: f64, what: &str| {
                    assert!((a - b).abs() <= 1e-9 * scale.max(1e-12), "block {block} {what}: {a} vs {b}")
                };
                close(folded.cost, sc, sc, "cost");
                for i in 0..N {
                    close(f.1[i], s.1[i], libm::sqrt(s.0[i][i] * sc), "g_x");
                    for j in i..N {
                        close(f.0[i][j], s.0[i][j], libm::sqrt(s.0[i][i] * s.0[j][j]), "U");
                    }
                    for k in 0..7 {
                        close(f.2[i][k], s.2[i][k], libm::sqrt(s.0[i][i] * s.3[k][k]), "W");
                    }
                }
                for k in 0..7 {
                    close(f.4[k], s.4[k], libm::sqrt(s.3[k][k] * sc), "g_y");
                    for l in k..7 {
                        close(f.3[k][l], s.3[k][l], libm::sqrt(s.3[k][k] * s.3[l][l]), "V");
                    }
                }
            }
        }
    }

    #[test]
    fn folded_joint_blocks_equal_the_streamed_rows() {
        assert_eq!(Layout::of(&moving_truth()).len(), 29);
        folded_equals_streamed::<29, 11, 12>(&moving_truth());
        folded_equals_streamed::<25, 11, 12>(&CameraModel::paper_rig());
    }

    /// Noise-free views of a moving-centre truth, the solve started away from it: the
    /// joint solve returns the truth (dz1, dz2, u1, v1 among its numbers) and the poses.
    #[test]
    fn noise_free_views_give_back_the_truth() {
        let truth = moving_truth();
        let mut stage_pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 30]; 4];
        let currents = [80.0, 120.0, 170.0, 225.0];
        for (k, view) in stage_pts.iter_mut().enumerate() {
            for (i, p) in view.iter_mut().enumerate() {
                let w = [1.0 * (i % 6) as f64 - 1.0, 1.0 * (i / 6) as f64 - 1.0, 45.0 - 12.0 * k as f64];
                *p = Point { world_mm: w, pixel: truth.project(w, currents[k]).unwrap() };
            }
        }
        let mut free_pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 30]; 8];
        let mut poses = [([0.0; 3], [0.0; 3]); 8];
        for (f, view) in free_pts.iter_mut().enumerate() {
            let sign = if f % 2 == 0 { 1.0 } else { -1.0 };
            poses[f] = ([0.3 * sign, 0.2 * (f % 3) as f64 - 0.2, 0.1], [-2.5, -2.0, 60.0 + 8.0 * (f % 4) as f64]);
            let mut m = truth;
            (m.rotation_rodrigues, m.translation_mm) = poses[f];
            for (i, p) in view.iter_mut().enumerate() {
                let b = [1.0 * (i % 6) as f64, 1.0 * (i / 6) as f64, 0.0];
                *p = Point { world_mm: b, pixel: m.project(b, currents[f % 4]).unwrap() };
            }
        }
        let stage: [View; 4] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &stage_pts[k] });
        let free: [FreeView; 8] = core::array::from_fn(|f| FreeView {
            e_com_ma: currents[f % 4],
            points: &free_pts[f],
            rotation_rodrigues: [poses[f].0[0] + 0.01, poses[f].0[1], poses[f].0[2]],
            translation_mm: [poses[f].1[0], poses[f].1[1] + 0.2, poses[f].1[2] - 0.5],
        });
        let mut start = truth;
        start.centre = Some(MovingCentre { dz_mm: [0.0, 0.0], principal_point_slope_px: [0.0, 0.0] });
        let mut scratch = [JointScratch::ZERO; 12];
        for estimator in [Estimator::Paper, Estimator::Eiv { sigma_z_mm: 0.01, sigma_e_ma: 0.4, sigma_px: Some(0.1) }] {
            let options = BundleAdjustOptions { estimator, ..Default::default() };
            let report = super::super::bundle_adjust_free_views(&stage, &free, &start, &options, &mut scratch).unwrap();
            let c = report.model.centre.unwrap();
            assert!((c.dz_mm[0] - 0.01).abs() < 1e-6 && (c.dz_mm[1] + 2e-5).abs() < 1e-9, "{c:?}");
            assert!((c.principal_point_slope_px[0] - 0.02).abs() < 1e-6, "{c:?}");
            assert!(report.rms_px < 1e-6, "{}", report.rms_px);
            let (r, t, _) = scratch[4].board_pose();
            assert!((r[0] - poses[0].0[0]).abs() < 1e-8 && (t[2] - poses[0].1[2]).abs() < 1e-6, "{r:?} {t:?}");
        }
    }
}
