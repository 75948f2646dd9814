//! A traced camera's focus current for a distance: its traced distance in focus d(E)
//! ([`OpticalRig::focus_distance_mm`], a golden-section search on the spot's RMS radius,
//! too slow to run per view) on a grid of currents over its procedure's range, inverted
//! by interpolation.
//!
//! d(E) falls as E grows (the ETL's power P(E) = p0 + p1 E rises) and 1/d is nearly
//! affine in E (thin lens: 1000 / d = P(E) - P_prime-defocus, in dioptres), so the table
//! interpolates linearly in w = 1 / d: between grid currents E_i, E_i+1 with w_i, w_i+1,
//!
//! ```text
//! E(d) = E_i + (1/d - w_i) (E_i+1 - E_i) / (w_i+1 - w_i)
//! ```
//!
//! Its error is that of a straight line through a curve that is straight to first order:
//! on the Cooke fixture's rig with the grid 5 mA apart, the distance the traced search
//! finds at the interpolated current differs from the asked one by less than
//! [`FOCUS_TOLERANCE_MM`] (a test checks it at the ends and the middle of the travel and
//! half-way between grid currents, where the error peaks). It only defocuses the board that little: the recorded current is the one
//! the lens runs at, so the interpolation adds no error to the data.

use etl_formats::{Error, Result};
use rayon::prelude::*;

use crate::optics::OpticalRig;

/// The interpolation's documented error bound (module docs), mm of distance in focus,
/// for a grid at most 5 mA apart.
pub const FOCUS_TOLERANCE_MM: f64 = 0.01;

/// The distance in focus on a grid of currents (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FocusTable {
    /// The grid's currents, mA, ascending: the procedure's lowest to its highest in steps
    /// of at most the asked step.
    pub e_ma: Vec<f64>,
    /// The traced distance in focus at each, camera z, mm (descending).
    pub distance_mm: Vec<f64>,
}

impl FocusTable {
    /// The table of `rig` over its procedure's currents, `step_ma` apart at most (the grid
    /// divides the range evenly). Errors: a step that is not positive and finite
    /// (`focus_step_ma`); a current at which the focus search fails; a distance in focus
    /// that does not fall as the current grows (`focus`).
    pub fn new(rig: &OpticalRig, step_ma: f64) -> Result<Self> {
        if !(step_ma > 0.0 && step_ma.is_finite()) {
            return Err(Error::invalid_value(
                "focus_step_ma",
                step_ma,
                format!("focus_step_ma: {step_ma} mA is not a positive step"),
            ));
        }
        let e = &rig.file.procedure.e_com_ma;
        let lo = e.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let n = ((hi - lo) / step_ma).ceil().max(1.0) as usize;
        let e_ma: Vec<f64> = (0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64).collect();
        let distance_mm = e_ma.par_iter().map(|&e| rig.focus_distance_mm(e)).collect::<Result<Vec<f64>>>()?;
        if distance_mm.windows(2).any(|w| w[1] >= w[0]) {
            return Err(Error::invalid(
                "focus",
                format!("focus: {}'s distance in focus does not fall as the current grows", rig.file.name),
            ));
        }
        Ok(FocusTable { e_ma, distance_mm })
    }

    /// The distances the table covers, [nearest, farthest], mm.
    pub fn range_mm(&self) -> [f64; 2] {
        [self.distance_mm[self.distance_mm.len() - 1], self.distance_mm[0]]
    }

    /// The current (mA) at which the lens is in focus at `distance_mm` (module docs), None
    /// outside [`Self::range_mm`].
    pub fn current_ma(&self, distance_mm: f64) -> Option<f64> {
        let [near, far] = self.range_mm();
        if !(near..=far).contains(&distance_mm) {
            return None;
        }
        let w = 1.0 / distance_mm;
        let i = self.distance_mm.windows(2).position(|d| distance_mm >= d[1]).unwrap_or(0);
        let (w0, w1) = (1.0 / self.distance_mm[i], 1.0 / self.distance_mm[i + 1]);
        Some(self.e_ma[i] + (w - w0) * (self.e_ma[i + 1] - self.e_ma[i]) / (w1 - w0))
    }

    /// The distance in focus (mm) at `e_ma` inside the grid, by the same interpolation
    /// the other way (1/d linear in E); None outside the grid's currents.
    pub fn distance_at_mm(&self, e_ma: f64) -> Option<f64> {
        let (lo, hi) = (self.e_ma[0], self.e_ma[self.e_ma.len() - 1]);
        if !(lo..=hi).contains(&e_ma) {
            return None;
        }
        let i = self.e_ma.windows(2).position(|e| e_ma <= e[1]).unwrap_or(0);
        let (w0, w1) = (1.0 / self.distance_mm[i], 1.0 / self.distance_mm[i + 1]);
        let t = (e_ma - self.e_ma[i]) / (self.e_ma[i + 1] - self.e_ma[i]);
        Some(1.0 / (w0 + t * (w1 - w0)))
    }
}
