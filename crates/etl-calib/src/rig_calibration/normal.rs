//! The joint problem's state and its normal equations (module docs of [`super`]).
//!
//! Camera k's numbers are solved in etl-core's internal parameters z_k ([`Basis`]:
//! Chebyshev coefficients on its own range of settings), mapped to the model's x_k = x(z_k);
//! its rows are accumulated in x and carried to z by D_k = dx/dz: J_z = J_x D_k. View j's
//! corrections y_j = (dZ_j, dE_k1j, dE_k2j, ...) (the stage's, then each camera's that took
//! part, in the order of [`JointProblem::present`]) exist with errors-in-variables only.

use etl_core::calib::basis::Basis;
use etl_core::calib::jacobian::{from_params, to_params, Projector};
use etl_core::calib::params::MAX_PARAMS;
use etl_core::calib::View;
use etl_core::model::CameraModel;
use etl_formats::{Error, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::cameras::JointCamera;

/// Weight of a held number's prior row per unit of its magnitude (etl-core's bundle
/// adjustment's: a held number moves by ~1e-8 of itself).
const HOLD_WEIGHT: f64 = 1e8;

/// The joint problem: the cameras, the number of rig views, the estimator's stage prior
/// (`None`: the paper's estimator, no corrections), and which cameras each view has.
#[derive(Clone)]
pub(super) struct JointProblem<'a> {
    pub cameras: &'a [JointCamera],
    pub bases: Vec<Basis>,
    pub sigma_z_mm: Option<f64>,
    /// Per rig view: (camera, index of its view in that camera's list), cameras ascending.
    pub present: Vec<Vec<(usize, usize)>>,
    /// Each camera's start numbers x (held numbers are held here).
    pub x_start: Vec<[f64; MAX_PARAMS]>,
}

/// The state: each camera's internal numbers and each view's corrections.
#[derive(Debug, Clone)]
pub(super) struct State {
    pub z: Vec<[f64; MAX_PARAMS]>,
    pub y: Vec<DVector<f64>>,
}

/// The normal equations at a state: per camera U_k, g_k (in z), per view W_j (rows: the
/// present cameras' numbers stacked), V_j, g_y,j, and the cost (sum of squared normalised
/// rows, priors included).
#[derive(Debug, Clone)]
pub(super) struct Normal {
    pub u: Vec<DMatrix<f64>>,
    pub g: Vec<DVector<f64>>,
    pub w: Vec<DMatrix<f64>>,
    pub v: Vec<DMatrix<f64>>,
    pub gy: Vec<DVector<f64>>,
    pub cost: f64,
}

/// One camera's part of the normal equations: U, g, and per view of it the columns of W
/// (stage, own setting), the V entries (ZZ, ZE, EE) and the row sums of r times them.
struct CameraNormal {
    u: DMatrix<f64>,
    g: DVector<f64>,
    w: Vec<[DVector<f64>; 2]>,
    v: Vec<[f64; 3]>,
    gy: Vec<[f64; 2]>,
    cost: f64,
}

impl<'a> JointProblem<'a> {
    /// The problem of `cameras` over `views` rig views; `sigma_z_mm` the stage prior
    /// (errors-in-variables) or `None` (the paper's estimator).
    pub fn new(cameras: &'a [JointCamera], views: usize, sigma_z_mm: Option<f64>) -> Self {
        let mut present = vec![vec![]; views];
        for (k, c) in cameras.iter().enumerate() {
            for (i, v) in c.views.iter().enumerate() {
                if let Some(p) = present.get_mut(v.view) {
                    p.push((k, i));
                }
            }
        }
        let bases = cameras
            .iter()
            .map(|c| {
                let views: Vec<View<'_>> = c.views.iter().map(|v| View { e_com_ma: v.e, points: &v.points }).collect();
                Basis::for_views(&views, c.layout)
            })
            .collect();
        let x_start = cameras.iter().map(|c| to_params(&c.start)).collect();
        JointProblem { cameras, bases, sigma_z_mm, present, x_start }
    }

    /// The numbers per camera (p_k).
    pub fn sizes(&self) -> Vec<usize> {
        self.cameras.iter().map(|c| c.layout.len()).collect()
    }

    /// Whether the views carry corrections (errors-in-variables).
    pub fn eiv(&self) -> bool {
        self.sigma_z_mm.is_some()
    }

