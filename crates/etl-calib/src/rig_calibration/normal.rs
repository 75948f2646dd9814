//! The joint problem's state and its normal equations (module docs of [`super`]).
//!
//! Camera k's numbers are solved in etl-core's internal parameters z_k ([`Basis`]:
//! Chebyshev coefficients on its own range of settings), mapped to the model's x_k = x(z_k);
//! its rows are accumulated in x and carried to z by D_k = dx/dz: J_z = J_x D_k. View j's
//! unknowns y_j exist with errors-in-variables only: its shared part, then each present
//! camera's setting correction dE_kj (in the order of [`JointProblem::present`]). The
//! shared part of a stage view is its stage correction dZ_j (the board's corner (X, Y) at
//! world (X, Y, Z_j + dZ_j)); that of a free view is the board's pose (om_b, t_b), board
//! to world, not corrections but unknowns without a prior (the corner (X, Y) at world
//! R(om_b) (X, Y, 0) + t_b). A free view's pixel derivative with respect to the world
//! point is d q / d w = (d q / d t_k) R_k (the camera's translation enters as R_k w + t_k),
//! and d w / d om_b = -R_b [X]x J_r(om_b) (etl-core's `rotate_point_jacobian`).

use etl_core::calib::basis::Basis;
use etl_core::calib::jacobian::{from_params, rotate_point_jacobian, to_params, Projection, Projector};
use etl_core::calib::params::{MAX_PARAMS, TRANSLATION};
use etl_core::calib::View;
use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use etl_core::model::CameraModel;
use etl_formats::{Error, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::cameras::JointCamera;

/// Weight of a held number's prior row per unit of its magnitude (etl-core's bundle
/// adjustment's: a held number moves by ~1e-8 of itself).
const HOLD_WEIGHT: f64 = 1e8;

/// The length of a free view's shared unknowns: the board's pose (om_b, t_b).
pub(super) const FREE_POSE_LEN: usize = 6;

/// The joint problem: the cameras, the rig views (the stage views, then the free views),
/// the estimator's stage prior (`None`: the paper's estimator, no view unknowns; free views
/// need errors-in-variables), and which cameras each view has.
#[derive(Clone)]
pub(super) struct JointProblem<'a> {
    pub cameras: &'a [JointCamera],
    pub bases: Vec<Basis>,
    pub sigma_z_mm: Option<f64>,
    /// Per rig view: (camera, index of its view in that camera's list), cameras ascending.
    pub present: Vec<Vec<(usize, usize)>>,
    /// Each camera's start numbers x (held numbers are held here).
    pub x_start: Vec<[f64; MAX_PARAMS]>,
    /// The number of stage views: views from this index on are free views.
    pub stage_views: usize,
    /// Each free view's starting board pose (om_b, t_b), board to world.
    pub free_start: Vec<[f64; FREE_POSE_LEN]>,
}

/// The state: each camera's internal numbers and each view's unknowns.
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
/// (the view's shared unknowns, then its own setting), their V block and B' r.
struct CameraNormal {
    u: DMatrix<f64>,
    g: DVector<f64>,
    w: Vec<DMatrix<f64>>,
    v: Vec<DMatrix<f64>>,
    gy: Vec<DVector<f64>>,
    cost: f64,
}

/// Where a view puts its board's corners in the world, and how they move with the view's
/// shared unknowns.
enum Placement {
    /// A stage view: (X, Y, Z + dZ).
    Stage { dz_mm: f64 },
    /// A free view: R_b (X, Y, 0) + t_b.
    Free { om: [f64; 3], r: Mat3, t: [f64; 3] },
}

