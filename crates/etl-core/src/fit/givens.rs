//! [`GivensQr`]: a streamed weighted linear least-squares accumulator.
//!
//! Each observation row is folded into an upper-triangular factor R (and Q^T y) by Givens
//! rotations as it arrives (the row-updating QR of Gentleman 1973, Miller's AS 274), so the
//! memory is one N x N triangle whatever the number of rows, and the conditioning is that
//! of the design matrix itself: the normal equations would square it.

use crate::error::{Error, Result};

/// Largest magnitude accepted in a row, a right-hand side or sqrt(weight) times either.
///
/// Keeps every intermediate (squares, sums of squares over up to 2^53 rows) finite. Callers
/// that centre and scale their variables stay many orders of magnitude below it.
pub const GIVENS_MAX_ABS: f64 = 1e100;

/// Relative size below which a diagonal element of R counts as zero when solving: the
/// columns are then (numerically) dependent and the solve is refused.
pub const GIVENS_RANK_TOL: f64 = 1e-12;

/// Streamed weighted least squares for up to `N` unknowns: minimises
/// sum_i w_i (row_i . x - y_i)^2.
///
/// Only the first `n` entries of each row are used (`n` set at construction, `1 <= n <= N`),
/// so one type serves fits of several sizes. No allocation; `N * N + 2 N + 4` numbers.
///
/// ```
/// use etl_core::fit::GivensQr;
/// // y = 2 + 3 x, sampled without noise.
/// let mut qr = GivensQr::<2>::new(2).unwrap();
/// for x in [0.0, 1.0, 2.0, 3.0] {
///     qr.add_row(&[1.0, x], 2.0 + 3.0 * x, 1.0).unwrap();
/// }
/// let sol = qr.solve().unwrap();
/// assert!((sol[0] - 2.0).abs() < 1e-12 && (sol[1] - 3.0).abs() < 1e-12);
/// assert!(qr.residual_sum_of_squares() < 1e-20);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GivensQr<const N: usize> {
    n: usize,
    r: [[f64; N]; N],
    qty: [f64; N],
    rss: f64,
    rows: usize,
    weight_sum: f64,
}

impl<const N: usize> GivensQr<N> {
    /// An empty accumulator for `n` unknowns.
    ///
    /// Errors: `n == 0` or `n > N` ([`Error::InvalidArgument`]).
    pub fn new(n: usize) -> Result<Self> {
        if n == 0 || n > N {
            return Err(Error::InvalidArgument { what: "number of unknowns must be between 1 and the capacity N" });
        }
        Ok(GivensQr { n, r: [[0.0; N]; N], qty: [0.0; N], rss: 0.0, rows: 0, weight_sum: 0.0 })
    }

    /// An empty accumulator for all `N` unknowns (infallible [`Self::new`]`(N)`).
    pub const fn full() -> Self {
        GivensQr { n: N, r: [[0.0; N]; N], qty: [0.0; N], rss: 0.0, rows: 0, weight_sum: 0.0 }
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.n
    }

    /// The upper-triangular factor R (rows and columns beyond [`Self::unknowns`] are zero).
    pub fn r_factor(&self) -> &[[f64; N]; N] {
        &self.r
    }

    /// Q^T y: the right-hand side rotated with the rows (R x = Q^T y solves the fit).
    pub fn qty(&self) -> &[f64; N] {
        &self.qty
    }

    /// Rows added with a positive weight.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Sum of the weights of the rows added.
    pub fn weight_sum(&self) -> f64 {
        self.weight_sum
    }

    /// Weighted residual sum of squares of the least-squares solution of the rows so far,
    /// sum_i w_i (row_i . x* - y_i)^2 (exact in exact arithmetic; no second pass needed).
    pub fn residual_sum_of_squares(&self) -> f64 {
        self.rss
    }

