//! The covariance of R, T in the fixed-intrinsics mode, with the uncertainty of the held
//! intrinsics carried through.
//!
//! Holding the intrinsics kappa at their estimates makes the solve's own covariance of
//! theta = (om, T) conditional on them; but kappa came from noisy views too. To first
//! order theta moves with kappa by d theta / d kappa = -S_tt^-1 S_tk, with S the reduced
//! (Schur) normal matrix of the joint problem, over (theta, kappa) with the pairs' poses
//! eliminated, at the solution. So
//!
//! ```text
//! Cov(theta) = Cov(theta | kappa) + A Cov(kappa) A^T,   A = -S_tt^-1 S_tk
//! ```
//!
//! with Cov(kappa) block-diagonal: each camera's Zhang covariance of its free numbers (the
//! cameras' images are independent). The correlation between the conditional error and
//! kappa's, through the pairs' images that both use, is left out.

use etl_core::lm::{BlockNormal, BlockProblem};
use etl_formats::{Error, Result};
use nalgebra::Matrix6;

use super::problem::StereoProblem;
use crate::zhang::ZhangResult;

/// A dense matrix as rows.
type Rows = Vec<Vec<f64>>;

/// `a b` for dense matrices of matching sizes.
fn mul(a: &Rows, b: &Rows) -> Rows {
    let m = b.first().map_or(0, Vec::len);
    a.iter().map(|r| (0..m).map(|j| r.iter().zip(b).map(|(x, bk)| x * bk[j]).sum()).collect()).collect()
}

/// The transpose of `a`.
fn transpose(a: &Rows) -> Rows {
    let m = a.first().map_or(0, Vec::len);
    (0..m).map(|j| a.iter().map(|r| r[j]).collect()).collect()
}

/// S = U - sum_j W_j V_j^-1 W_j^T of the problem over its `N` shared numbers at `x` and
/// the pairs' `poses`.
fn reduced<const N: usize>(problem: &mut StereoProblem<'_>, x: &[f64], poses: &[[f64; 6]]) -> Result<Rows> {
    let x: [f64; N] = core::array::from_fn(|k| x.get(k).copied().unwrap_or(0.0));
    let (mut u, mut gx) = ([[0.0; N]; N], [0.0; N]);
    let mut s = vec![vec![0.0; N]; N];
    for (b, y) in poses.iter().enumerate() {
        let (mut w, mut v, mut gy) = ([[0.0; 6]; N], [[0.0; 6]; 6], [0.0; 6]);
        let mut sink = BlockNormal { u: &mut u, gx: &mut gx, w: &mut w, v: &mut v, gy: &mut gy, cost: 0.0, rows: 0 };
        <StereoProblem<'_> as BlockProblem<N, 6>>::eval_block(problem, b, &x, y, true, &mut sink)?;
        let v_inv = Matrix6::from_fn(|i, j| v[i.min(j)][i.max(j)])
            .try_inverse()
            .ok_or(Error::Core(etl_core::Error::Degenerate { what: "a pair's board pose is not determined" }))?;
        let wm: Rows = w.iter().map(|r| r.to_vec()).collect();
        let v_inv: Rows = (0..6).map(|i| (0..6).map(|j| v_inv[(i, j)]).collect()).collect();
        let wvw = mul(&mul(&wm, &v_inv), &transpose(&wm));
        for (srow, row) in s.iter_mut().zip(wvw) {
            for (sv, v) in srow.iter_mut().zip(row) {
                *sv -= v;
            }
        }
    }
    for (i, srow) in s.iter_mut().enumerate() {
        for (j, sv) in srow.iter_mut().enumerate() {
            *sv += u[i.min(j)][i.max(j)];
        }
    }
    Ok(s)
}

/// Cov(kappa): each camera's Zhang covariance of its `free` numbers, block-diagonal (the
/// left camera's first); `None` when a result carries no covariance blocks.
fn intrinsics_covariance(left: &ZhangResult, right: &ZhangResult, free: &[usize]) -> Option<Rows> {
    let n = free.len();
    let mut c = vec![vec![0.0; 2 * n]; 2 * n];
    for (side, z) in [left, right].into_iter().enumerate() {
        let cov = z.uncertainty.as_ref()?.shared_covariance();
        for (a, &i) in free.iter().enumerate() {
            for (b, &j) in free.iter().enumerate() {
                c[side * n + a][side * n + b] = cov[i][j];
            }
        }
    }
    Some(c)
}

/// The covariance of (om, T) of a fixed-intrinsics solve (`conditional`: the solve's own)
/// with the intrinsics' uncertainty carried through (module docs). `problem` frees both
/// cameras' `free` numbers; `x` is (om, T, the left's free numbers, the right's) at the
/// solution, `poses` the pairs'. Errors: a count of numbers no mode gives; a singular
/// block.
pub(super) fn with_intrinsics(
    problem: &mut StereoProblem<'_>,
    (x, poses): (&[f64], &[[f64; 6]]),
    conditional: &[Vec<f64>],
    (left, right, free): (&ZhangResult, &ZhangResult, &[usize]),
) -> Result<[[f64; 6]; 6]> {
    let cond: [[f64; 6]; 6] = core::array::from_fn(|i| core::array::from_fn(|j| conditional[i][j]));
    let Some(cov_k) = intrinsics_covariance(left, right, free) else { return Ok(cond) };
    let s = match x.len() {
        18 => reduced::<18>(problem, x, poses)?,
        20 => reduced::<20>(problem, x, poses)?,
        22 => reduced::<22>(problem, x, poses)?,
        24 => reduced::<24>(problem, x, poses)?,
        n => return Err(Error::invalid("options", format!("the stereo covariance: {n} numbers"))),
    };
    let inv = Matrix6::from_fn(|i, j| s[i][j])
        .try_inverse()
        .ok_or(Error::Core(etl_core::Error::Degenerate { what: "the relative pose is not determined by the pairs" }))?;
    // A = -S_tt^-1 S_tk, 6 x (numbers - 6).
    let s_tk: Rows = s.iter().take(6).map(|r| r[6..].to_vec()).collect();
    let inv: Rows = (0..6).map(|i| (0..6).map(|j| -inv[(i, j)]).collect()).collect();
    let a = mul(&inv, &s_tk);
    let prop = mul(&mul(&a, &cov_k), &transpose(&a));
    Ok(core::array::from_fn(|i| core::array::from_fn(|j| cond[i][j] + prop[i][j])))
}