impl Placement {
    /// The corner's world point, and d w / d (shared unknowns) as columns (1 or 6).
    fn world(&self, board_mm: [f64; 3], jacobian: bool) -> ([f64; 3], Vec<[f64; 3]>) {
        match self {
            Placement::Stage { dz_mm } => ([board_mm[0], board_mm[1], board_mm[2] + dz_mm], vec![[0.0, 0.0, 1.0]]),
            Placement::Free { om, r, t } => {
                let p = mat_vec(r, board_mm);
                let w = [p[0] + t[0], p[1] + t[1], p[2] + t[2]];
                if !jacobian {
                    return (w, vec![]);
                }
                let dr = rotate_point_jacobian(r, *om, board_mm);
                let mut cols: Vec<[f64; 3]> = (0..3).map(|c| [dr[0][c], dr[1][c], dr[2][c]]).collect();
                cols.extend([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
                (w, cols)
            }
        }
    }
}

/// d pixel / d (shared unknowns) of one projected point: a stage view's d_z_w, or a free
/// view's (d q / d t_k) R_k (d w / d pose) (module docs).
fn shared_derivatives(pr: &Projection, r_camera: &Mat3, dw: &[[f64; 3]], free: bool) -> [Vec<f64>; 2] {
    core::array::from_fn(|row| {
        if !free {
            return vec![pr.d_z_w[row]];
        }
        let dt: [f64; 3] = core::array::from_fn(|k| pr.d_params[row][TRANSLATION.at(k)]);
        let dq_dw: [f64; 3] = core::array::from_fn(|i| (0..3).map(|k| dt[k] * r_camera[k][i]).sum());
        dw.iter().map(|c| dq_dw[0] * c[0] + dq_dw[1] * c[1] + dq_dw[2] * c[2]).collect()
    })
}

impl<'a> JointProblem<'a> {
    /// The problem of `cameras` over `stage_views` stage views, then the free views whose
    /// starting board poses are `free_start`; `sigma_z_mm` the stage prior
    /// (errors-in-variables) or `None` (the paper's estimator, which takes no free views).
    pub fn new(
        cameras: &'a [JointCamera],
        stage_views: usize,
        free_start: Vec<[f64; FREE_POSE_LEN]>,
        sigma_z_mm: Option<f64>,
    ) -> Self {
        let mut present = vec![vec![]; stage_views + free_start.len()];
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
                let stage = c.views.iter().filter(|v| v.view < stage_views);
                let views: Vec<View<'_>> = stage.map(|v| View { e_com_ma: v.e, points: &v.points }).collect();
                Basis::for_views(&views, c.layout)
            })
            .collect();
        let x_start = cameras.iter().map(|c| to_params(&c.start)).collect();
        JointProblem { cameras, bases, sigma_z_mm, present, x_start, stage_views, free_start }
    }

    /// The numbers per camera (p_k).
    pub fn sizes(&self) -> Vec<usize> {
        self.cameras.iter().map(|c| c.layout.len()).collect()
    }

    /// Whether the views carry unknowns (errors-in-variables).
    pub fn eiv(&self) -> bool {
        self.sigma_z_mm.is_some()
    }

    /// Whether rig view `j` is a free view.
    pub fn is_free(&self, j: usize) -> bool {
        j >= self.stage_views
    }

    /// The length of view j's shared unknowns: a free view's pose (6), a stage view's dZ
    /// (1).
    pub fn shared_len(&self, j: usize) -> usize {
        if self.is_free(j) {
            FREE_POSE_LEN
        } else {
            1
        }
    }

    /// The start: each camera's own solution, zero corrections, the free views' starting
    /// poses.
    pub fn start(&self) -> State {
        let z = self.bases.iter().zip(&self.x_start).map(|(b, x)| b.to_internal(x)).collect();
        let y = self
            .present
            .iter()
            .enumerate()
            .map(|(j, p)| {
                if !self.eiv() {
                    return DVector::zeros(0);
                }
                let mut y = DVector::zeros(self.shared_len(j) + p.len());
                if self.is_free(j) {
                    y.rows_mut(0, FREE_POSE_LEN).copy_from_slice(&self.free_start[j - self.stage_views]);
                }
                y
            })
            .collect();
        State { z, y }
    }

    /// Camera k's model at the state.
    pub fn model(&self, k: usize, s: &State) -> CameraModel {
        from_params(&self.cameras[k].layout, &self.bases[k].to_params(&s.z[k]))
    }

