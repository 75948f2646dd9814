//! Inverse of a small symmetric positive definite matrix by a diagonally scaled Cholesky
//! factorisation, with a certificate of full numerical rank; the solvers fall back to the
//! SVD ([`super::svd::sym_pinv`]) when the certificate fails.

#![allow(clippy::needless_range_loop)] // small fixed-size linear algebra reads best indexed

use super::svd::sym_pinv;

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
    // Cholesky of S (lower L, row-major).
    let mut l = [[0.0; K]; K];
    for i in 0..K {
        for j in 0..=i {
            let mut s = a[i][j] / (d[i] * d[j]);
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0) {
                    return None;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // L^-1 (lower) by forward substitution, column by column.
    let mut li = [[0.0; K]; K];
    for j in 0..K {
        li[j][j] = 1.0 / l[j][j];
        for i in (j + 1)..K {
            let mut s = 0.0;
            for k in j..i {
                s -= l[i][k] * li[k][j];
            }
            li[i][j] = s / l[i][i];
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
pub(crate) fn psd_inverse<const K: usize>(a: &[[f64; K]; K], rank_tolerance: f64) -> ([[f64; K]; K], usize) {
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
