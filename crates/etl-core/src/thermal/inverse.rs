//! The inverse of the compensation: which driver current E_in gives a wanted E_com at
//! temperature T, i.e. the root of g(E_in) = E_in - E_T(T, E_in) - E_com.
//!
//! A controller that wants the focus of E_com needs this every time the temperature
//! changes. g is a cubic in E_in; for a sane surface it is close to the identity
//! (|dE_T/dE_in| << 1), but a fitted cubic may bend back far outside its data, so the
//! root is bracketed first (a scan of the whole driver range) and then polished by Newton's
//! method safeguarded by bisection inside the bracket.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` is meant: NaN must fail the check.

use super::surface::ThermalSurface;
use super::{check_domain, E_IN_DOMAIN_MA};
use crate::error::{finite, Error, Result};

/// Tolerance on |E_in - E_T(T, E_in) - E_com| of the returned E_in, mA.
pub const INVERSE_TOL_MA: f64 = 1e-9;

/// Segments of the driver range scanned for sign changes of g.
pub const INVERSE_SEGMENTS: usize = 64;

/// Newton/bisection iterations allowed in the bracket (bisection alone needs ~60 to
/// shrink a segment to one ulp).
const MAX_ITER: usize = 100;

impl ThermalSurface {
    /// The driver current E_in (mA) at which E_in - E_T(`t_c`, E_in) = `e_com_ma`, to
    /// [`INVERSE_TOL_MA`].
    ///
    /// E_in is searched over the driver range [`E_IN_DOMAIN_MA`].
    /// If the surface is not one-to-one there and several roots exist, the one nearest to
    /// `e_com_ma` is returned (E_T is a small correction, so that is the physical one).
    ///
    /// Errors: a non-finite input or coefficient ([`Error::NotFinite`]); `t_c` outside
    /// [`T_DOMAIN_C`](crate::thermal::T_DOMAIN_C) ([`Error::OutOfRange`]); no E_in in the driver range
    /// reaches `e_com_ma` at this temperature ([`Error::OutOfRange`], with the span of E_com
    /// the driver range does reach); the polish missing the tolerance
    /// ([`Error::NotConverged`], not expected for finite coefficients of sane size).
    pub fn e_in_for_e_com(&self, e_com_ma: f64, t_c: f64) -> Result<f64> {
        finite(e_com_ma, "e_com_ma")?;
        check_domain(t_c, 0.0)?;
        self.validate()?;
        let g = |e: f64| e - self.eval_unchecked(t_c, e) - e_com_ma;
        let [lo, hi] = E_IN_DOMAIN_MA;
        let step = (hi - lo) / INVERSE_SEGMENTS as f64;

        // Scan for the sign change nearest to E_in ~ E_com.
        let mut a = lo;
        let mut ga = g(a);
        finite(ga, "E_com over the driver range (check the thermal coefficients)")?;
        let (mut reach_min, mut reach_max) = (ga, ga);
        let mut best: Option<(f64, f64, f64, f64)> = None;
        let mut best_dist = f64::INFINITY;
        for i in 1..=INVERSE_SEGMENTS {
            let b = if i == INVERSE_SEGMENTS { hi } else { lo + step * i as f64 };
            let gb = g(b);
            finite(gb, "E_com over the driver range (check the thermal coefficients)")?;
            reach_min = reach_min.min(gb);
            reach_max = reach_max.max(gb);
            if ga == 0.0 || gb == 0.0 || (ga < 0.0) != (gb < 0.0) {
                let dist = if e_com_ma < a {
                    a - e_com_ma
                } else if e_com_ma > b {
                    e_com_ma - b
                } else {
                    0.0
                };
                if dist < best_dist {
                    best_dist = dist;
                    best = Some((a, b, ga, gb));
                }
            }
            a = b;
            ga = gb;
        }
        let Some((a, b, ga, gb)) = best else {
            return Err(Error::OutOfRange {
                what: "e_com_ma (no driver current reaches it at this temperature)",
                value: e_com_ma,
                min: reach_min + e_com_ma,
                max: reach_max + e_com_ma,
            });
        };
        if ga == 0.0 {
            return Ok(a);
        }
        if gb == 0.0 {
            return Ok(b);
        }

        // Safeguarded Newton in [a, b]: keep g(x_neg) < 0 < g(x_pos).
        let (mut x_neg, mut x_pos) = if ga < 0.0 { (a, b) } else { (b, a) };
        let mut x = if e_com_ma > a && e_com_ma < b { e_com_ma } else { 0.5 * (a + b) };
        let (mut best_x, mut best_g) = (a, ga.abs());
        if gb.abs() < best_g {
            best_x = b;
            best_g = gb.abs();
        }
        for _ in 0..MAX_ITER {
            let gx = g(x);
            if gx.abs() < best_g {
                best_x = x;
                best_g = gx.abs();
            }
            if gx == 0.0 || best_g <= 0.01 * INVERSE_TOL_MA {
                break;
            }
            if gx < 0.0 {
                x_neg = x;
            } else {
                x_pos = x;
            }
            let (l, h) = if x_neg < x_pos { (x_neg, x_pos) } else { (x_pos, x_neg) };
            if h - l <= 4.0 * f64::EPSILON * h.abs().max(l.abs()).max(1.0) {
                break;
            }
            let slope = 1.0 - self.d_e_t_d_e_unchecked(t_c, x);
            let newton = x - gx / slope;
            x = if newton > l && newton < h { newton } else { 0.5 * (l + h) };
        }
        if best_g <= INVERSE_TOL_MA {
            Ok(best_x)
        } else {
            Err(Error::NotConverged { what: "inverse of the thermal compensation", iterations: MAX_ITER })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 2: E_in - E_T(T, E_in) = E_com to 1e-9 mA, over the paper's range and beyond.
    #[test]
    fn inverse_meets_the_tolerance_over_the_grid() {
        let s = ThermalSurface::PAPER;
        let mut worst = 0.0f64;
        for it in 0..=26 {
            let t = 20.0 + it as f64 * 0.8; // 20..40.8 degC
            for ie in 0..=56 {
                let e_com = 5.0 * ie as f64 - 20.0; // -20..260 mA
                let e_in = s.e_in_for_e_com(e_com, t).unwrap();
                let r = (e_in - s.e_t_ma(t, e_in).unwrap() - e_com).abs();
                worst = worst.max(r);
                // The physical root: E_in stays within a few tens of mA of E_com.
                assert!((e_in - e_com).abs() < 60.0, "T {t} E_com {e_com}: E_in {e_in}");
            }
        }
        assert!(worst <= INVERSE_TOL_MA, "worst residual {worst} mA");
    }

    #[test]
    fn inverse_of_forward_is_identity() {
        let s = ThermalSurface::PAPER;
        for &(t, e) in &[(27.0, 40.0), (32.5, 133.3), (37.0, 240.0), (36.0, 0.0), (29.0, -50.0)] {
            let e_com = s.e_com_ma(t, e).unwrap();
            let back = s.e_in_for_e_com(e_com, t).unwrap();
            assert!((back - e).abs() < 1e-9, "{t} {e}: {back}");
        }
    }

    #[test]
    fn nearest_root_of_a_folded_surface() {
        // E_T = 2e-5 E^3 gives g = E - 2e-5 E^3 - E_com with three real roots in the driver
        // range for E_com = 10: about 10.02 (the physical one), 218 and -228.
        let s = ThermalSurface { coefficients: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2e-5] };
        let e = s.e_in_for_e_com(10.0, 30.0).unwrap();
        assert!((e - 10.0).abs() < 1.0 && (e - 2e-5 * e * e * e - 10.0).abs() < 1e-9, "{e}");
    }

    #[test]
    fn unreachable_e_com_and_bad_input_are_typed_errors() {
        let s = ThermalSurface::PAPER;
        match s.e_in_for_e_com(1000.0, 30.0) {
            Err(Error::OutOfRange { value, min, max, .. }) => {
                assert!(value == 1000.0 && min < -250.0 && max > 250.0 && max < 400.0, "{min} {max}");
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(s.e_in_for_e_com(f64::NAN, 30.0), Err(Error::NotFinite { what: "e_com_ma" })));
        assert!(matches!(s.e_in_for_e_com(100.0, f64::NEG_INFINITY), Err(Error::NotFinite { what: "t_c" })));
        assert!(matches!(s.e_in_for_e_com(100.0, 500.0), Err(Error::OutOfRange { what: "t_c", .. })));
        let bad = ThermalSurface { coefficients: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, f64::INFINITY] };
        assert!(matches!(bad.e_in_for_e_com(100.0, 30.0), Err(Error::NotFinite { .. })));
    }
}
