//! The two least-squares problems of the bundle adjustment over the internal parameters z
//! ([`Basis`]): the paper's ([`Plain`], dense LM) and the errors-in-variables one
//! ([`Eiv`], block LM with a view's correction as its block), each with its rows streamed
//! and, faster, folded through the per-view variables ([`super::normal`]).

use super::normal::{fold_block, fold_view, ViewNormal};
use super::{BundleAdjustOptions, RobustLoss};
use crate::calib::basis::Basis;
use crate::calib::jacobian::{from_params, Projector};
use crate::calib::observations::View;
use crate::calib::params::{Layout, ParamMask};
use crate::error::{Error, Result};
use crate::lm::{BlockNormal, BlockProblem, BlockRowSink, NormalEquations, Problem, RowSink};

/// The projector of the parameter vector `x` of `layout`.
pub(super) fn projector<const N: usize>(layout: &Layout, x: &[f64; N]) -> Projector {
    Projector::new(&from_params(layout, x))
}

/// sqrt of the IRLS weight of a point, from its error at the reference estimate.
pub(super) fn robust_scale(
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

/// Weight of a hold row per unit of the held number's magnitude.
const HOLD_WEIGHT: f64 = 1e8;

/// The prior rows that hold the numbers of `mask` at their start values `x0`, in z.
pub(super) fn hold_rows<const N: usize>(
    mask: ParamMask,
    x: &[f64; N],
    x0: &[f64; N],
    dxdz: &[[f64; N]; N],
    mut push: impl FnMut(f64, &[f64; N]),
) {
    for i in mask.indices() {
        let (Some(&xi), Some(&x0i), Some(row)) = (x.get(i), x0.get(i), dxdz.get(i)) else { continue };
        let w = HOLD_WEIGHT / x0i.abs().max(1.0);
        let j: [f64; N] = core::array::from_fn(|k| w * row.get(k).copied().unwrap_or(0.0));
        push((xi - x0i) * w, &j);
    }
}

/// A gradient row with respect to x (the first N of `jx`) as one with respect to z:
/// j_z = j_x dx/dz.
pub(super) fn row_in<const N: usize>(dxdz: &[[f64; N]; N], jx: &[f64]) -> [f64; N] {
    let mut jz = [0.0; N];
    for (&ji, di) in jx.iter().zip(dxdz.iter()) {
        if ji != 0.0 {
            for (jzk, &dik) in jz.iter_mut().zip(di.iter()) {
                *jzk += ji * dik;
            }
        }
    }
    jz
}

/// The paper's problem over the internal parameters z ([`Basis`]).
pub(super) struct Plain<'a, 'b, const N: usize, const O: usize, const P: usize> {
    pub views: &'a [View<'b>],
    pub x0: [f64; N],
    pub options: &'a BundleAdjustOptions,
    pub reference: Option<Projector>,
    /// The solver's parameters: x = to_params(z), dx/dz evaluated at z (basis.rs).
    pub basis: &'a Basis,
}

