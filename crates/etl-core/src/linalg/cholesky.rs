//! Cholesky factorisations of small symmetric matrices, all through one diagonally
//! scaled factor (`scaled_upper_factor`): the certified inverse of a positive definite
//! matrix ([`spd_inverse`], with the SVD fallback [`psd_inverse`]) and the semidefinite
//! factor of normal equations ([`normal_equations_factor`]) that the dense
//! Levenberg-Marquardt step starts from.

use super::svd::sym_pinv;

/// What [`scaled_upper_factor`] does with a pivot at or below its floor.
#[derive(Debug, Clone, Copy, PartialEq)]
enum SmallPivot {
    /// The matrix is refused (`None`).
    Refuse,
    /// The pivot's row of R stays zero: that direction carries no information.
    ZeroRow,
}

/// The upper triangular R with R^T R = S = D^-1 A D^-1 (unit diagonal), row by row:
///
/// ```text
/// R_ii = sqrt(S_ii - sum_{k<i} R_ki^2),   R_ij = (S_ij - sum_{k<i} R_ki R_kj) / R_ii  (j > i)
/// ```
///
/// `upper(i, j)` gives A_ij for i <= j (which triangle of a stored matrix is read is the
/// caller's choice: the results are then bit for bit those of that triangle); `d` = sqrt
/// of the diagonal, positive. A pivot S_ii - sum R_ki^2 not above `floor` is handled as
/// `small` says.
fn scaled_upper_factor<const K: usize>(
    upper: impl Fn(usize, usize) -> f64,
    d: &[f64; K],
    floor: f64,
    small: SmallPivot,
) -> Option<[[f64; K]; K]> {
    let mut r = [[0.0; K]; K];
    for i in 0..K {
        let mut diag = upper(i, i) / (d[i] * d[i]);
        for k in 0..i {
            diag -= r[k][i] * r[k][i];
        }
        if !(diag > floor) {
            match small {
                SmallPivot::Refuse => return None,
                SmallPivot::ZeroRow => continue, // row i stays zero
            }
        }
        let rii = libm::sqrt(diag);
        r[i][i] = rii;
        for j in (i + 1)..K {
            let mut v = upper(i, j) / (d[i] * d[j]);
            for k in 0..i {
                v -= r[k][i] * r[k][j];
            }
            r[i][j] = v / rii;
        }
    }
    Some(r)
}

/// R with R^T R = A (A = J^T J, upper triangle given) and Q^T r = R^-T g (g = J^T r), by
/// the Cholesky factorisation of the diagonally scaled A (unit diagonal), semidefinite: a
/// pivot below 1e-14 of its scaled diagonal ends its row at zero (that direction then
/// carries no information; the SVD of the step finds the rank). A zero or negative
/// diagonal entry is scaled by 1.
pub fn normal_equations_factor<const N: usize>(a: &[[f64; N]; N], g: &[f64; N]) -> ([[f64; N]; N], [f64; N]) {
    let d: [f64; N] = core::array::from_fn(|i| {
        let v = a[i][i];
        if v > 0.0 {
            libm::sqrt(v)
        } else {
            1.0
        }
    });
    let mut r = scaled_upper_factor(|i, j| a[i][j], &d, 1e-14, SmallPivot::ZeroRow).unwrap_or([[0.0; N]; N]);
    // Forward substitution R_scaled^T q = D^-1 g (a zero row gives q_i = 0).
    let mut qtf = [0.0; N];
    for i in 0..N {
        let mut v = g[i] / d[i];
        for k in 0..i {
            v -= r[k][i] * qtf[k];
        }
        qtf[i] = if r[i][i] > 0.0 { v / r[i][i] } else { 0.0 };
    }
    // Unscale: R_scaled = R D^-1 column-wise, so R = R_scaled D.
    for row in r.iter_mut() {
        for (rij, dj) in row.iter_mut().zip(d.iter()) {
            *rij *= dj;
        }
    }
    (r, qtf)
}

