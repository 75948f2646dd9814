//! One damped step of the joint problem through its reduced system, by either path of
//! [`super::LinearSolver`] (module docs of [`super`]).
//!
//! With the step's damping lambda (Marquardt's: each diagonal entry times 1 + lambda), the
//! system is
//!
//! ```text
//! [ U  W ] [dx]     [g  ]
//! [ W' V ] [dy] = - [g_y]        U = blockdiag(U_k),  W = (W_1 .. W_J),  V = blockdiag(V_j)
//! ```
//!
//! **Dense**: every correction eliminated, S = U - sum_j W_j V_j^-1 W_j' ((sum p_k)
//! square), S dx = -g + sum_j W_j V_j^-1 g_y,j, by nalgebra's Cholesky;
//! dy_j = V_j^-1 (-g_y,j - W_j' dx). The stage correction dZ_j is seen by every camera of
//! view j, so S has every block (k, l) of two cameras that share a view: dense.
//!
//! **Sparse**: only the setting corrections dE_kj eliminated (each touches camera k and
//! view j's shared unknowns alone: V_j's setting block is diagonal), the shared unknowns
//! kept (a stage view's dZ_j; a free view's board pose, 6 numbers): unknowns
//! (dx, y_1..y_J shared), camera blocks dense, each view's shared block bordered by the
//! cameras of view j: an arrow, factored by faer's sparse Cholesky (its own fill-reducing
//! ordering). For camera k at position c of view j (v the damped V_j; for a free view
//! v_0c and B_kj have 6 rows or columns, D_jj is 6 x 6):
//!
//! ```text
//! U_k  -= w_E w_E' / v_cc                 rhs_k  += w_E g_c / v_cc
//! B_kj  = w_Z - w_E v_0c / v_cc           rhs_Zj  = -g_0 + sum_c v_0c g_c / v_cc
//! D_jj  = v_00 - sum_c v_0c^2 / v_cc      dE_c   = (-g_c - w_E' dx_k - v_0c dZ_j) / v_cc
//! ```
//!
//! Both give the same step (a test checks it to 1e-9).

use etl_formats::{Error, Result};
use std::sync::OnceLock;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use nalgebra::{DMatrix, DVector};

use super::normal::Normal;

/// `m` with its diagonal times 1 + lambda (a zero diagonal entry given 1e-12 first, so
/// that a column no row touches is still damped).
fn damped(m: &DMatrix<f64>, lambda: f64) -> DMatrix<f64> {
    let mut out = m.clone();
    for i in 0..m.nrows() {
        out[(i, i)] = m[(i, i)].max(1e-12) * (1.0 + lambda);
    }
    out
}

/// The offsets of the cameras' numbers in dx.
fn offsets(sizes: &[usize]) -> Vec<usize> {
    sizes.iter().scan(0, |at, p| Some(std::mem::replace(at, *at + p))).collect()
}

/// What [`not_positive`] says.
const NOT_POSITIVE: &str = "the rig's reduced system is not positive definite";

pub(super) fn not_positive() -> Error {
    Error::Core(etl_core::Error::Degenerate { what: NOT_POSITIVE })
}

/// Whether `e` is [`not_positive`]'s error (a damped system rounding left indefinite).
pub(super) fn is_not_positive(e: &Error) -> bool {
    matches!(e, Error::Core(etl_core::Error::Degenerate { what }) if *what == NOT_POSITIVE)
}

/// The dense path's system: the damped Schur complement S, its right-hand side and each
/// view's damped V_j^-1.
pub(super) struct Schur {
    pub s: DMatrix<f64>,
    pub rhs: DVector<f64>,
    pub v_inverses: Vec<DMatrix<f64>>,
}

