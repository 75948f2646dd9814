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
    /// The current range searched, mA (`[lo, hi]`, `lo < hi`, both within the lens
    /// driver's [`E_IN_DOMAIN_MA`](crate::thermal::E_IN_DOMAIN_MA)).
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

/// The preconditions of [`autofocus`] on its options.
fn check_options(options: &AutofocusOptions) -> Result<()> {
    let [lo, hi] = options.range_ma;
    finite(lo, "autofocus range_ma[0]")?;
    finite(hi, "autofocus range_ma[1]")?;
    if !(hi > lo) {
        return Err(Error::InvalidArgument { what: "autofocus range_ma must have lo < hi" });
    }
    // Currents a lens driver can give: a range of 1e308 would also make the coarse grid's
    // step infinite and every current searched NaN.
    let [d0, d1] = crate::thermal::E_IN_DOMAIN_MA;
    for (value, what) in [(lo, "autofocus range_ma[0]"), (hi, "autofocus range_ma[1]")] {
        if !(d0..=d1).contains(&value) {
            return Err(Error::OutOfRange { what, value, min: d0, max: d1 });
        }
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
    Ok(())
}

/// The coarse scan's points: `n` currents evenly spaced over [lo, hi], both ends exact.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: f64,
    hi: f64,
    n: usize,
    step: f64,
}

impl Grid {
    fn new(options: &AutofocusOptions) -> Self {
        let ([lo, hi], n) = (options.range_ma, options.coarse_points);
        Grid { lo, hi, n, step: (hi - lo) / (n - 1) as f64 }
    }

    /// Current of point i, mA.
    fn at(&self, i: usize) -> f64 {
        if i + 1 == self.n {
            self.hi
        } else {
            self.lo + self.step * i as f64
        }
    }
}

/// The best point of the coarse scan (index, sharpness) and its neighbours' sharpness
/// (NaN past an end of the range).
struct Coarse {
    best: usize,
    sharpness: f64,
    before: f64,
    after: f64,
}

/// The coarse scan; keeps the best point and its neighbours' values without storing the
/// scan.
fn coarse_scan(grid: &Grid, mut eval: impl FnMut(f64) -> Result<f64>) -> Result<Coarse> {
    let mut best = (0usize, f64::NEG_INFINITY);
    let (mut prev, mut before_best, mut after_best) = (f64::NAN, f64::NAN, f64::NAN);
    for i in 0..grid.n {
        let s = eval(grid.at(i))?;
        if s > best.1 {
            best = (i, s);
            before_best = prev;
            after_best = f64::NAN;
        } else if i == best.0 + 1 {
            after_best = s;
        }
        prev = s;
    }
    Ok(Coarse { best: best.0, sharpness: best.1, before: before_best, after: after_best })
}

/// Brent's minimisation of f = -sharpness (Numerical Recipes' `brent`): the bracket
/// [a, b], the best point x, the second best w, the previous w in v, the last step d and
/// the one before e.
struct Brent {
    a: f64,
    b: f64,
    x: f64,
    fx: f64,
    w: f64,
    fw: f64,
    v: f64,
    fv: f64,
    d: f64,
    e: f64,
}

impl Brent {
    /// Seeded with x = the best coarse point, w and v = its neighbours (the better one is
    /// w), so that the first step is the parabola through the three.
    fn seeded(grid: &Grid, coarse: &Coarse) -> Self {
        let k = coarse.best;
        let a = grid.at(k.saturating_sub(1));
        let b = grid.at(if k + 1 < grid.n { k + 1 } else { k });
        let (w, fw, v, fv) = match (coarse.before.is_nan(), coarse.after.is_nan()) {
            (false, false) => {
                let (l, fl, r, fr) = (a, -coarse.before, b, -coarse.after);
                if fl <= fr {
                    (l, fl, r, fr)
                } else {
                    (r, fr, l, fl)
                }
            }
            (true, _) => (b, -coarse.after, b, -coarse.after),
            (false, true) => (a, -coarse.before, a, -coarse.before),
        };
        // A large previous step lets the first parabolic step through.
        Brent { a, b, x: grid.at(k), fx: -coarse.sharpness, w, fw, v, fv, d: 0.0, e: b - a }
    }

    /// |x - (a + b) / 2| <= 2 tol - (b - a) / 2: the bracket is within the tolerance.
    fn converged(&self, tol2: f64) -> bool {
        let xm = 0.5 * (self.a + self.b);
        (self.x - xm).abs() <= tol2 - 0.5 * (self.b - self.a)
    }

    /// The next point to evaluate: the parabola through x, w, v when it falls inside the
    /// bracket and moves less than half the step before last, else a golden-section step
    /// into the larger part; never closer than `tol1` to x.
    fn next_point(&mut self, tol1: f64, tol2: f64) -> f64 {
        let Brent { a, b, x, fx, w, fw, v, fv, .. } = *self;
        let xm = 0.5 * (a + b);
        let mut golden = true;
        if self.e.abs() > tol1 && w != x && v != x && w != v {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let e_before = self.e;
            if !(p.abs() >= (0.5 * q * e_before).abs() || p <= q * (a - x) || p >= q * (b - x)) {
                self.e = self.d;
                self.d = p / q;
                let u = x + self.d;
                if u - a < tol2 || b - u < tol2 {
                    self.d = tol1.copysign(xm - x);
                }
                golden = false;
            }
        }
        if golden {
            self.e = if x >= xm { a - x } else { b - x };
            self.d = CGOLD * self.e;
        }
        if self.d.abs() >= tol1 {
            x + self.d
        } else {
            x + tol1.copysign(self.d)
        }
    }

    /// Takes in f(u) = `fu`: shrinks the bracket and reorders x, w, v.
    fn update(&mut self, u: f64, fu: f64) {
        if fu <= self.fx {
            if u >= self.x {
                self.a = self.x;
            } else {
                self.b = self.x;
            }
            (self.v, self.fv) = (self.w, self.fw);
            (self.w, self.fw) = (self.x, self.fx);
            (self.x, self.fx) = (u, fu);
        } else {
            if u < self.x {
                self.a = u;
            } else {
                self.b = u;
            }
            if fu <= self.fw || self.w == self.x {
                (self.v, self.fv) = (self.w, self.fw);
                (self.w, self.fw) = (u, fu);
            } else if fu <= self.fv || self.v == self.x || self.v == self.w {
                (self.v, self.fv) = (u, fu);
            }
        }
    }
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
    check_options(options)?;
    let mut evaluations = 0usize;
    let mut eval = |e: f64, count: &mut usize| -> Result<f64> {
        *count += 1;
        finite(sharpness_at(e)?, "sharpness returned by the measure")
    };
    let grid = Grid::new(options);
    let coarse = coarse_scan(&grid, |e| eval(e, &mut evaluations))?;
    let mut brent = Brent::seeded(&grid, &coarse);
    let tol1 = options.tolerance_ma;
    let tol2 = 2.0 * tol1;
    let mut converged = false;
    while evaluations < options.max_evaluations {
        if brent.converged(tol2) {
            converged = true;
            break;
        }
        let u = brent.next_point(tol1, tol2);
        let fu = -eval(u, &mut evaluations)?;
        brent.update(u, fu);
    }
    converged = converged || brent.converged(tol2);
    let Brent { a, b, x, fx, .. } = brent;
    Ok(AutofocusResult { best_ma: x, best_sharpness: -fx, evaluations, bracket_ma: [a, b], converged })
}
