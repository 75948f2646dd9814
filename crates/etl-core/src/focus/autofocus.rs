//! Autofocus: the lens current that maximises a sharpness measure, with few evaluations.
//!
//! Each evaluation costs a frame (set the current, wait for the lens, grab, measure), so
//! the search spends a fixed, small budget: a coarse scan of the whole current range
//! finds the peak's neighbourhood even when the measure is flat far from focus, then
//! Brent's method (parabolic interpolation safeguarded by golden-section steps) refines it
//! inside the bracket of the best coarse point. The first refinement step is the parabola
//! through the best coarse point and its two neighbours, so no evaluation is spent on a
//! blind golden-section step.

use crate::error::{finite, Error, Result};

/// 2 - golden ratio: the golden-section step as a fraction of the larger sub-interval.
const CGOLD: f64 = 0.381_966_011_250_105_1;

/// How [`autofocus`] searches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutofocusOptions {
    /// The current range searched, mA (`[lo, hi]`, `lo < hi`).
    pub range_ma: [f64; 2],
    /// Points of the coarse scan, both ends included (at least 3). Their spacing must be
    /// finer than the measure's capture range (the width of its peak).
    pub coarse_points: usize,
    /// Total evaluations allowed, coarse scan included (at least `coarse_points`).
    pub max_evaluations: usize,
    /// The refinement stops once the bracket around the best current is narrower than
    /// twice this, mA (> 0).
    pub tolerance_ma: f64,
}

impl Default for AutofocusOptions {
    /// The paper rig's range (80 to 225 mA, with 5 mA to spare at each end), 7 coarse
    /// points (27.5 mA apart), 15 evaluations, 0.1 mA.
    fn default() -> Self {
        Self { range_ma: [75.0, 240.0], coarse_points: 7, max_evaluations: 15, tolerance_ma: 0.1 }
    }
}

/// What [`autofocus`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutofocusResult {
    /// The current of the sharpest evaluation, mA.
    pub best_ma: f64,
    /// The sharpness there.
    pub best_sharpness: f64,
    /// Evaluations spent (at most `max_evaluations`).
    pub evaluations: usize,
    /// The final bracket that contains the peak if the measure is unimodal there, mA.
    pub bracket_ma: [f64; 2],
    /// Whether the bracket shrank to the tolerance within the budget.
    pub converged: bool,
}

