//! [`PolyFit`]: streamed weighted least-squares polynomials of degree 1..6 in one variable.

use serde::{Deserialize, Serialize};

use super::basis::{chebyshev_to_monomial, chebyshev_values, horner, scaled_to_raw, MAX_BASIS_DEGREE};
use super::givens::GivensQr;
use crate::error::{count_in_range, finite, Error, Result};

/// Highest degree [`PolyFit`] accepts.
pub const MAX_POLY_DEGREE: usize = MAX_BASIS_DEGREE;

/// A polynomial in x of degree <= 6, held in the centred and scaled variable
/// t = (x - x_centre) / x_half_width so that evaluation is accurate; the raw monomial
/// coefficients are available from [`Polynomial::monomial_coefficients`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Polynomial {
    /// Degree of the fit that produced it (entries of `scaled` above it are zero then);
    /// informational: evaluation uses all of `scaled`.
    pub degree: usize,
    /// Centre of the fitted range of x.
    pub x_centre: f64,
    /// Half the width of the fitted range of x (> 0).
    pub x_half_width: f64,
    /// Coefficients of t^0 .. t^6.
    pub scaled: [f64; MAX_POLY_DEGREE + 1],
}

impl Polynomial {
    /// p(x). Outside the fitted range this extrapolates (no error): the range is the
    /// caller's to keep.
    ///
    /// Errors: `x` or the result not finite ([`Error::NotFinite`]); a zero or non-finite
    /// `x_half_width` ([`Error::Degenerate`]).
    pub fn eval(&self, x: f64) -> Result<f64> {
        finite(x, "x")?;
        if !(self.x_half_width.is_finite() && self.x_half_width != 0.0 && self.x_centre.is_finite()) {
            return Err(Error::Degenerate { what: "polynomial scaling (x_centre, x_half_width) is not usable" });
        }
        let t = (x - self.x_centre) / self.x_half_width;
        finite(horner(&self.scaled, t), "polynomial value")
    }

    /// Coefficients c_0 .. c_6 of p(x) = sum_k c_k x^k in the raw variable (the form the
    /// paper prints, e.g. kf0..kf3 of Eq. 12). Summing them at raw x loses digits to
    /// cancellation when |x_centre| >> x_half_width; prefer [`Self::eval`].
    ///
    /// Errors: the conversion overflows ([`Error::NotFinite`]).
    pub fn monomial_coefficients(&self) -> Result<[f64; MAX_POLY_DEGREE + 1]> {
        let raw = scaled_to_raw(&self.scaled, self.x_centre, self.x_half_width);
        if raw.iter().all(|c| c.is_finite()) {
            Ok(raw)
        } else {
            Err(Error::NotFinite { what: "monomial coefficients" })
        }
    }
}

/// Streamed weighted least-squares fit of a polynomial of degree 1..6 in x over a range
/// given up front (used to centre and scale x into [-1, 1]).
///
/// Rows are Chebyshev polynomials of the scaled variable folded into a Givens QR
/// ([`GivensQr`]): no normal equations, no raw powers of mA, no allocation. The fit is
/// converted back to monomials in t for the returned [`Polynomial`].
///
/// ```
/// use etl_core::fit::PolyFit;
/// // f(E) = 50 - 0.1 E + 2e-4 E^2 over 0..260 mA.
/// let mut fit = PolyFit::new(2, [0.0, 260.0]).unwrap();
/// for i in 0..=26 {
///     let e = 10.0 * i as f64;
///     fit.add(e, 50.0 - 0.1 * e + 2e-4 * e * e).unwrap();
/// }
/// let (p, rms) = fit.solve().unwrap();
/// let c = p.monomial_coefficients().unwrap();
/// assert!((c[0] - 50.0).abs() < 1e-9 && (c[1] + 0.1).abs() < 1e-12 && (c[2] - 2e-4).abs() < 1e-15);
/// assert!(rms < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolyFit {
    degree: usize,
    x_range: [f64; 2],
    x_centre: f64,
    x_half_width: f64,
    qr: GivensQr<{ MAX_POLY_DEGREE + 1 }>,
    distinct_x: [f64; MAX_POLY_DEGREE + 1],
    n_distinct_x: usize,
}