    /// The start: each camera's own solution, zero corrections.
    pub fn start(&self) -> State {
        let z = self.bases.iter().zip(&self.x_start).map(|(b, x)| b.to_internal(x)).collect();
        let m = |p: &Vec<(usize, usize)>| if self.eiv() { 1 + p.len() } else { 0 };
        State { z, y: self.present.iter().map(|p| DVector::zeros(m(p))).collect() }
    }

    /// Camera k's model at the state.
    pub fn model(&self, k: usize, s: &State) -> CameraModel {
        from_params(&self.cameras[k].layout, &self.bases[k].to_params(&s.z[k]))
    }

    /// Camera k's stage and setting corrections in its view `i` (zeros without them).
    fn corrections(&self, k: usize, i: usize, s: &State) -> [f64; 2] {
        let j = self.cameras[k].views[i].view;
        let Some(c) = self.present[j].iter().position(|&(kk, _)| kk == k) else { return [0.0; 2] };
        match s.y.get(j) {
            Some(y) if y.len() > 1 + c => [y[0], y[1 + c]],
            _ => [0.0; 2],
        }
    }

    /// Camera k's rows in x at the state: U_x, g_x, per view W columns, V entries.
    fn camera_normal(&self, k: usize, s: &State, jacobian: bool) -> Result<CameraNormal> {
        let cam = &self.cameras[k];
        let p = cam.layout.len();
        let x = self.bases[k].to_params(&s.z[k]);
        let proj = Projector::new(&from_params(&cam.layout, &x));
        let f = 1.0 / cam.sigma_px;
        let mut out =
            CameraNormal { u: DMatrix::zeros(p, p), g: DVector::zeros(p), w: vec![], v: vec![], gy: vec![], cost: 0.0 };
        for (i, v) in cam.views.iter().enumerate() {
            let [dz, de] = self.corrections(k, i, s);
            let (mut wz, mut we) = (DVector::zeros(p), DVector::zeros(p));
            let (mut vv, mut gy) = ([0.0; 3], [0.0; 2]);
            for pt in &v.points {
                let w = [pt.world_mm[0], pt.world_mm[1], pt.world_mm[2] + dz];
                let pr = proj.project(w, v.e + de, jacobian).map_err(Error::Core)?;
                for row in 0..2 {
                    let r = f * (pr.pixel[row] - pt.pixel[row]);
                    out.cost += r * r;
                    if !jacobian {
                        continue;
                    }
                    let jr = DVector::from_iterator(p, pr.d_params[row].iter().take(p).map(|d| f * d));
                    let (b, e) = (f * pr.d_z_w[row], f * pr.d_e[row]);
                    out.u.ger(1.0, &jr, &jr, 1.0);
                    out.g.axpy(r, &jr, 1.0);
                    wz.axpy(b, &jr, 1.0);
                    we.axpy(e, &jr, 1.0);
                    vv[0] += b * b;
                    vv[1] += b * e;
                    vv[2] += e * e;
                    gy[0] += b * r;
                    gy[1] += e * r;
                }
            }
            out.w.push([wz, we]);
            out.v.push(vv);
            out.gy.push(gy);
        }
        self.hold_rows(k, &x, &mut out);
        Ok(out)
    }

    /// The prior rows of camera k's held numbers at `x` (module docs of etl-core's bundle
    /// adjustment: weight [`HOLD_WEIGHT`] per unit of the start's magnitude).
    fn hold_rows(&self, k: usize, x: &[f64; MAX_PARAMS], out: &mut CameraNormal) {
        for i in self.cameras[k].hold.indices() {
            let x0 = self.x_start[k][i];
            let w = HOLD_WEIGHT / x0.abs().max(1e-12);
            let r = w * (x[i] - x0);
            out.cost += r * r;
            if let (Some(u), Some(g)) = (out.u.get_mut((i, i)), out.g.get_mut(i)) {
                *u += w * w;
                *g += w * r;
            }
        }
    }

    /// Camera k's RMS reprojection distance at the state, px (its corrections applied),
    /// and its corrections per view of it (dZ mm, dE).
    pub fn camera_rms(&self, k: usize, s: &State) -> Result<(f64, Vec<[f64; 2]>)> {
        let cam = &self.cameras[k];
        let proj = Projector::new(&self.model(k, s));
        let (mut sum, mut n, mut corrections) = (0.0, 0usize, vec![]);
        for (i, v) in cam.views.iter().enumerate() {
            let [dz, de] = self.corrections(k, i, s);
            for pt in &v.points {
                let w = [pt.world_mm[0], pt.world_mm[1], pt.world_mm[2] + dz];
                let pr = proj.project(w, v.e + de, false).map_err(Error::Core)?;
                sum += (pr.pixel[0] - pt.pixel[0]).powi(2) + (pr.pixel[1] - pt.pixel[1]).powi(2);
                n += 1;
            }
            corrections.push([dz, de]);
        }
        Ok(((sum / n.max(1) as f64).sqrt(), corrections))
    }

