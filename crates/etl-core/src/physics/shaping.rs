//! Faster refocus: a zero-vibration (ZV) input shaper for the membrane's second-order
//! response ([`super::dynamics`], D3).
//!
//! A step of the command excites the membrane's resonance, which rings for about
//! 4 / (zeta w) (15 ms with [`LensDynamics::PUBLISHED`]). Splitting the step into two
//! steps, a fraction A1 = 1 / (1 + K) of it at once and the rest half a damped period
//! later, t2 = pi / w_d, with K = exp(-zeta pi / sqrt(1 - zeta^2)) and
//! w_d = w sqrt(1 - zeta^2), cancels the ringing of the first by that of the second: the
//! response of (D3) reaches the new level at t2 and stays there (Singer and Seering,
//! "Preshaping command inputs to reduce system vibration", J. Dyn. Sys., Meas., Control
//! 112(1), 1990). Creep and hysteresis (D1-D2) are not vibrations and are left as they are.

use super::dynamics::LensDynamics;

/// A two-step command: `first_fraction` of the step at once, the whole step `delay_s`
/// later.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZvShaper {
    /// A1: the fraction of the step commanded at once, in (0.5, 1).
    pub first_fraction: f64,
    /// t2: when the rest follows, s.
    pub delay_s: f64,
}

impl ZvShaper {
    /// The shaper of `d`'s membrane, or None when it is not underdamped (zeta >= 1: a
    /// step does not ring, and there is nothing to cancel).
    pub fn of(d: &LensDynamics) -> Option<ZvShaper> {
        let z = d.damping;
        if !(z > 0.0 && z < 1.0) {
            return None;
        }
        let root = libm::sqrt(1.0 - z * z);
        let k = libm::exp(-z * core::f64::consts::PI / root);
        Some(ZvShaper { first_fraction: 1.0 / (1.0 + k), delay_s: core::f64::consts::PI / (d.omega() * root) })
    }

    /// The command at `t_s` after a step from `from_ma` to `to_ma` begins.
    pub fn command_ma(&self, from_ma: f64, to_ma: f64, t_s: f64) -> f64 {
        if t_s < self.delay_s {
            from_ma + self.first_fraction * (to_ma - from_ma)
        } else {
            to_ma
        }
    }
}