/// A^-1 for a symmetric `a` (full square given), when A is certified positive definite
/// with every eigenvalue of the scaled S = D^-1 A D^-1 (D = sqrt(diag A), unit diagonal)
/// above `100 rank_tolerance` times the largest.
///
/// With S = L L^T: lambda_min(S) = 1 / ||L^-1||_2^2 >= 1 / ||L^-1||_F^2 and
/// lambda_max(S) <= trace S = K, so 1 / ||L^-1||_F^2 > 100 `rank_tolerance` K certifies
/// that a rank decision by the SVD at `rank_tolerance` would keep every direction (the
/// factor 100 leaves room for rounding). `None` when A is not certified (the caller then
/// decides the rank by the SVD) or not finite.
pub fn spd_inverse<const K: usize>(a: &[[f64; K]; K], rank_tolerance: f64) -> Option<[[f64; K]; K]> {
    let mut d = [0.0; K];
    for i in 0..K {
        let v = a[i][i];
        if !(v > 0.0 && v.is_finite()) {
            return None;
        }
        d[i] = libm::sqrt(v);
    }
    // S = L L^T with L = R^T; the lower triangle of `a` is read.
    let r = scaled_upper_factor(|i, j| a[j][i], &d, 0.0, SmallPivot::Refuse)?;
    // L^-1 (lower) by forward substitution, column by column (L_ik = R_ki).
    let mut li = [[0.0; K]; K];
    for j in 0..K {
        li[j][j] = 1.0 / r[j][j];
        for i in (j + 1)..K {
            let mut s = 0.0;
            for k in j..i {
                s -= r[k][i] * li[k][j];
            }
            li[i][j] = s / r[i][i];
        }
    }
    let frob2: f64 = li.iter().flatten().map(|v| v * v).sum();
    if !(frob2.is_finite() && 100.0 * rank_tolerance * K as f64 * frob2 < 1.0) {
        return None;
    }
    // A^-1 = D^-1 L^-T L^-1 D^-1.
    let mut inv = [[0.0; K]; K];
    for i in 0..K {
        for j in 0..K {
            let mut s = 0.0;
            for k in i.max(j)..K {
                s += li[k][i] * li[k][j];
            }
            inv[i][j] = s / (d[i] * d[j]);
        }
    }
    Some(inv)
}

/// (A^-1, K) when [`spd_inverse`] certifies A, else the SVD pseudo-inverse and its rank
/// ([`sym_pinv`]): the fast path for the usual well-posed case, the honest rank otherwise.
pub fn psd_inverse<const K: usize>(a: &[[f64; K]; K], rank_tolerance: f64) -> ([[f64; K]; K], usize) {
    match spd_inverse(a, rank_tolerance) {
        Some(inv) => (inv, K),
        None => sym_pinv(a, rank_tolerance),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverts_a_graded_matrix() {
        let a = [[4.0, 1e-3, 2.0], [1e-3, 1e-6, 3e-7], [2.0, 3e-7, 9.0]];
        let inv = spd_inverse(&a, 1e-13).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i][k] * inv[k][j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-9, "{i}{j}: {p}");
            }
        }
    }

    #[test]
    fn refuses_singular_indefinite_and_nearly_singular() {
        assert!(spd_inverse(&[[1.0, 2.0], [2.0, 4.0]], 1e-13).is_none());
        assert!(spd_inverse(&[[1.0, 2.0], [2.0, 1.0]], 1e-13).is_none());
        assert!(spd_inverse(&[[1.0, 0.0], [0.0, 0.0]], 1e-13).is_none());
        assert!(spd_inverse(&[[1.0, 1.0 - 1e-14], [1.0 - 1e-14, 1.0]], 1e-13).is_none());
        assert!(spd_inverse(&[[f64::NAN, 0.0], [0.0, 1.0]], 1e-13).is_none());
        assert!(spd_inverse(&[[1.0, 0.5], [0.5, 1.0]], 1e-13).is_some());
    }
}
