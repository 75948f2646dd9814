//! The joint covariance of every camera's numbers, and of each extrinsic pose.
//!
//! Errors-in-variables: the rows are normalised by their standard deviations (each
//! camera's sigma_px, the priors given), so the inverse Fisher information of the numbers
//! with the corrections marginalised out, S^-1 (S the undamped Schur complement of
//! [`super::reduced`]), is the covariance (not rescaled: etl-core's `unscaled`). The
//! paper's estimator: its own covariance under the whole noise model (etl-core's
//! `input_noise`), now joint: C = H^-1 + H^-1 M H^-1 with
//! M = sum_j W_j Q_j W_j', Q_j = diag(sigma_z^2, sigma_e,k^2 ...): one stage error per view
//! seen by every camera makes the cameras' estimates correlated even though H is block
//! diagonal. Both are mapped from the internal numbers to the model's by
//! D = blockdiag(dx_k/dz_k): C_x = D C_z D'.
//!
//! Camera k's extrinsics e_k = (om(R_k R_0'), t_k - R_k R_0' t_0) depend on (om_0, t_0,
//! om_k, t_k): cov(e_k) = J C_x J' with J (6 x 12) their Jacobian, by central differences
//! (step 1e-6 rad / 1e-6 mm: the pose is smooth, the differences exact to ~1e-9).

use etl_formats::rig::relative_pose;
use etl_formats::{Error, Result};
use nalgebra::{DMatrix, DVector};

use super::normal::{JointProblem, State};
use super::reduced::schur_complement;

/// The covariance of all numbers in the model's parameters (cameras stacked in the
/// order of the problem, each in its layout's order).
pub(super) fn joint_covariance(
    problem: &JointProblem<'_>,
    state: &State,
    input_noise_sigma_z_mm: Option<f64>,
) -> Result<DMatrix<f64>> {
    let sizes = problem.sizes();
    let total: usize = sizes.iter().sum();
    let n = problem.normal(state)?;
    let schur = schur_complement(&n, &sizes, &problem.present, 0.0)?.s;
    let Some(factor) = schur.clone().cholesky() else { return Err(undetermined(&schur, problem)) };
    let mut cz = factor.inverse();
    if let (false, Some(sz)) = (problem.eiv(), input_noise_sigma_z_mm) {
        let with_corrections = JointProblem { sigma_z_mm: Some(sz), ..problem.clone() };
        let s0 = State { z: state.z.clone(), y: with_corrections.start().y };
        let ne = with_corrections.normal(&s0)?;
        let mut m = DMatrix::zeros(total, total);
        let off: Vec<usize> = sizes.iter().scan(0, |a, p| Some(std::mem::replace(a, *a + p))).collect();
        for (j, p) in problem.present.iter().enumerate() {
            let mut q = DVector::zeros(1 + p.len());
            q[0] = sz * sz;
            for (c, &(k, _)) in p.iter().enumerate() {
                q[1 + c] = problem.cameras[k].sigma_e.powi(2);
            }
            let wq = &ne.w[j] * DMatrix::from_diagonal(&q) * ne.w[j].transpose();
            let rows: Vec<(usize, usize, usize)> =
                p.iter().scan(0, |a, &(k, _)| Some((off[k], std::mem::replace(a, *a + sizes[k]), sizes[k]))).collect();
            for &(ok, ak, pk) in &rows {
                for &(ol, al, pl) in &rows {
                    let mut b = m.view_mut((ok, ol), (pk, pl));
                    b += wq.view((ak, al), (pk, pl));
                }
            }
        }
        cz = &cz + &cz * m * &cz;
    }
    let mut d = DMatrix::zeros(total, total);
    let mut at = 0;
    for (k, &pk) in sizes.iter().enumerate() {
        d.view_mut((at, at), (pk, pk)).copy_from(&problem.dx_dz(k, state));
        at += pk;
    }
    let c = &d * cz * d.transpose();
    if !c.iter().all(|x| x.is_finite()) {
        return Err(Error::Core(etl_core::Error::Degenerate { what: "the rig's covariance is not finite" }));
    }
    Ok((&c + c.transpose()) * 0.5)
}

/// The 6 x 6 covariance of camera k's extrinsics from the joint covariance `c` (x),
/// camera 0's pose numbers at `pose0` (indices into c of om_0, t_0), camera k's at `posek`.
pub(super) fn extrinsics_covariance(
    c: &DMatrix<f64>,
    (pose0, posek): (&[usize; 6], &[usize; 6]),
    (p0, pk): ([f64; 6], [f64; 6]),
) -> [[f64; 6]; 6] {
    let rel = |a: [f64; 6], b: [f64; 6]| {
        let (om, t) = relative_pose(pose_pair(a), pose_pair(b));
        [om[0], om[1], om[2], t[0], t[1], t[2]]
    };
    let mut jac = DMatrix::zeros(6, 12);
    for i in 0..12 {
        let h = 1e-6;
        let (mut ap, mut am, mut bp, mut bm) = (p0, p0, pk, pk);
        if i < 6 {
            ap[i] += h;
            am[i] -= h;
        } else {
            bp[i - 6] += h;
            bm[i - 6] -= h;
        }
        let (fp, fm) = (rel(ap, bp), rel(am, bm));
        for r in 0..6 {
            jac[(r, i)] = (fp[r] - fm[r]) / (2.0 * h);
        }
    }
    let idx: Vec<usize> = pose0.iter().chain(posek).copied().collect();
    let sub = DMatrix::from_fn(12, 12, |a, b| c[(idx[a], idx[b])]);
    let e = &jac * sub * jac.transpose();
    core::array::from_fn(|i| core::array::from_fn(|j| 0.5 * (e[(i, j)] + e[(j, i)])))
}

/// A pose's six numbers (om, t) as the pair etl-formats' `relative_pose` takes.
pub(super) fn pose_pair(p: [f64; 6]) -> ([f64; 3], [f64; 3]) {
    ([p[0], p[1], p[2]], [p[3], p[4], p[5]])
}

/// The refusal of a rig whose numbers its views do not determine: the undamped Schur
/// complement S is singular. It names the numbers of S's weakest direction (the
/// eigenvector of the smallest eigenvalue of S scaled to a unit diagonal, its two largest
/// components), so that the user knows what to hold or which views to add.
fn undetermined(s: &DMatrix<f64>, problem: &JointProblem<'_>) -> Error {
    let n = s.nrows();
    let d = DVector::from_fn(n, |i, _| 1.0 / s[(i, i)].abs().max(1e-300).sqrt());
    let eig = DMatrix::from_fn(n, n, |i, j| s[(i, j)] * d[i] * d[j]).symmetric_eigen();
    let weakest = (0..n).min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b])).unwrap_or(0);
    let v = eig.eigenvectors.column(weakest);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| v[b].abs().total_cmp(&v[a].abs()));
    let sizes = problem.sizes();
    let name = |i: usize| {
        let (mut k, mut at) = (0, i);
        while k + 1 < sizes.len() && at >= sizes[k] {
            at -= sizes[k];
            k += 1;
        }
        let number = problem.cameras[k].layout.names().nth(at).unwrap_or("?");
        format!("camera {k}'s {number}")
    };
    let along: Vec<String> = order.iter().take(2).map(|&i| name(i)).collect();
    Error::invalid(
        "rig",
        format!(
            "the rig's numbers are not determined by its views: the joint system is singular along {} (hold them, or add \
             views that fix them: lens-off views for A0, free views of the board tilted)",
            along.join(" and ")
        ),
    )
}