/// The dense path's system ([`Schur`]; `present`: per view the cameras present).
pub(super) fn schur_complement(
    n: &Normal,
    sizes: &[usize],
    present: &[Vec<(usize, usize)>],
    lambda: f64,
) -> Result<Schur> {
    let off = offsets(sizes);
    let total: usize = sizes.iter().sum();
    let mut s = DMatrix::zeros(total, total);
    let mut rhs = DVector::zeros(total);
    for (k, (u, g)) in n.u.iter().zip(&n.g).enumerate() {
        s.view_mut((off[k], off[k]), (sizes[k], sizes[k])).copy_from(&damped(u, lambda));
        rhs.rows_mut(off[k], sizes[k]).copy_from(&(-g));
    }
    let mut inverses = vec![];
    for (j, p) in present.iter().enumerate().filter(|_| !n.w.is_empty()) {
        let v_inv = damped(&n.v[j], lambda).cholesky().ok_or_else(not_positive)?.inverse();
        let wv = &n.w[j] * &v_inv;
        let wvw = &wv * n.w[j].transpose();
        let wvg = &wv * &n.gy[j];
        let rows: Vec<(usize, usize, usize)> =
            p.iter().scan(0, |at, &(k, _)| Some((k, std::mem::replace(at, *at + sizes[k]), sizes[k]))).collect();
        for &(k, ak, pk) in &rows {
            for &(l, al, pl) in &rows {
                let mut block = s.view_mut((off[k], off[l]), (pk, pl));
                block -= wvw.view((ak, al), (pk, pl));
            }
            let mut part = rhs.rows_mut(off[k], pk);
            part += wvg.rows(ak, pk);
        }
        inverses.push(v_inv);
    }
    Ok(Schur { s, rhs, v_inverses: inverses })
}

/// The step (dx, dy) by the dense path.
pub(super) fn dense_step(
    n: &Normal,
    sizes: &[usize],
    present: &[Vec<(usize, usize)>],
    lambda: f64,
) -> Result<(DVector<f64>, Vec<DVector<f64>>)> {
    let Schur { s, rhs, v_inverses } = schur_complement(n, sizes, present, lambda)?;
    let dx = s.cholesky().ok_or_else(not_positive)?.solve(&rhs);
    let dy = back_substitute(n, sizes, present, &dx, |j, b| &v_inverses[j] * b);
    Ok((dx, dy))
}

/// dy_j = V_j^-1 (-g_y,j - W_j' dx_j) for every view, `solve(j, b)` applying V_j^-1.
fn back_substitute(
    n: &Normal,
    sizes: &[usize],
    present: &[Vec<(usize, usize)>],
    dx: &DVector<f64>,
    solve: impl Fn(usize, &DVector<f64>) -> DVector<f64>,
) -> Vec<DVector<f64>> {
    if n.w.is_empty() {
        return present.iter().map(|_| DVector::zeros(0)).collect();
    }
    let off = offsets(sizes);
    present
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let dxj: Vec<f64> =
                p.iter().flat_map(|&(k, _)| dx.rows(off[k], sizes[k]).iter().copied().collect::<Vec<_>>()).collect();
            let b = -&n.gy[j] - n.w[j].transpose() * DVector::from_vec(dxj);
            solve(j, &b)
        })
        .collect()
}

