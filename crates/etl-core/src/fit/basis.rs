//! Bases for the fits: Chebyshev polynomials of a centred and scaled variable, and the
//! exact conversions back to monomials in the raw variable.
//!
//! Fitting in T_k(t), t = (x - centre) / half_width in [-1, 1], keeps the least-squares
//! columns nearly orthogonal (condition number of tens, not the ~1e16 of raw mA powers);
//! the monomial coefficients the paper prints are derived afterwards, exactly.

/// Highest polynomial degree the bases provide.
pub const MAX_BASIS_DEGREE: usize = 6;

/// Monomial coefficients of the Chebyshev polynomials: `CHEB_TO_MONO[k][j]` is the
/// coefficient of t^j in T_k(t).
pub(crate) const CHEB_TO_MONO: [[f64; MAX_BASIS_DEGREE + 1]; MAX_BASIS_DEGREE + 1] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-1.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, -3.0, 0.0, 4.0, 0.0, 0.0, 0.0],
    [1.0, 0.0, -8.0, 0.0, 8.0, 0.0, 0.0],
    [0.0, 5.0, 0.0, -20.0, 0.0, 16.0, 0.0],
    [-1.0, 0.0, 18.0, 0.0, -48.0, 0.0, 32.0],
];

/// Binomial coefficients C(n, k) for n, k <= 6.
pub(crate) const BINOMIAL: [[f64; MAX_BASIS_DEGREE + 1]; MAX_BASIS_DEGREE + 1] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 3.0, 3.0, 1.0, 0.0, 0.0, 0.0],
    [1.0, 4.0, 6.0, 4.0, 1.0, 0.0, 0.0],
    [1.0, 5.0, 10.0, 10.0, 5.0, 1.0, 0.0],
    [1.0, 6.0, 15.0, 20.0, 15.0, 6.0, 1.0],
];

/// Chebyshev coefficients of the monomials, the inverse of [`CHEB_TO_MONO`]:
/// `MONO_TO_CHEB[n][k]` is the coefficient of T_k in t^n. Derived from [`BINOMIAL`] by
/// t^n = 2^(1-n) sum_j C(n, j) T_(n-2j) (the T_0 term halved) rather than written out, so
/// that the table cannot disagree with the other two; every entry is a small integer over
/// a power of two, exact in f64.
pub(crate) const MONO_TO_CHEB: [[f64; MAX_BASIS_DEGREE + 1]; MAX_BASIS_DEGREE + 1] = mono_to_cheb();

const fn mono_to_cheb() -> [[f64; MAX_BASIS_DEGREE + 1]; MAX_BASIS_DEGREE + 1] {
    let mut table = [[0.0; MAX_BASIS_DEGREE + 1]; MAX_BASIS_DEGREE + 1];
    let mut n = 0;
    while n <= MAX_BASIS_DEGREE {
        let mut j = 0;
        while 2 * j <= n {
            let k = n - 2 * j;
            let halvings = if k == 0 { n } else { n - 1 };
            table[n][k] = BINOMIAL[n][j] / (1u64 << halvings) as f64;
            j += 1;
        }
        n += 1;
    }
    table
}

/// T_0(t) .. T_6(t) by the three-term recurrence T_{k+1} = 2 t T_k - T_{k-1}.
#[inline]
pub fn chebyshev_values(t: f64) -> [f64; MAX_BASIS_DEGREE + 1] {
    let mut v = [0.0; MAX_BASIS_DEGREE + 1];
    v[0] = 1.0;
    v[1] = t;
    for k in 2..=MAX_BASIS_DEGREE {
        v[k] = 2.0 * t * v[k - 1] - v[k - 2];
    }
    v
}

/// Coefficients of sum_k c_k T_k(t) as a polynomial in t (index = power).
pub fn chebyshev_to_monomial(cheb: &[f64; MAX_BASIS_DEGREE + 1]) -> [f64; MAX_BASIS_DEGREE + 1] {
    let mut mono = [0.0; MAX_BASIS_DEGREE + 1];
    for (ck, row) in cheb.iter().zip(CHEB_TO_MONO.iter()) {
        for (m, r) in mono.iter_mut().zip(row.iter()) {
            *m += ck * r;
        }
    }
    mono
}