    /// Where camera k's view `i` puts the board, and its setting correction (the state's,
    /// zeros without unknowns).
    fn placement(&self, k: usize, i: usize, s: &State) -> (Placement, f64) {
        let j = self.cameras[k].views[i].view;
        let c = self.present[j].iter().position(|&(kk, _)| kk == k);
        let (y, sh) = (s.y.get(j), self.shared_len(j));
        let de = match (y, c) {
            (Some(y), Some(c)) if y.len() > sh + c => y[sh + c],
            _ => 0.0,
        };
        if !self.is_free(j) {
            return (Placement::Stage { dz_mm: y.and_then(|y| y.get(0)).copied().unwrap_or(0.0) }, de);
        }
        let pose: [f64; FREE_POSE_LEN] = match y {
            Some(y) if y.len() >= FREE_POSE_LEN => core::array::from_fn(|a| y[a]),
            _ => self.free_start.get(j - self.stage_views).copied().unwrap_or([0.0; FREE_POSE_LEN]),
        };
        let om = [pose[0], pose[1], pose[2]];
        (Placement::Free { om, r: rodrigues_to_matrix(om), t: [pose[3], pose[4], pose[5]] }, de)
    }

    /// Camera k's rows in x at the state: U_x, g_x, per view W columns, V block, B' r.
    fn camera_normal(&self, k: usize, s: &State, jacobian: bool) -> Result<CameraNormal> {
        let cam = &self.cameras[k];
        let p = cam.layout.len();
        let x = self.bases[k].to_params(&s.z[k]);
        let model = from_params(&cam.layout, &x);
        let (proj, r_camera) = (Projector::new(&model), rodrigues_to_matrix(model.rotation_rodrigues));
        let f = 1.0 / cam.sigma_px;
        let mut out =
            CameraNormal { u: DMatrix::zeros(p, p), g: DVector::zeros(p), w: vec![], v: vec![], gy: vec![], cost: 0.0 };
        for (i, v) in cam.views.iter().enumerate() {
            let (placement, de) = self.placement(k, i, s);
            let q = self.shared_len(v.view) + 1;
            let (mut w, mut vv, mut gy) = (DMatrix::zeros(p, q), DMatrix::zeros(q, q), DVector::zeros(q));
            for pt in &v.points {
                let (world, dw) = placement.world(pt.world_mm, jacobian);
                let pr = proj.project(world, v.e + de, jacobian).map_err(Error::Core)?;
                let shared = jacobian.then(|| shared_derivatives(&pr, &r_camera, &dw, self.is_free(v.view)));
                for row in 0..2 {
                    let r = f * (pr.pixel[row] - pt.pixel[row]);
                    out.cost += r * r;
                    let Some(shared) = &shared else { continue };
                    let jr = DVector::from_iterator(p, pr.d_params[row].iter().take(p).map(|d| f * d));
                    let mut b: Vec<f64> = shared[row].iter().map(|d| f * d).collect();
                    b.push(f * pr.d_e[row]);
                    let b = DVector::from_vec(b);
                    out.u.ger(1.0, &jr, &jr, 1.0);
                    out.g.axpy(r, &jr, 1.0);
                    w.ger(1.0, &jr, &b, 1.0);
                    vv.ger(1.0, &b, &b, 1.0);
                    gy.axpy(r, &b, 1.0);
                }
            }
            out.w.push(w);
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

    /// Camera k's RMS reprojection distance at the state over all its views, px, and its
    /// corrections per stage view of it (dZ mm, dE).
    pub fn camera_rms(&self, k: usize, s: &State) -> Result<(f64, Vec<[f64; 2]>)> {
        let cam = &self.cameras[k];
        let proj = Projector::new(&self.model(k, s));
        let (mut sum, mut n, mut corrections) = (0.0, 0usize, vec![]);
        for (i, v) in cam.views.iter().enumerate() {
            let (placement, de) = self.placement(k, i, s);
            for pt in &v.points {
                let pr = proj.project(placement.world(pt.world_mm, false).0, v.e + de, false).map_err(Error::Core)?;
                sum += (pr.pixel[0] - pt.pixel[0]).powi(2) + (pr.pixel[1] - pt.pixel[1]).powi(2);
                n += 1;
            }
            if let Placement::Stage { dz_mm } = placement {
                corrections.push([dz_mm, de]);
            }
        }
        Ok(((sum / n.max(1) as f64).sqrt(), corrections))
    }

    /// The cost at the state (no Jacobian).
    pub fn cost(&self, s: &State) -> Result<f64> {
        let rows: Result<Vec<f64>> =
            (0..self.cameras.len()).into_par_iter().map(|k| Ok(self.camera_normal(k, s, false)?.cost)).collect();
        Ok(rows?.iter().sum::<f64>() + self.prior_cost(s))
    }

    /// The corrections' prior cost: sum (dZ / sigma_z)^2 over stage views plus
    /// (dE / sigma_e)^2 over every camera's views (a free pose has no prior).
    fn prior_cost(&self, s: &State) -> f64 {
        let Some(sz) = self.sigma_z_mm else { return 0.0 };
        let mut cost = 0.0;
        for (j, (y, p)) in s.y.iter().zip(&self.present).enumerate() {
            let sh = self.shared_len(j);
            if !self.is_free(j) {
                cost += (y[0] / sz).powi(2);
            }
            for (c, &(k, _)) in p.iter().enumerate() {
                cost += (y[sh + c] / self.cameras[k].sigma_e).powi(2);
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
        for j in 0..self.present.len() {
            let (w, v, gy) = self.view_block(j, s, (&parts, &d), &sizes);
            n.w.push(w);
            n.v.push(v);
            n.gy.push(gy);
        }
        Ok(n)
    }

    /// View j's W_j (the present cameras' numbers in z stacked, by its unknowns), V_j with
    /// the priors, and g_y,j, from the cameras' parts and their D_k; `sizes` the p_k.
    fn view_block(
        &self,
        j: usize,
        s: &State,
        (parts, d): (&[CameraNormal], &[DMatrix<f64>]),
        sizes: &[usize],
    ) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
        let p = &self.present[j];
        let sh = self.shared_len(j);
        let rows: usize = p.iter().map(|&(k, _)| sizes[k]).sum();
        let m = sh + p.len();
        let (mut w, mut v, mut gy) = (DMatrix::zeros(rows, m), DMatrix::zeros(m, m), DVector::zeros(m));
        if !self.is_free(j) {
            let sz2 = self.sigma_z_mm.unwrap_or(1.0).powi(2);
            v[(0, 0)] = 1.0 / sz2;
            gy[0] = s.y[j][0] / sz2;
        }
        let mut at = 0;
        for (c, &(k, i)) in p.iter().enumerate() {
            let pk = sizes[k];
            let wt = d[k].transpose() * &parts[k].w[i];
            w.view_mut((at, 0), (pk, sh)).copy_from(&wt.columns(0, sh));
            w.view_mut((at, sh + c), (pk, 1)).copy_from(&wt.column(sh));
            let (pv, pg) = (&parts[k].v[i], &parts[k].gy[i]);
            let mut shared = v.view_mut((0, 0), (sh, sh));
            shared += pv.view((0, 0), (sh, sh));
            v.view_mut((0, sh + c), (sh, 1)).copy_from(&pv.view((0, sh), (sh, 1)));
            v.view_mut((sh + c, 0), (1, sh)).copy_from(&pv.view((sh, 0), (1, sh)));
            let se2 = self.cameras[k].sigma_e.powi(2);
            v[(sh + c, sh + c)] = pv[(sh, sh)] + 1.0 / se2;
            let mut g0 = gy.rows_mut(0, sh);
            g0 += pg.rows(0, sh);
            gy[sh + c] = pg[sh] + s.y[j][sh + c] / se2;
            at += pk;
        }
        (w, v, gy)
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

    /// Each free view's board pose at the state (om_b, t_b), board to world.
    pub fn free_poses(&self, s: &State) -> Vec<[f64; FREE_POSE_LEN]> {
        (self.stage_views..self.present.len())
            .map(|j| match s.y.get(j) {
                Some(y) if y.len() >= FREE_POSE_LEN => core::array::from_fn(|a| y[a]),
                _ => self.free_start[j - self.stage_views],
            })
            .collect()
    }
}