/// Finds the current (mA) that maximises `sharpness_at(current_ma)` over
/// `options.range_ma`.
///
/// Preconditions: the measure is unimodal around its peak over at least the two coarse
/// intervals next to it (flat or noisy far from focus is fine), and larger is sharper.
/// When the best coarse point is an end of the range, the refinement stays in the interval
/// next to it (the peak may then lie outside the range: widen it).
///
/// The search never allocates and never evaluates outside the range. When the budget runs
/// out first, the best point so far is returned with `converged == false`.
///
/// Errors: bad options ([`Error::OutOfRange`], [`Error::NotFinite`]); any error of
/// `sharpness_at` (returned as is); a non-finite sharpness ([`Error::NotFinite`]).
///
/// ```
/// use etl_core::focus::{autofocus, AutofocusOptions};
/// // A sharpness peak at 151.3 mA with the cusp-like shape of a defocused edge.
/// let f = |e: f64| Ok(1.0 / (1.0 + ((e - 151.3) / 4.0).powi(2)).sqrt());
/// let r = autofocus(f, &AutofocusOptions::default()).unwrap();
/// assert!((r.best_ma - 151.3).abs() < 0.5 && r.evaluations <= 15);
/// ```
pub fn autofocus<F>(mut sharpness_at: F, options: &AutofocusOptions) -> Result<AutofocusResult>
where
    F: FnMut(f64) -> Result<f64>,
{
    let [lo, hi] = options.range_ma;
    finite(lo, "autofocus range_ma[0]")?;
    finite(hi, "autofocus range_ma[1]")?;
    if !(hi > lo) {
        return Err(Error::InvalidArgument { what: "autofocus range_ma must have lo < hi" });
    }
    finite(options.tolerance_ma, "autofocus tolerance_ma")?;
    if !(options.tolerance_ma > 0.0) {
        return Err(Error::OutOfRange {
            what: "autofocus tolerance_ma",
            value: options.tolerance_ma,
            min: f64::MIN_POSITIVE,
            max: f64::INFINITY,
        });
    }
    let n = options.coarse_points;
    if n < 3 {
        return Err(Error::OutOfRange {
            what: "autofocus coarse_points",
            value: n as f64,
            min: 3.0,
            max: f64::INFINITY,
        });
    }
    if options.max_evaluations < n {
        return Err(Error::OutOfRange {
            what: "autofocus max_evaluations (must cover the coarse scan)",
            value: options.max_evaluations as f64,
            min: n as f64,
            max: f64::INFINITY,
        });
    }

    let mut evaluations = 0usize;
    let mut eval = |e: f64, count: &mut usize| -> Result<f64> {
        *count += 1;
        finite(sharpness_at(e)?, "sharpness returned by the measure")
    };

    // Coarse scan; keep the best point and its neighbours' values without storing the scan.
    let step = (hi - lo) / (n - 1) as f64;
    let at = |i: usize| if i + 1 == n { hi } else { lo + step * i as f64 };
    let mut best = (0usize, f64::NEG_INFINITY);
    let (mut prev, mut before_best, mut after_best) = (f64::NAN, f64::NAN, f64::NAN);
    for i in 0..n {
        let s = eval(at(i), &mut evaluations)?;
        if s > best.1 {
            best = (i, s);
            before_best = prev;
            after_best = f64::NAN;
        } else if i == best.0 + 1 {
            after_best = s;
        }
        prev = s;
    }
    let (k, fk) = best;

    // Brent's minimisation of -sharpness in [a, b] (Numerical Recipes' `brent`), seeded
    // with x = best coarse point, w and v = its neighbours.
    let mut a = at(k.saturating_sub(1));
    let mut b = at(if k + 1 < n { k + 1 } else { k });
    let (mut x, mut fx) = (at(k), -fk);
    let (mut w, mut fw, mut v, mut fv);
    match (before_best.is_nan(), after_best.is_nan()) {
        (false, false) => {
            // The better neighbour is w (second best), the other v.
            let (l, fl, r, fr) = (a, -before_best, b, -after_best);
            if fl <= fr {
                (w, fw, v, fv) = (l, fl, r, fr);
            } else {
                (w, fw, v, fv) = (r, fr, l, fl);
            }
        }
        (true, _) => (w, fw, v, fv) = (b, -after_best, b, -after_best),
        (false, true) => (w, fw, v, fv) = (a, -before_best, a, -before_best),
    }
    // A large previous step lets the first parabolic step through.
    let mut d = 0.0f64;
    let mut e = b - a;
    let tol1 = options.tolerance_ma;
    let tol2 = 2.0 * tol1;
    let mut converged = false;
    while evaluations < options.max_evaluations {
        let xm = 0.5 * (a + b);
        if (x - xm).abs() <= tol2 - 0.5 * (b - a) {
            converged = true;
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 && w != x && v != x && w != v {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let e_before = e;
            if !(p.abs() >= (0.5 * q * e_before).abs() || p <= q * (a - x) || p >= q * (b - x)) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = tol1.copysign(xm - x);
                }
                golden = false;
            }
        }
        if golden {
            e = if x >= xm { a - x } else { b - x };
            d = CGOLD * e;
        }
        let u = if d.abs() >= tol1 { x + d } else { x + tol1.copysign(d) };
        let fu = -eval(u, &mut evaluations)?;
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv) = (w, fw);
            (w, fw) = (x, fx);
            (x, fx) = (u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv) = (w, fw);
                (w, fw) = (u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    if !converged {
        let xm = 0.5 * (a + b);
        converged = (x - xm).abs() <= tol2 - 0.5 * (b - a);
    }
    Ok(AutofocusResult { best_ma: x, best_sharpness: -fx, evaluations, bracket_ma: [a, b], converged })
}