/// The bordered system of the sparse path: its lower triangle as triplets and its
/// right-hand side (dx, then each view's shared unknowns: dZ_j, or a free view's pose).
fn bordered(
    n: &Normal,
    sizes: &[usize],
    present: &[Vec<(usize, usize)>],
    lambda: f64,
) -> (Vec<Triplet<usize, usize, f64>>, Vec<f64>) {
    let off = offsets(sizes);
    let total: usize = sizes.iter().sum();
    let mut blocks: Vec<DMatrix<f64>> = n.u.iter().map(|u| damped(u, lambda)).collect();
    let mut rhs: Vec<f64> = n.g.iter().flat_map(|g| g.iter().map(|x| -x)).collect();
    let mut triplets = vec![];
    for (j, p) in present.iter().enumerate().filter(|_| !n.w.is_empty()) {
        let v = damped(&n.v[j], lambda);
        let (g, w, sh, at_z) = (&n.gy[j], &n.w[j], v.nrows() - p.len(), rhs.len());
        let mut d: DMatrix<f64> = v.view((0, 0), (sh, sh)).into_owned();
        let mut rz: DVector<f64> = -g.rows(0, sh);
        let mut at = 0;
        for (c, &(k, _)) in p.iter().enumerate() {
            let pk = sizes[k];
            let (vcc, gc) = (v[(sh + c, sh + c)], g[sh + c]);
            let v0c: DVector<f64> = v.view((0, sh + c), (sh, 1)).column(0).into_owned();
            let we: DVector<f64> = w.view((at, sh + c), (pk, 1)).column(0).into_owned();
            let b: DMatrix<f64> = w.view((at, 0), (pk, sh)) - &we * v0c.transpose() / vcc;
            blocks[k].ger(-1.0 / vcc, &we, &we, 1.0);
            for i in 0..pk {
                rhs[off[k] + i] += we[i] * gc / vcc;
                for a in 0..sh {
                    triplets.push(Triplet::new(at_z + a, off[k] + i, b[(i, a)]));
                }
            }
            d.ger(-1.0 / vcc, &v0c, &v0c, 1.0);
            rz.axpy(gc / vcc, &v0c, 1.0);
            at += pk;
        }
        for a in 0..sh {
            for c in 0..=a {
                triplets.push(Triplet::new(at_z + a, at_z + c, d[(a, c)]));
            }
        }
        rhs.extend(rz.iter());
    }
    for (k, b) in blocks.iter().enumerate() {
        for c in 0..sizes[k] {
            for r in c..sizes[k] {
                triplets.push(Triplet::new(off[k] + r, off[k] + c, b[(r, c)]));
            }
        }
    }
    debug_assert!(rhs.len() >= total);
    (triplets, rhs)
}

/// The symbolic factorisation of the sparse path's system: its pattern (which cameras share
/// which views) does not change between steps, so it is computed once per problem and the
/// steps redo the numeric factorisation only.
pub(super) type SparsePattern = OnceLock<SymbolicLlt<usize>>;

/// The step (dx, dy) by the sparse path, the symbolic factorisation taken from `pattern`
/// (computed there on the first step).
pub(super) fn sparse_step(
    n: &Normal,
    sizes: &[usize],
    present: &[Vec<(usize, usize)>],
    lambda: f64,
    pattern: &SparsePattern,
) -> Result<(DVector<f64>, Vec<DVector<f64>>)> {
    let (triplets, rhs) = bordered(n, sizes, present, lambda);
    let dim = rhs.len();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(dim, dim, &triplets)
        .map_err(|_| Error::invalid("rig", "the rig's reduced system could not be assembled"))?;
    let symbolic = match pattern.get() {
        Some(s) => s.clone(),
        None => {
            let s = SymbolicLlt::try_new(a.symbolic(), Side::Lower).map_err(|_| not_positive())?;
            pattern.get_or_init(|| s).clone()
        }
    };
    let llt = Llt::try_new_with_symbolic(symbolic, a.as_ref(), Side::Lower).map_err(|_| not_positive())?;
    let mut b = Mat::<f64>::from_fn(dim, 1, |i, _| rhs[i]);
    llt.solve_in_place(b.as_mut());
    let total: usize = sizes.iter().sum();
    let dx = DVector::from_fn(total, |i, _| b[(i, 0)]);
    if n.w.is_empty() {
        return Ok((dx, present.iter().map(|_| DVector::zeros(0)).collect()));
    }
    let off = offsets(sizes);
    let mut at_z = total;
    let dy = present
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let (v, g, w) = (damped(&n.v[j], lambda), &n.gy[j], &n.w[j]);
            let sh = v.nrows() - p.len();
            let dz = DVector::from_fn(sh, |a, _| b[(at_z + a, 0)]);
            at_z += sh;
            let mut y = DVector::zeros(sh + p.len());
            y.rows_mut(0, sh).copy_from(&dz);
            let mut at = 0;
            for (c, &(k, _)) in p.iter().enumerate() {
                let we = w.view((at, sh + c), (sizes[k], 1));
                let wdx = we.dot(&dx.rows(off[k], sizes[k]));
                let v0c = v.view((0, sh + c), (sh, 1));
                y[sh + c] = (-g[sh + c] - wdx - v0c.dot(&dz)) / v[(sh + c, sh + c)];
                at += sizes[k];
            }
            y
        })
        .collect();
    Ok((dx, dy))
}
