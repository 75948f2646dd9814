//! Least-squares fits without allocation: a streamed Givens-QR accumulator
//! ([`GivensQr`], shared by every fit in the crate, e.g. the thermal surface) and weighted
//! polynomials of degree 1..6 in one variable ([`PolyFit`]), e.g. the focal length against
//! the current (Eq. 12, Fig. 5).
//!
//! Numerical soundness: the variable is centred and scaled into [-1, 1] over a range
//! given up front, rows are Chebyshev polynomials of it, and they are folded into R by
//! Givens rotations. Normal equations on raw mA powers (E^6 ~ 1e14) would lose every digit.

pub mod basis;
pub mod givens;
pub mod polynomial;

pub use givens::GivensQr;
pub use polynomial::{PolyFit, Polynomial, MAX_POLY_DEGREE};