    /// Folds in the observation `row . x = y` with weight `weight` (>= 0; 0 ignores it).
    ///
    /// Errors (the accumulator is unchanged): a non-finite entry, weight or `y`
    /// ([`Error::NotFinite`]); a negative weight ([`Error::InvalidArgument`]); a magnitude
    /// above [`GIVENS_MAX_ABS`] ([`Error::OutOfRange`]).
    pub fn add_row(&mut self, row: &[f64; N], y: f64, weight: f64) -> Result<()> {
        if !weight.is_finite() {
            return Err(Error::NotFinite { what: "weight" });
        }
        if weight < 0.0 {
            return Err(Error::InvalidArgument { what: "weight must not be negative" });
        }
        if !y.is_finite() {
            return Err(Error::NotFinite { what: "least-squares right-hand side" });
        }
        let sw = libm::sqrt(weight);
        let mut x = [0.0; N];
        for (xi, &ri) in x.iter_mut().zip(row.iter()).take(self.n) {
            if !ri.is_finite() {
                return Err(Error::NotFinite { what: "least-squares row" });
            }
            *xi = sw * ri;
            if !(xi.abs() <= GIVENS_MAX_ABS) {
                return Err(Error::OutOfRange {
                    what: "least-squares row entry times sqrt(weight)",
                    value: *xi,
                    min: -GIVENS_MAX_ABS,
                    max: GIVENS_MAX_ABS,
                });
            }
        }
        let mut yy = sw * y;
        if !(yy.abs() <= GIVENS_MAX_ABS) {
            return Err(Error::OutOfRange {
                what: "least-squares right-hand side times sqrt(weight)",
                value: yy,
                min: -GIVENS_MAX_ABS,
                max: GIVENS_MAX_ABS,
            });
        }
        if weight == 0.0 {
            return Ok(());
        }
        // n <= N always; the min lets the compiler drop the bounds checks (no panic path).
        let n = self.n.min(N);
        for k in 0..n {
            let xk = x[k];
            if xk == 0.0 {
                continue;
            }
            let rkk = self.r[k][k];
            // Entries are bounded by GIVENS_MAX_ABS (1e100), so the squares cannot overflow
            // and the plain square root is exact enough and much cheaper than hypot.
            let rho = libm::sqrt(rkk * rkk + xk * xk);
            let inv = 1.0 / rho;
            let (c, s) = (rkk * inv, xk * inv);
            self.r[k][k] = rho;
            for j in k + 1..n {
                let t = self.r[k][j];
                self.r[k][j] = c * t + s * x[j];
                x[j] = c * x[j] - s * t;
            }
            let t = self.qty[k];
            self.qty[k] = c * t + s * yy;
            yy = c * yy - s * t;
        }
        self.rss += yy * yy;
        self.rows += 1;
        self.weight_sum += weight;
        Ok(())
    }

    /// The least-squares solution (entries beyond `n` are zero).
    ///
    /// Errors: no rows ([`Error::TooFew`]); a diagonal element of R at most
    /// [`GIVENS_RANK_TOL`] times the largest: the rows do not determine the unknowns
    /// ([`Error::Degenerate`]).
    pub fn solve(&self) -> Result<[f64; N]> {
        let n = self.n.min(N);
        if self.rows < n {
            return Err(Error::TooFew { what: "least-squares rows", needed: n, got: self.rows });
        }
        let dmax = (0..n).fold(0.0f64, |m, k| m.max(self.r[k][k].abs()));
        if !(dmax > 0.0) || (0..n).any(|k| !(self.r[k][k].abs() > GIVENS_RANK_TOL * dmax)) {
            return Err(Error::Degenerate {
                what: "the least-squares columns are linearly dependent (rank-deficient)",
            });
        }
        let mut sol = [0.0; N];
        for k in (0..n).rev() {
            let mut s = self.qty[k];
            for j in k + 1..n {
                s -= self.r[k][j] * sol[j];
            }
            sol[k] = s / self.r[k][k];
        }
        if sol.iter().all(|v| v.is_finite()) {
            Ok(sol)
        } else {
            Err(Error::Degenerate { what: "least-squares solution is not finite (ill-conditioned columns)" })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_fit_matches_closed_form() {
        // Weighted mean: the 1-unknown problem x = y_i with weights w_i.
        let mut qr = GivensQr::<3>::new(1).unwrap();
        let data = [(1.0, 1.0), (2.0, 3.0), (4.0, 0.5)];
        for &(y, w) in &data {
            qr.add_row(&[1.0, 99.0, 99.0], y, w).unwrap();
        }
        let mean = (1.0 + 6.0 + 2.0) / 4.5;
        let sol = qr.solve().unwrap();
        assert!((sol[0] - mean).abs() < 1e-14 && sol[1] == 0.0);
        let rss: f64 = data.iter().map(|&(y, w)| w * (y - mean) * (y - mean)).sum();
        assert!((qr.residual_sum_of_squares() - rss).abs() < 1e-13);
        assert_eq!(qr.rows(), 3);
        assert!((qr.weight_sum() - 4.5).abs() < 1e-15);
    }

    #[test]
    fn bad_input_leaves_the_accumulator_unchanged() {
        let mut qr = GivensQr::<2>::new(2).unwrap();
        qr.add_row(&[1.0, 2.0], 3.0, 1.0).unwrap();
        let before = qr;
        assert!(matches!(qr.add_row(&[f64::NAN, 1.0], 1.0, 1.0), Err(Error::NotFinite { .. })));
        assert!(matches!(qr.add_row(&[1.0, 1.0], f64::INFINITY, 1.0), Err(Error::NotFinite { .. })));
        assert!(matches!(qr.add_row(&[1.0, 1.0], 1.0, -1.0), Err(Error::InvalidArgument { .. })));
        assert!(matches!(qr.add_row(&[1e200, 1.0], 1.0, 1.0), Err(Error::OutOfRange { .. })));
        assert_eq!(qr, before);
        assert!(GivensQr::<2>::new(3).is_err() && GivensQr::<2>::new(0).is_err());
    }

    #[test]
    fn dependent_columns_are_refused() {
        let mut qr = GivensQr::<2>::new(2).unwrap();
        assert!(matches!(qr.solve(), Err(Error::TooFew { .. })));
        for x in [1.0, 2.0, 3.0] {
            qr.add_row(&[x, 2.0 * x], x, 1.0).unwrap();
        }
        assert!(matches!(qr.solve(), Err(Error::Degenerate { .. })));
    }
}