impl PolyFit {
    /// An empty fit of degree `degree` (1..=6) for x in `x_range` = [min, max].
    ///
    /// Errors: degree outside 1..=6 ([`Error::OutOfRange`]); a non-finite range
    /// ([`Error::NotFinite`]); min >= max or a width that overflows
    /// ([`Error::InvalidArgument`]).
    pub fn new(degree: usize, x_range: [f64; 2]) -> Result<Self> {
        count_in_range(degree, 1, MAX_POLY_DEGREE, "polynomial degree")?;
        let [lo, hi] = x_range;
        finite(lo, "x_range min")?;
        finite(hi, "x_range max")?;
        let half = 0.5 * hi - 0.5 * lo;
        if !(lo < hi) || !(half > 0.0) || !half.is_finite() {
            return Err(Error::InvalidArgument { what: "x_range must be [min, max] with min < max" });
        }
        Ok(PolyFit {
            degree,
            x_range,
            x_centre: 0.5 * lo + 0.5 * hi,
            x_half_width: half,
            qr: GivensQr::new(degree + 1)?,
            distinct_x: [0.0; MAX_POLY_DEGREE + 1],
            n_distinct_x: 0,
        })
    }

    /// Degree being fitted.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Samples added with a positive weight.
    pub fn samples(&self) -> usize {
        self.qr.rows()
    }

    /// Adds the sample (x, y) with weight 1.
    pub fn add(&mut self, x: f64, y: f64) -> Result<()> {
        self.add_weighted(x, y, 1.0)
    }

    /// Adds the sample (x, y) with weight `weight` (>= 0; a weight of 0 ignores it).
    ///
    /// Errors (the fit is unchanged): non-finite x, y or weight ([`Error::NotFinite`]); x
    /// outside the range given to [`PolyFit::new`] ([`Error::OutOfRange`]); a negative
    /// weight ([`Error::InvalidArgument`]); |y| or sqrt(weight) too large to accumulate
    /// safely (above 1e100, [`Error::OutOfRange`]).
    pub fn add_weighted(&mut self, x: f64, y: f64, weight: f64) -> Result<()> {
        finite(x, "x")?;
        let [lo, hi] = self.x_range;
        if !(x >= lo && x <= hi) {
            return Err(Error::OutOfRange { what: "x (outside the fit's range)", value: x, min: lo, max: hi });
        }
        let t = ((x - self.x_centre) / self.x_half_width).clamp(-1.0, 1.0);
        let mut row = chebyshev_values(t);
        for v in row.iter_mut().skip(self.degree + 1) {
            *v = 0.0;
        }
        self.qr.add_row(&row, y, weight)?;
        if weight > 0.0
            && self.n_distinct_x < self.distinct_x.len()
            && !self.distinct_x.iter().take(self.n_distinct_x).any(|&v| v == x)
        {
            self.distinct_x[self.n_distinct_x] = x;
            self.n_distinct_x += 1;
        }
        Ok(())
    }

