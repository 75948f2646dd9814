//! Singular value decomposition of a small square matrix by one-sided Jacobi rotations
//! (Hestenes 1958), accurate to high relative precision even for graded matrices, which
//! is why the solvers use it for their rank decisions.

/// A = U diag(s) V^T for an N x N matrix.
///
/// Stored column-wise: `u[j]` is the j-th left singular vector, `v[j]` the j-th right one.
/// Singular values are >= 0 and not sorted; `u[j]` is zero where `s[j]` is zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Svd<const N: usize> {
    /// Left singular vectors, one per column index.
    pub u: [[f64; N]; N],
    /// Singular values.
    pub s: [f64; N],
    /// Right singular vectors, one per column index.
    pub v: [[f64; N]; N],
}

/// Sweeps allowed; Jacobi converges quadratically, 6-10 sweeps are typical.
const MAX_SWEEPS: usize = 60;

impl<const N: usize> Svd<N> {
    /// SVD of the matrix whose j-th *column* is `cols[j]`.
    ///
    /// Non-finite input gives non-finite singular values (the caller checks); it never
    /// loops forever (at most `MAX_SWEEPS` sweeps).
    pub fn of_columns(mut cols: [[f64; N]; N]) -> Self {
        let mut v = [[0.0; N]; N];
        for (j, vj) in v.iter_mut().enumerate() {
            vj[j] = 1.0;
        }
        for _ in 0..MAX_SWEEPS {
            let mut rotated = false;
            for p in 0..N {
                for q in (p + 1)..N {
                    let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                    for i in 0..N {
                        alpha += cols[p][i] * cols[p][i];
                        beta += cols[q][i] * cols[q][i];
                        gamma += cols[p][i] * cols[q][i];
                    }
                    if gamma == 0.0 || !(gamma.abs() > 1e-15 * libm::sqrt(alpha * beta)) {
                        continue;
                    }
                    rotated = true;
                    let zeta = (beta - alpha) / (2.0 * gamma);
                    let t = libm::copysign(1.0, zeta) / (zeta.abs() + libm::sqrt(1.0 + zeta * zeta));
                    let c = 1.0 / libm::sqrt(1.0 + t * t);
                    let s = c * t;
                    for i in 0..N {
                        let (a, b) = (cols[p][i], cols[q][i]);
                        cols[p][i] = c * a - s * b;
                        cols[q][i] = s * a + c * b;
                        let (a, b) = (v[p][i], v[q][i]);
                        v[p][i] = c * a - s * b;
                        v[q][i] = s * a + c * b;
                    }
                }
            }
            if !rotated {
                break;
            }
        }
        let mut s = [0.0; N];
        let mut u = [[0.0; N]; N];
        for j in 0..N {
            let n = libm::sqrt(cols[j].iter().map(|x| x * x).sum::<f64>());
            s[j] = n;
            if n > 0.0 {
                for i in 0..N {
                    u[j][i] = cols[j][i] / n;
                }
            }
        }
        Svd { u, s, v }
    }

    /// SVD of a row-major matrix `a[row][col]`.
    pub fn of_rows(a: &[[f64; N]; N]) -> Self {
        let mut cols = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                cols[j][i] = a[i][j];
            }
        }
        Self::of_columns(cols)
    }

    /// Largest singular value.
    pub fn max_singular_value(&self) -> f64 {
        self.s.iter().fold(0.0f64, |m, &x| m.max(x))
    }

    /// Number of singular values above `rel_tol` times the largest.
    pub fn rank(&self, rel_tol: f64) -> usize {
        let smax = self.max_singular_value();
        self.s.iter().filter(|&&x| x > rel_tol * smax && x > 0.0).count()
    }
}

/// Pseudo-inverse of the symmetric positive semi-definite `a` through the SVD of
/// D^-1 a D^-1 (D = sqrt(diag a)), dropping singular values below `tol` times the largest.
/// Returns the pseudo-inverse and the rank.
pub fn sym_pinv<const K: usize>(a: &[[f64; K]; K], tol: f64) -> ([[f64; K]; K], usize) {
    let mut d = [1.0; K];
    for i in 0..K {
        if a[i][i] > 0.0 {
            d[i] = libm::sqrt(a[i][i]);
        }
    }
    let mut cols = [[0.0; K]; K];
    for i in 0..K {
        for j in 0..K {
            cols[j][i] = a[i][j] / (d[i] * d[j]);
        }
    }
    let svd = Svd::of_columns(cols);
    let smax = svd.max_singular_value();
    let mut inv = [[0.0; K]; K];
    let mut rank = 0;
    for k in 0..K {
        let s = svd.s[k];
        if !(s > tol * smax && s > 0.0) {
            continue;
        }
        rank += 1;
        for i in 0..K {
            for j in 0..K {
                inv[i][j] += svd.v[k][i] * svd.u[k][j] / s / (d[i] * d[j]);
            }
        }
    }
    (inv, rank)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reconstructs_a_graded_matrix() {
        let a = [[4.0, 1e-3, 2.0], [1e-3, 1e-6, 3e-7], [2.0, 3e-7, 9.0]];
        let d = Svd::of_rows(&a);
        for i in 0..3 {
            for j in 0..3 {
                let r: f64 = (0..3).map(|k| d.u[k][i] * d.s[k] * d.v[k][j]).sum();
                assert!((r - a[i][j]).abs() < 1e-14 * 10.0, "{i}{j}: {r} vs {}", a[i][j]);
            }
        }
        assert_eq!(d.rank(1e-13), 3);
    }

    #[test]
    fn detects_rank_deficiency() {
        let a = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [1.0, 0.0, 1.0]];
        assert_eq!(Svd::of_rows(&a).rank(1e-12), 2);
    }
}
