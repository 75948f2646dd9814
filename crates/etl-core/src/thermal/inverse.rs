//! The inverse of the compensation: which driver current E_in gives a wanted E_com at
//! temperature T, i.e. the root of g(E_in) = E_in - E_T(T, E_in) - E_com.
//!
//! A controller that wants the focus of E_com needs this every time the temperature
//! changes. g is a cubic in E_in; for a sane surface it is close to the identity
//! (|dE_T/dE_in| << 1), but a fitted cubic may bend back far outside its data, so the
//! root is bracketed first (a scan of the whole driver range) and then polished by Newton's
//! method safeguarded by bisection inside the bracket.

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

/// A segment [a, b] of the driver range over which g changes sign (or touches zero), with
/// g(a) and g(b).
#[derive(Debug, Clone, Copy)]
struct Bracket {
    a: f64,
    b: f64,
    ga: f64,
    gb: f64,
}

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
        check_domain(0.0, t_c)?;
        self.validate()?;
        let bracket = self.bracket_e_in(e_com_ma, t_c)?;
        if bracket.ga == 0.0 {
            return Ok(bracket.a);
        }
        if bracket.gb == 0.0 {
            return Ok(bracket.b);
        }
        self.polish_e_in(e_com_ma, t_c, bracket)
    }

    /// g(E_in) = E_in - E_T(T, E_in) - E_com at driver current `e_in_ma` and temperature
    /// `t_c`, without domain checks (the callers have checked T and the coefficients).
    #[inline]
    fn inverse_residual_ma(&self, e_in_ma: f64, t_c: f64, e_com_ma: f64) -> f64 {
        e_in_ma - self.eval_unchecked(e_in_ma, t_c) - e_com_ma
    }

    /// Scans the driver range in [`INVERSE_SEGMENTS`] segments for the sign change of g
    /// nearest to E_in ~ `e_com_ma` (distance from `e_com_ma` to the segment; the first
    /// segment wins a tie).
    ///
    /// Errors: g not finite somewhere on the scan ([`Error::NotFinite`]); no sign change
    /// ([`Error::OutOfRange`] with the span of E_com the driver range reaches).
    fn bracket_e_in(&self, e_com_ma: f64, t_c: f64) -> Result<Bracket> {
        let [lo, hi] = E_IN_DOMAIN_MA;
        let step = (hi - lo) / INVERSE_SEGMENTS as f64;
        let mut a = lo;
        let mut ga = self.inverse_residual_ma(a, t_c, e_com_ma);
        finite(ga, "E_com over the driver range (check the thermal coefficients)")?;
        let (mut reach_min, mut reach_max) = (ga, ga);
        let mut best: Option<Bracket> = None;
        let mut best_dist = f64::INFINITY;
        for i in 1..=INVERSE_SEGMENTS {
            // The last end is `hi` itself, not lo + 64 steps rounded.
            let b = if i == INVERSE_SEGMENTS { hi } else { lo + step * i as f64 };
            let gb = self.inverse_residual_ma(b, t_c, e_com_ma);
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
                    best = Some(Bracket { a, b, ga, gb });
                }
            }
            a = b;
            ga = gb;
        }
        best.ok_or(Error::OutOfRange {
            what: "e_com_ma (no driver current reaches it at this temperature)",
            value: e_com_ma,
            min: reach_min + e_com_ma,
            max: reach_max + e_com_ma,
        })
    }

    /// Newton's method on g inside `bracket`, safeguarded by bisection: the bracket
    /// [x_neg, x_pos] with g(x_neg) < 0 < g(x_pos) shrinks every step, and a Newton step
    /// leaving it is replaced by the midpoint. Returns the best E_in seen.
    ///
    /// Precondition: g(a) and g(b) are non-zero with opposite signs.
    /// Errors: the best |g| above [`INVERSE_TOL_MA`] after [`MAX_ITER`] steps
    /// ([`Error::NotConverged`]).
    fn polish_e_in(&self, e_com_ma: f64, t_c: f64, bracket: Bracket) -> Result<f64> {
        let Bracket { a, b, ga, gb } = bracket;
        let (mut x_neg, mut x_pos) = if ga < 0.0 { (a, b) } else { (b, a) };
        // E_T is small, so E_in ~ E_com is the natural first guess when it is inside.
        let mut x = if e_com_ma > a && e_com_ma < b { e_com_ma } else { 0.5 * (a + b) };
        let (mut best_x, mut best_g) = (a, ga.abs());
        if gb.abs() < best_g {
            best_x = b;
            best_g = gb.abs();
        }
        for _ in 0..MAX_ITER {
            let gx = self.inverse_residual_ma(x, t_c, e_com_ma);
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
            let slope = 1.0 - self.d_e_t_d_e_unchecked(x, t_c);
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
                let r = (e_in - s.e_t_ma(e_in, t).unwrap() - e_com).abs();
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
            let e_com = s.e_com_ma(e, t).unwrap();
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
