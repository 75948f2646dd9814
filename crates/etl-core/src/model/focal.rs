//! [`FocalPoly`]: a focal length as a polynomial in the compensated current (Eq. 16,
//! generalised from the paper's cubic to any degree 1..=5).

use crate::error::{all_finite, Error, Result};

/// Highest degree of the focal polynomial.
pub const MAX_FOCAL_DEGREE: usize = 5;
/// The paper's degree (Eq. 16: a cubic), the default.
pub const PAPER_FOCAL_DEGREE: usize = 3;

/// f(E) = kf_0 + kf_1 E + ... + kf_d E^d (px, E in mA), 1 <= d <= [`MAX_FOCAL_DEGREE`].
///
/// Fixed capacity, no allocation: the coefficients past the degree are zero. The paper's
/// model is the cubic ([`FocalPoly::cubic`]); a cubic evaluates exactly as Eq. 16's Horner
/// form ((kf3 E + kf2) E + kf1) E + kf0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalPoly {
    degree: usize,
    c: [f64; MAX_FOCAL_DEGREE + 1],
}

/// As the list of its coefficients (kf_0 first), the form of the calibration file.
impl serde::Serialize for FocalPoly {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> core::result::Result<S::Ok, S::Error> {
        serializer.collect_seq(self.coefficients())
    }
}

impl Default for FocalPoly {
    fn default() -> Self {
        FocalPoly::cubic([0.0; 4])
    }
}

impl FocalPoly {
    /// The paper's cubic [kf0, kf1, kf2, kf3].
    pub const fn cubic(c: [f64; 4]) -> Self {
        FocalPoly { degree: 3, c: [c[0], c[1], c[2], c[3], 0.0, 0.0] }
    }

    /// The polynomial with coefficients `c` (lowest degree first); its degree is
    /// `c.len() - 1`. Errors: fewer than 2 or more than 6 coefficients
    /// ([`Error::InvalidArgument`] naming the degree's range).
    pub fn new(c: &[f64]) -> Result<Self> {
        if !(2..=MAX_FOCAL_DEGREE + 1).contains(&c.len()) {
            return Err(Error::InvalidArgument {
                what: "a focal polynomial (kf_x, kf_y) needs 2..=6 coefficients (degree 1..=5)",
            });
        }
        let mut out = FocalPoly { degree: c.len() - 1, c: [0.0; MAX_FOCAL_DEGREE + 1] };
        for (slot, &v) in out.c.iter_mut().zip(c) {
            *slot = v;
        }
        Ok(out)
    }

    /// The zero polynomial of degree `degree` (1..=5; clamped into that range).
    pub const fn zero(degree: usize) -> Self {
        let d = if degree < 1 {
            1
        } else if degree > MAX_FOCAL_DEGREE {
            MAX_FOCAL_DEGREE
        } else {
            degree
        };
        FocalPoly { degree: d, c: [0.0; MAX_FOCAL_DEGREE + 1] }
    }

    /// The degree d.
    pub const fn degree(&self) -> usize {
        self.degree
    }

    /// kf_0..kf_d.
    pub fn coefficients(&self) -> &[f64] {
        self.c.get(..=self.degree).unwrap_or(&self.c)
    }

    /// kf_0..kf_d, mutable.
    pub fn coefficients_mut(&mut self) -> &mut [f64] {
        let n = (self.degree + 1).min(MAX_FOCAL_DEGREE + 1);
        let (head, _) = self.c.split_at_mut(n);
        head
    }

    /// The coefficients at capacity (zeros past the degree).
    pub const fn padded(&self) -> &[f64; MAX_FOCAL_DEGREE + 1] {
        &self.c
    }

    /// Checks that every coefficient is finite (naming `what`).
    pub fn validate(&self, what: &'static str) -> Result<()> {
        all_finite(self.coefficients(), what)
    }

    /// f(E) by Horner's rule from the highest degree (written out per degree: this runs
    /// twice per point of every bundle-adjustment evaluation).
    #[inline(always)]
    pub fn eval(&self, e: f64) -> f64 {
        let [c0, c1, c2, c3, c4, c5] = self.c;
        match self.degree {
            1 => c1 * e + c0,
            2 => (c2 * e + c1) * e + c0,
            3 => ((c3 * e + c2) * e + c1) * e + c0,
            4 => (((c4 * e + c3) * e + c2) * e + c1) * e + c0,
            _ => ((((c5 * e + c4) * e + c3) * e + c2) * e + c1) * e + c0,
        }
    }

    /// df/dE = sum i kf_i E^(i-1).
    #[inline]
    pub fn slope(&self, e_ma: f64) -> f64 {
        let c = self.coefficients();
        let mut acc = c.get(1).copied().unwrap_or(0.0);
        for (i, &ci) in c.iter().enumerate().skip(2) {
            // ((i kf_i) E) E ...: the order of the paper cubic's kf1 + 2 kf2 E + 3 kf3 E E.
            let mut t = i as f64 * ci;
            for _ in 1..i {
                t *= e_ma;
            }
            acc += t;
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_is_eq16_bit_for_bit() {
        let k = [5380.0, -7.0, 0.02, -3e-5];
        let p = FocalPoly::cubic(k);
        for e in [0.0, 80.0, 151.3, 225.0, -3.0] {
            assert_eq!(p.eval(e), ((k[3] * e + k[2]) * e + k[1]) * e + k[0]);
            assert_eq!(p.slope(e), k[1] + 2.0 * k[2] * e + 3.0 * k[3] * e * e);
        }
        assert_eq!(p.degree(), 3);
        assert_eq!(p.coefficients(), &k);
    }

    #[test]
    fn any_degree_and_its_slope() {
        for d in 1..=MAX_FOCAL_DEGREE {
            let c: [f64; 6] = core::array::from_fn(|i| 1.0 / (i as f64 + 1.0));
            let p = FocalPoly::new(&c[..=d]).unwrap();
            let e = 1.7;
            let want: f64 = (0..=d).map(|i| c[i] * libm::pow(e, i as f64)).sum();
            assert!((p.eval(e) - want).abs() < 1e-12);
            let h = 1e-6;
            let fd = (p.eval(e + h) - p.eval(e - h)) / (2.0 * h);
            assert!((p.slope(e) - fd).abs() < 1e-8, "degree {d}");
        }
        assert!(FocalPoly::new(&[1.0]).is_err());
        assert!(FocalPoly::new(&[1.0; 7]).is_err());
    }
}
