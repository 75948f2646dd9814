//! The small dense factorisations of the crate, one file per factorisation, on fixed-size
//! arrays (no heap): Cholesky ([`cholesky`]: certified inverses, the semidefinite factor of
//! normal equations), the one-sided Jacobi SVD ([`svd`]: rank decisions, pseudo-inverses)
//! and triangular inversion ([`triangular`]). The Levenberg-Marquardt solvers
//! ([`crate::lm`]), the linear initialisers and the std crates build on them.

pub mod cholesky;
pub mod svd;
pub mod triangular;

pub use cholesky::{normal_equations_factor, psd_inverse, spd_inverse};
pub use svd::{sym_pinv, Svd};
pub use triangular::certified_upper_inverse;