    /// The cost at the state (no Jacobian).
    pub fn cost(&self, s: &State) -> Result<f64> {
        let rows: Result<Vec<f64>> =
            (0..self.cameras.len()).into_par_iter().map(|k| Ok(self.camera_normal(k, s, false)?.cost)).collect();
        Ok(rows?.iter().sum::<f64>() + self.prior_cost(s))
    }

    /// The corrections' prior cost: sum (dZ / sigma_z)^2 + (dE / sigma_e)^2.
    fn prior_cost(&self, s: &State) -> f64 {
        let Some(sz) = self.sigma_z_mm else { return 0.0 };
        let mut cost = 0.0;
        for (y, p) in s.y.iter().zip(&self.present) {
            cost += (y[0] / sz).powi(2);
            for (c, &(k, _)) in p.iter().enumerate() {
                cost += (y[1 + c] / self.cameras[k].sigma_e).powi(2);
            }
        }
        cost
    }

    /// The normal equations at the state, in the internal numbers z.
    pub fn normal(&self, s: &State) -> Result<Normal> {
        let parts: Result<Vec<CameraNormal>> =
            (0..self.cameras.len()).into_par_iter().map(|k| self.camera_normal(k, s, true)).collect();
        let parts = parts?;
        let d: Vec<DMatrix<f64>> = (0..self.cameras.len()).map(|k| self.dx_dz(k, s)).collect();
        let mut n = Normal { u: vec![], g: vec![], w: vec![], v: vec![], gy: vec![], cost: self.prior_cost(s) };
        for (part, dk) in parts.iter().zip(&d) {
            n.u.push(dk.transpose() * &part.u * dk);
            n.g.push(dk.transpose() * &part.g);
            n.cost += part.cost;
        }
        if !self.eiv() {
            return Ok(n);
        }
        let sizes = self.sizes();
        for (j, p) in self.present.iter().enumerate() {
            let rows: usize = p.iter().map(|&(k, _)| sizes[k]).sum();
            let m = 1 + p.len();
            let (mut w, mut v, mut gy) = (DMatrix::zeros(rows, m), DMatrix::zeros(m, m), DVector::zeros(m));
            let sz = self.sigma_z_mm.unwrap_or(1.0);
            v[(0, 0)] = 1.0 / (sz * sz);
            gy[0] = s.y[j][0] / (sz * sz);
            let mut at = 0;
            for (c, &(k, i)) in p.iter().enumerate() {
                let pk = sizes[k];
                let dt = d[k].transpose();
                w.view_mut((at, 0), (pk, 1)).copy_from(&(&dt * &parts[k].w[i][0]));
                w.view_mut((at, 1 + c), (pk, 1)).copy_from(&(&dt * &parts[k].w[i][1]));
                let [zz, ze, ee] = parts[k].v[i];
                let se2 = self.cameras[k].sigma_e.powi(2);
                v[(0, 0)] += zz;
                v[(0, 1 + c)] = ze;
                v[(1 + c, 0)] = ze;
                v[(1 + c, 1 + c)] = ee + 1.0 / se2;
                gy[0] += parts[k].gy[i][0];
                gy[1 + c] = parts[k].gy[i][1] + s.y[j][1 + c] / se2;
                at += pk;
            }
            n.w.push(w);
            n.v.push(v);
            n.gy.push(gy);
        }
        Ok(n)
    }

    /// D_k = dx/dz of camera k at the state (p_k square).
    pub fn dx_dz(&self, k: usize, s: &State) -> DMatrix<f64> {
        let p = self.cameras[k].layout.len();
        let full = self.bases[k].params_jacobian(&s.z[k]);
        DMatrix::from_fn(p, p, |i, j| full[i][j])
    }

    /// The state moved by the step (dz per camera stacked, dy per view).
    pub fn moved(&self, s: &State, dz: &DVector<f64>, dy: &[DVector<f64>]) -> State {
        let mut next = s.clone();
        let mut at = 0;
        for (z, p) in next.z.iter_mut().zip(self.sizes()) {
            for (i, zi) in z.iter_mut().take(p).enumerate() {
                *zi += dz[at + i];
            }
            at += p;
        }
        for (y, d) in next.y.iter_mut().zip(dy) {
            *y += d;
        }
        next
    }
}