    /// The least-squares polynomial and the weighted RMS of its residuals,
    /// sqrt(sum w_i r_i^2 / sum w_i) (the plain RMS for unit weights), in y's unit.
    ///
    /// Errors: fewer samples, or fewer distinct x, than degree + 1 ([`Error::TooFew`]); a
    /// numerically rank-deficient system ([`Error::Degenerate`]).
    pub fn solve(&self) -> Result<(Polynomial, f64)> {
        let needed = self.degree + 1;
        if self.qr.rows() < needed {
            return Err(Error::TooFew { what: "samples", needed, got: self.qr.rows() });
        }
        if self.n_distinct_x < needed {
            return Err(Error::TooFew { what: "distinct x values", needed, got: self.n_distinct_x });
        }
        let cheb = self.qr.solve()?;
        let scaled = chebyshev_to_monomial(&cheb);
        let rms = libm::sqrt(self.qr.residual_sum_of_squares() / self.qr.weight_sum());
        if !(rms.is_finite() && scaled.iter().all(|c| c.is_finite())) {
            return Err(Error::Degenerate { what: "polynomial fit is not finite" });
        }
        Ok((Polynomial { degree: self.degree, x_centre: self.x_centre, x_half_width: self.x_half_width, scaled }, rms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// The paper rig's fx(E) = 5380 - 7 E + 0.02 E^2 - 3e-5 E^3 (px), E in mA: a cubic with
    /// raw coefficients over 8 orders of magnitude, recovered exactly from clean samples.
    #[test]
    fn recovers_a_raw_cubic_to_1e_12_relative() {
        let kf = [5380.0, -7.0, 0.02, -3e-5];
        let mut fit = PolyFit::new(3, [80.0, 225.0]).unwrap();
        for i in 0..=29 {
            let e = 80.0 + 5.0 * i as f64;
            fit.add(e, ((kf[3] * e + kf[2]) * e + kf[1]) * e + kf[0]).unwrap();
        }
        let (p, rms) = fit.solve().unwrap();
        let c = p.monomial_coefficients().unwrap();
        for k in 0..4 {
            assert!((c[k] - kf[k]).abs() <= 1e-9 * kf[k].abs(), "c{k} = {} vs {}", c[k], kf[k]);
        }
        assert!(c[4..].iter().all(|&x| x == 0.0));
        assert!(rms < 1e-9);
        assert!((p.eval(150.0).unwrap() - (5380.0 - 1050.0 + 450.0 - 101.25)).abs() < 1e-9);
    }

    #[test]
    fn degree_six_on_a_wide_offset_range() {
        // Raw powers of x near 1e4 would overflow the normal equations' conditioning.
        let c = [1.0, -2.0e-1, 3.0e-5, -1.0e-9, 2.0e-13, -1.0e-17, 3.0e-22];
        let mut fit = PolyFit::new(6, [9000.0, 11000.0]).unwrap();
        for i in 0..=40 {
            let x = 9000.0 + 50.0 * i as f64;
            fit.add(x, horner(&c, x)).unwrap();
        }
        let (p, _) = fit.solve().unwrap();
        for i in 0..=20 {
            let x = 9000.0 + 100.0 * i as f64 + 7.0;
            let want = horner(&c, x);
            assert!((p.eval(x).unwrap() - want).abs() < 1e-9 * (1.0 + want.abs()), "x = {x}");
        }
    }

    #[test]
    fn weights_and_noise_give_the_weighted_rms() {
        // A line with Gaussian noise of 0.5: the RMS of the residuals is about 0.5.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let noise = Normal::new(0.0, 0.5).unwrap();
        let mut fit = PolyFit::new(1, [0.0, 100.0]).unwrap();
        for _ in 0..4000 {
            let x: f64 = rng.random_range(0.0..100.0);
            fit.add(x, 3.0 + 0.25 * x + noise.sample(&mut rng)).unwrap();
        }
        let (p, rms) = fit.solve().unwrap();
        assert!((rms - 0.5).abs() < 0.02, "{rms}");
        let c = p.monomial_coefficients().unwrap();
        assert!((c[1] - 0.25).abs() < 2e-3 && (c[0] - 3.0).abs() < 0.1, "{c:?}");
        // Weight 4 on a sample equals adding it four times.
        let mut a = PolyFit::new(2, [0.0, 4.0]).unwrap();
        let mut b = a;
        for (x, y) in [(0.0, 1.0), (1.0, 0.0), (2.0, 2.0), (3.0, 5.0), (4.0, 3.0)] {
            a.add_weighted(x, y, if x == 2.0 { 4.0 } else { 1.0 }).unwrap();
            for _ in 0..(if x == 2.0 { 4 } else { 1 }) {
                b.add(x, y).unwrap();
            }
        }
        let (pa, ra) = a.solve().unwrap();
        let (pb, rb) = b.solve().unwrap();
        assert!((ra - rb).abs() < 1e-12);
        for k in 0..3 {
            assert!((pa.scaled[k] - pb.scaled[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        assert!(matches!(PolyFit::new(0, [0.0, 1.0]), Err(Error::OutOfRange { .. })));
        assert!(matches!(PolyFit::new(7, [0.0, 1.0]), Err(Error::OutOfRange { .. })));
        assert!(matches!(PolyFit::new(2, [1.0, 1.0]), Err(Error::InvalidArgument { .. })));
        assert!(matches!(PolyFit::new(2, [f64::NAN, 1.0]), Err(Error::NotFinite { .. })));
        // The widest finite range is usable: the scaling is computed without overflow.
        assert!(PolyFit::new(2, [-f64::MAX, f64::MAX]).is_ok());
        let mut fit = PolyFit::new(3, [0.0, 10.0]).unwrap();
        assert!(matches!(fit.add(f64::NAN, 1.0), Err(Error::NotFinite { .. })));
        assert!(matches!(fit.add(1.0, f64::INFINITY), Err(Error::NotFinite { .. })));
        assert!(matches!(fit.add(11.0, 1.0), Err(Error::OutOfRange { .. })));
        assert!(matches!(fit.add_weighted(1.0, 1.0, -2.0), Err(Error::InvalidArgument { .. })));
        for x in [1.0, 2.0, 3.0] {
            fit.add(x, x).unwrap();
        }
        assert_eq!(fit.solve().unwrap_err(), Error::TooFew { what: "samples", needed: 4, got: 3 });
        fit.add(3.0, 3.5).unwrap();
        fit.add(3.0, 3.5).unwrap();
        fit.add_weighted(4.0, 3.5, 0.0).unwrap();
        assert_eq!(fit.solve().unwrap_err(), Error::TooFew { what: "distinct x values", needed: 4, got: 3 });
        fit.add(4.0, 4.0).unwrap();
        assert!(fit.solve().is_ok());
        let p = Polynomial { degree: 1, x_centre: 0.0, x_half_width: 0.0, scaled: [0.0; 7] };
        assert!(matches!(p.eval(1.0), Err(Error::Degenerate { .. })));
    }
}