impl<const N: usize, const O: usize, const P: usize> Problem<N> for Plain<'_, '_, N, O, P> {
    fn eval(&mut self, z: &[f64; N], jacobian: bool, sink: &mut dyn RowSink<N>) -> Result<()> {
        let layout = self.basis.layout();
        let x = &self.basis.to_params(z);
        let proj = projector(&layout, x);
        let dxdz = self.basis.params_jacobian(z);
        for view in self.views {
            for p in view.points {
                let f = robust_scale(self.options.robust, self.reference.as_ref(), p.world_mm, view.e_com_ma, p.pixel)?;
                if !jacobian {
                    // Trial points need only the cost: skip the rows' gradients altogether.
                    let pr = proj.project_reduced(p.world_mm, view.e_com_ma, false)?;
                    sink.push(f * (pr.pixel[0] - p.pixel[0]), &[0.0; N]);
                    sink.push(f * (pr.pixel[1] - p.pixel[1]), &[0.0; N]);
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
        hold_rows(self.options.hold, x, &self.x0, &dxdz, |r, j| sink.push(r, j));
        Ok(())
    }

    /// The same rows as [`Plain::eval`], folded view by view through the per-view
    /// variables: J_view = J_reduced C_view, so J_view^T J_view = C^T (J_reduced^T
    /// J_reduced) C costs 13 x 13 per point instead of 25 x 25.
    fn normal_equations(&mut self, z: &[f64; N], out: &mut NormalEquations<N>) -> Result<bool> {
        let layout = self.basis.layout();
        let x = &self.basis.to_params(z);
        let proj = projector(&layout, x);
        let dxdz = self.basis.params_jacobian(z);
        for view in self.views {
            let mut normal = ViewNormal::<O, P>::new();
            for p in view.points {
                // Read in place: moving the projection (16 + 240 bytes) out of its
                // Result was a memcpy per point.
                let projected = proj.project_reduced(p.world_mm, view.e_com_ma, true);
                let pr = projected.as_ref().map_err(|e| *e)?;
                let f = robust_scale(self.options.robust, self.reference.as_ref(), p.world_mm, view.e_com_ma, p.pixel)?;
                let r = [f * (pr.pixel[0] - p.pixel[0]), f * (pr.pixel[1] - p.pixel[1])];
                out.cost += r[0] * r[0] + r[1] * r[1];
                out.rows += 2;
                normal.add_point(&pr.d_reduced, f, r);
            }
            let (a, g) = normal.expand();
            fold_view(O + 2, &a, &g, &proj.chain_in(view.e_com_ma, &dxdz)?, &mut out.a, &mut out.g);
        }
        hold_rows(self.options.hold, x, &self.x0, &dxdz, |r, j| out.push(r, j));
        Ok(true)
    }
}

/// What every view's rows need at the internal parameters z: dx/dz, x = to_params(z) and
/// x's projector. The solver evaluates all views at one z in turn, so [`Eiv`] keeps them
/// for the last z instead of recomputing them per view (dx/dz alone, 25 x 25, cost about
/// a tenth of the errors-in-variables pipeline when it was recomputed for each of the 15
/// views of the paper rig); the same functions of the same z, so the same numbers.
#[derive(Debug, Clone, Copy)]
pub(super) struct AtZ<const N: usize> {
    z: [f64; N],
    pub dxdz: [[f64; N]; N],
    pub x: [f64; N],
    pub proj: Projector,
}

impl<const N: usize> AtZ<N> {
    /// dx/dz, x and the projector of `basis` at `z`.
    pub(super) fn new(basis: &Basis, z: &[f64; N]) -> Self {
        let x = basis.to_params(z);
        AtZ { z: *z, dxdz: basis.params_jacobian(z), x, proj: projector(&basis.layout(), &x) }
    }

    /// Whether these are the quantities at `z` (bit for bit: -0.0 is not 0.0 here).
    pub(super) fn is_at(&self, z: &[f64; N]) -> bool {
        self.z.iter().zip(z).all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// The errors-in-variables problem: the shared z and, per view, its correction
/// y = (dZ mm, dE mA) with Gaussian priors; rows normalised by their standard deviations.
pub(super) struct Eiv<'a, 'b, const N: usize, const O: usize, const P: usize> {
    pub views: &'a [View<'b>],
    /// The solver's parameters: x = to_params(z), dx/dz evaluated at z (basis.rs).
    pub basis: &'a Basis,
    pub x0: [f64; N],
    pub options: &'a BundleAdjustOptions,
    pub sigma_px: f64,
    pub sigma_z_mm: f64,
    pub sigma_e_ma: f64,
    pub reference: Option<Projector>,
    /// The quantities at the last z evaluated ([`AtZ`]); `None` to start with.
    pub at: Option<AtZ<N>>,
}

impl<const N: usize, const O: usize, const P: usize> BlockProblem<N, 2> for Eiv<'_, '_, N, O, P> {
    fn block_count(&self) -> usize {
        self.views.len()
    }

    fn eval_block(
        &mut self,
        block: usize,
        x: &[f64; N],
        y: &[f64; 2],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<N, 2>,
    ) -> Result<()> {
        self.refresh(x);
        let (view, at) = self.at_view(block)?;
        let is = 1.0 / self.sigma_px;
        let e_ma = view.e_com_ma + y[1];
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + y[0]];
            if !jacobian {
                // Trial points need only the cost: the same pixel without any gradient.
                let pr = at.proj.project_reduced(w, e_ma, false)?;
                let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
                sink.push(f * (pr.pixel[0] - p.pixel[0]), &[0.0; N], &[0.0; 2]);
                sink.push(f * (pr.pixel[1] - p.pixel[1]), &[0.0; N], &[0.0; 2]);
                continue;
            }
            let pr = at.proj.project(w, e_ma, jacobian)?;
            let e = [pr.pixel[0] - p.pixel[0], pr.pixel[1] - p.pixel[1]];
            let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
            for row in 0..2 {
                let mut j = row_in(&at.dxdz, &pr.d_params[row]);
                j.iter_mut().for_each(|v| *v *= f);
                sink.push(f * e[row], &j, &[f * pr.d_z_w[row], f * pr.d_e[row]]);
            }
        }
        self.prior_rows(block, &at.x, &at.dxdz, y, sink);
        Ok(())
    }

    /// The same rows as [`Eiv::eval_block`], folded through the per-view variables:
    /// J_x = J_reduced C and J_y = J_reduced C_y ([`Projector::shift_chain`]), so U, W_b,
    /// V_b all come from one small accumulation per view.
    fn block_normal_equations(
        &mut self,
        block: usize,
        x: &[f64; N],
        y: &[f64; 2],
        out: &mut BlockNormal<'_, N, 2>,
    ) -> Result<bool> {
        self.refresh(x);
        let (view, at) = self.at_view(block)?;
        let (dxdz, proj) = (&at.dxdz, &at.proj);
        let is = 1.0 / self.sigma_px;
        let e_ma = view.e_com_ma + y[1];
        let mut normal = ViewNormal::<O, P>::new();
        for p in view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + y[0]];
            // Read in place, as in Plain::normal_equations.
            let projected = proj.project_reduced(w, e_ma, true);
            let pr = projected.as_ref().map_err(|e| *e)?;
            let f = robust_scale(self.options.robust, self.reference.as_ref(), w, e_ma, p.pixel)? * is;
            let r = [f * (pr.pixel[0] - p.pixel[0]), f * (pr.pixel[1] - p.pixel[1])];
            out.cost += r[0] * r[0] + r[1] * r[1];
            out.rows += 2;
            normal.add_point(&pr.d_reduced, f, r);
        }
        let (a, g) = normal.expand();
        let c = proj.chain_in(e_ma, dxdz)?;
        fold_view(O + 2, &a, &g, &c, out.u, out.gx);
        // W = C^T a C_y, V = C_y^T a C_y, g_y = C_y^T g.
        fold_block(&a, &g, &c, &proj.shift_chain(e_ma), out.w, out.v, out.gy);
        self.prior_rows(block, &at.x, dxdz, y, out);
        Ok(true)
    }
}