/// Monomial coefficients of t^i as a polynomial in the raw variable x, where
/// t = (x - centre) / half_width: entry j is C(i, j) (-centre)^(i-j) / half_width^i.
/// Entries above `i` are zero; `i` is clamped to [`MAX_BASIS_DEGREE`].
pub fn scaled_power_in_raw(i: usize, centre: f64, half_width: f64) -> [f64; MAX_BASIS_DEGREE + 1] {
    let i = i.min(MAX_BASIS_DEGREE);
    let mut out = [0.0; MAX_BASIS_DEGREE + 1];
    let inv_h = libm::pow(half_width, -(i as f64));
    for (j, o) in out.iter_mut().enumerate().take(i + 1) {
        *o = BINOMIAL[i][j] * libm::pow(-centre, (i - j) as f64) * inv_h;
    }
    out
}

/// Coefficients of sum_k b_k t^k, t = (x - centre) / half_width, as a polynomial in x.
pub fn scaled_to_raw(
    scaled: &[f64; MAX_BASIS_DEGREE + 1],
    centre: f64,
    half_width: f64,
) -> [f64; MAX_BASIS_DEGREE + 1] {
    let mut raw = [0.0; MAX_BASIS_DEGREE + 1];
    for (i, &b) in scaled.iter().enumerate() {
        if b == 0.0 {
            continue;
        }
        let p = scaled_power_in_raw(i, centre, half_width);
        for (r, pj) in raw.iter_mut().zip(p.iter()) {
            *r += b * pj;
        }
    }
    raw
}

/// Horner evaluation of sum_k c_k x^k.
#[inline]
pub fn horner(c: &[f64; MAX_BASIS_DEGREE + 1], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The derived table inverts the written one exactly: their product is the identity.
    #[test]
    fn monomial_to_chebyshev_inverts_chebyshev_to_monomial() {
        for n in 0..=MAX_BASIS_DEGREE {
            for j in 0..=MAX_BASIS_DEGREE {
                let product: f64 = (0..=MAX_BASIS_DEGREE).map(|k| MONO_TO_CHEB[n][k] * CHEB_TO_MONO[k][j]).sum();
                assert_eq!(product, if n == j { 1.0 } else { 0.0 }, "t^{n} -> t^{j}");
            }
        }
        assert_eq!(MONO_TO_CHEB[4], [0.375, 0.0, 0.5, 0.0, 0.125, 0.0, 0.0]);
        assert_eq!(MONO_TO_CHEB[5], [0.0, 0.625, 0.0, 0.3125, 0.0, 0.0625, 0.0]);
    }

    #[test]
    fn chebyshev_tables_agree_with_the_recurrence_and_cosines() {
        for &t in &[-1.0, -0.37, 0.0, 0.5, 0.99, 1.0] {
            let v = chebyshev_values(t);
            let theta = libm::acos(t);
            for k in 0..=MAX_BASIS_DEGREE {
                let mut unit = [0.0; MAX_BASIS_DEGREE + 1];
                unit[k] = 1.0;
                let mono = chebyshev_to_monomial(&unit);
                assert!((horner(&mono, t) - v[k]).abs() < 1e-13);
                assert!((libm::cos(k as f64 * theta) - v[k]).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn change_of_variable_is_exact() {
        let scaled = [0.3, -1.2, 0.7, 2.0, -0.4, 0.05, 0.9];
        let (c, h) = (130.0, 130.0);
        let raw = scaled_to_raw(&scaled, c, h);
        for &x in &[0.0, 13.0, 80.0, 200.0, 260.0] {
            let a = horner(&scaled, (x - c) / h);
            let b = horner(&raw, x);
            assert!((a - b).abs() < 1e-12 * (1.0 + a.abs()), "{a} {b}");
        }
    }
}