impl<'b, const N: usize, const O: usize, const P: usize> Eiv<'_, 'b, N, O, P> {
    /// Makes [`Eiv::at`] the quantities at the internal parameters `z` (computed only when
    /// `z` is not the last one's).
    fn refresh(&mut self, z: &[f64; N]) {
        if !self.at.as_ref().is_some_and(|at| at.is_at(z)) {
            self.at = Some(AtZ::new(self.basis, z));
        }
    }

    /// The view of `block` and what its rows need at the z of the last [`Eiv::refresh`].
    fn at_view(&self, block: usize) -> Result<(&'_ View<'b>, &AtZ<N>)> {
        let view = self.views.get(block).ok_or(Error::InvalidArgument { what: "block index out of range" })?;
        let at = self.at.as_ref().ok_or(Error::InvalidArgument { what: "errors-in-variables rows before refresh" })?;
        Ok((view, at))
    }

    /// The rows of the priors on the view's corrections, and (once) the hold rows.
    fn prior_rows(
        &self,
        block: usize,
        x: &[f64; N],
        dxdz: &[[f64; N]; N],
        y: &[f64; 2],
        sink: &mut dyn BlockRowSink<N, 2>,
    ) {
        let zero = [0.0; N];
        sink.push(y[0] / self.sigma_z_mm, &zero, &[1.0 / self.sigma_z_mm, 0.0]);
        sink.push(y[1] / self.sigma_e_ma, &zero, &[0.0, 1.0 / self.sigma_e_ma]);
        if block == 0 {
            hold_rows(self.options.hold, x, &self.x0, dxdz, |r, j| sink.push(r, j, &[0.0, 0.0]));
        }
    }
}
