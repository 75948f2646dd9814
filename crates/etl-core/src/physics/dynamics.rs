//! The lens's dynamics: how the current the optics follow lags the current commanded.
//!
//! The driver's DAC sets the coil current at once; the membrane does not follow at once.
//! [`LensResponse`] models the *effective* current y(t): the current whose static power
//! law gives the power the lens has at time t (so the rest of the model, E_com and the
//! camera, applies to y unchanged). From the command c(t), piecewise constant:
//!
//! - (D1) hysteresis, a rate-independent play operator of width h: at each new command,
//!   p = clamp(p, c - h/2, c + h/2). A level approached from below settles h/2 under the
//!   command, from above h/2 over it, so the in-focus currents of one target approached
//!   from the two sides differ by h.
//! - (D2) creep: a fraction a of each move of p arrives slowly,
//!   r(t) = p - a (p - q(t)), dq/dt = (p - q) / tau_c.
//! - (D3) the membrane, a damped second-order system driven by r:
//!   y'' + 2 zeta w y' + w^2 y = w^2 r, with w = 2 pi f_n.
//!
//! Between commands (D2)-(D3) are linear with r(t) = p + B e^{-t/tau_c}, so
//! [`LensResponse::advance`] is exact over any interval, however long: the particular part
//! K e^{-t/tau_c} with K = w^2 B / (w^2 - 2 zeta w / tau_c + 1/tau_c^2), plus the damped
//! homogeneous part in closed form (under-, critically and over-damped alike, written with
//! the decay folded into each exponential so that nothing overflows).
//!
//! A linear time-invariant model of the step response is what the published fast
//! focimetry of tunable lenses found (Opt. Express 27(3) 2085, 2019: "the temporal
//! response is repetitive and linear"). [`LensDynamics::PUBLISHED`] says where each default
//! comes from. Self-heating ([`LensDynamics::thermal_tau_s`],
//! [`LensDynamics::self_heating_c_per_ma`]) is carried here for the file and applied by
//! the virtual lens's thermal model.

use crate::error::{Error, Result};

/// The numbers of the dynamics (`etlcal.lens-dynamics/1`), units in the names.
///
/// ```
/// use etl_core::physics::dynamics::{LensDynamics, LensResponse};
/// let d = LensDynamics::PUBLISHED;
/// d.validate().unwrap();
/// let mut lens = LensResponse::at_rest(100.0);
/// lens.command(150.0, &d);
/// lens.advance(0.002, &d); // 2 ms after the step: still on its way
/// assert!(lens.effective_ma() < 149.0);
/// lens.advance(0.2, &d); // creep aside, settled
/// assert!((lens.effective_ma() - 150.0 + d.hysteresis_ma / 2.0).abs() < d.creep_fraction * 50.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensDynamics {
    /// Natural frequency f_n of the membrane's second-order response (D3), Hz.
    pub natural_frequency_hz: f64,
    /// Damping ratio zeta of (D3) (1: critically damped).
    pub damping: f64,
    /// Fraction a of a step that arrives by creep (D2), in [0, 0.5].
    pub creep_fraction: f64,
    /// Time constant tau_c of the creep (D2), s.
    pub creep_tau_s: f64,
    /// Width h of the hysteresis loop (D1), mA.
    pub hysteresis_ma: f64,
    /// Time constant of the lens's temperature, s.
    pub thermal_tau_s: f64,
    /// Rise of the lens's equilibrium temperature per mA of coil current, degC / mA.
    pub self_heating_c_per_ma: f64,
}

/// The accepted range of each number: (name, min, max). The creep must be at least ten
/// times slower than the membrane's natural period (checked apart), which keeps the
/// particular solution of (D2)-(D3) away from resonance.
const RANGES: [(&str, f64, f64); 7] = [
    ("natural_frequency_hz", 1.0, 1.0e5),
    ("damping", 1.0e-3, 10.0),
    ("creep_fraction", 0.0, 0.5),
    ("creep_tau_s", 1.0e-4, 1.0e5),
    ("hysteresis_ma", 0.0, 50.0),
    ("thermal_tau_s", 1.0e-3, 1.0e6),
    ("self_heating_c_per_ma", 0.0, 1.0),
];

impl LensDynamics {
    /// Defaults from published figures where there are some:
    /// - the step response: ASI's page on the EL-10-30 (shared/protocol, section 5) gives a
    ///   "15 ms transient response" and resonances at 150 Hz and 600 Hz. f_n = 150 Hz (the
    ///   lower, dominant one) and zeta = 0.28, which makes the 2 % settling time
    ///   4 / (zeta w) = 15 ms;
    /// - creep and hysteresis: no published figure was at hand. 1 % of a step creeping in
    ///   with tau = 2 s ("creep over seconds") and a loop of 0.5 mA (0.02 dpt at the
    ///   EL-10-30's ~0.04 dpt/mA, under the vendor's 0.1 dpt reproducibility) are this
    ///   project's choices;
    /// - self-heating: the virtual lens's thermal model (60 s; +5.5 degC at 240 mA, so
    ///   0.023 degC/mA), also this project's.
    pub const PUBLISHED: LensDynamics = LensDynamics {
        natural_frequency_hz: 150.0,
        damping: 0.28,
        creep_fraction: 0.01,
        creep_tau_s: 2.0,
        hysteresis_ma: 0.5,
        thermal_tau_s: 60.0,
        self_heating_c_per_ma: 0.023,
    };

    /// The numbers in [`RANGES`] order.
    fn values(&self) -> [f64; 7] {
        [
            self.natural_frequency_hz,
            self.damping,
            self.creep_fraction,
            self.creep_tau_s,
            self.hysteresis_ma,
            self.thermal_tau_s,
            self.self_heating_c_per_ma,
        ]
    }

    /// Checks every number: finite, within its range (`Error::OutOfRange` naming it), and
    /// the creep at least ten natural periods long.
    pub fn validate(&self) -> Result<()> {
        for ((what, min, max), value) in RANGES.into_iter().zip(self.values()) {
            if !value.is_finite() {
                return Err(Error::NotFinite { what });
            }
            if !(min..=max).contains(&value) {
                return Err(Error::OutOfRange { what, value, min, max });
            }
        }
        let min = 10.0 / self.omega();
        if self.creep_tau_s < min {
            let (what, value, max) = ("creep_tau_s", self.creep_tau_s, RANGES[3].2);
            return Err(Error::OutOfRange { what, value, min, max });
        }
        Ok(())
    }

    /// w = 2 pi f_n, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * core::f64::consts::PI * self.natural_frequency_hz
    }
}

/// The state of (D1)-(D3): the play operator's output p, the creep's q, the effective
/// current y and its rate, all in mA (rate in mA/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensResponse {
    play_ma: f64,
    creep_ma: f64,
    effective_ma: f64,
    rate_ma_per_s: f64,
}

impl LensResponse {
    /// At rest at `e_ma` (the loop centred on it).
    pub fn at_rest(e_ma: f64) -> Self {
        LensResponse { play_ma: e_ma, creep_ma: e_ma, effective_ma: e_ma, rate_ma_per_s: 0.0 }
    }

    /// The effective current y: what the optics follow, mA.
    pub fn effective_ma(&self) -> f64 {
        self.effective_ma
    }

    /// Its rate of change, mA/s.
    pub fn rate_ma_per_s(&self) -> f64 {
        self.rate_ma_per_s
    }

    /// Where the response tends at the present command (the play's output p), mA.
    pub fn resting_ma(&self) -> f64 {
        self.play_ma
    }

    /// A new command `c_ma` (D1): the play operator moves p to within h/2 of it. (Not
    /// `f64::clamp`, which panics on a NaN bound: a NaN command leaves p where it is.)
    pub fn command(&mut self, c_ma: f64, d: &LensDynamics) {
        let half = d.hysteresis_ma / 2.0;
        self.play_ma = self.play_ma.max(c_ma - half).min(c_ma + half);
    }

    /// Brings the membrane to rest where the present command leaves it (creep done, no
    /// motion), keeping the loop's branch.
    pub fn settle(&mut self) {
        self.creep_ma = self.play_ma;
        self.effective_ma = self.play_ma;
        self.rate_ma_per_s = 0.0;
    }

    /// Advances by `dt_s` (> 0; anything else leaves the state as it is) at the present
    /// command, exactly (module docs).
    pub fn advance(&mut self, dt_s: f64, d: &LensDynamics) {
        if !(dt_s > 0.0) {
            return;
        }
        let (p, w, z) = (self.play_ma, d.omega(), d.damping);
        let lambda = 1.0 / d.creep_tau_s;
        let b = d.creep_fraction * (self.creep_ma - p);
        let k = w * w * b / (w * w - 2.0 * z * w * lambda + lambda * lambda);
        let (e0, v0) = (self.effective_ma - p - k, self.rate_ma_per_s + lambda * k);
        let (e, v) = damped(e0, v0, w, z, dt_s);
        let decay = libm::exp(-lambda * dt_s);
        self.effective_ma = p + k * decay + e;
        self.rate_ma_per_s = -lambda * k * decay + v;
        self.creep_ma = p + (self.creep_ma - p) * decay;
    }
}

/// The homogeneous solution of x'' + 2 z w x' + w^2 x = 0 from (x0, v0) after `t` s:
/// x = x0 C + (v0 + z w x0) S and v = v0 C' + ..., with C and S the decaying cosine and
/// sine (or their hyperbolic or critical forms), each exponential carrying its own decay.
fn damped(x0: f64, v0: f64, w: f64, z: f64, t: f64) -> (f64, f64) {
    let beta2 = w * w * (1.0 - z * z);
    let decay = libm::exp(-z * w * t);
    // (C, S) = e^{-z w t} (cos bt, sin bt / b) for beta2 > 0, the hyperbolic forms below
    // zero, (1, t) at zero.
    let (c, s) = if beta2 > 0.0 {
        let b = libm::sqrt(beta2);
        (decay * libm::cos(b * t), decay * libm::sin(b * t) / b)
    } else if beta2 < 0.0 {
        let g = libm::sqrt(-beta2);
        let (up, down) = (libm::exp((g - z * w) * t), libm::exp(-(g + z * w) * t));
        (0.5 * (up + down), 0.5 * (up - down) / g)
    } else {
        (decay, decay * t)
    };
    let a = v0 + z * w * x0;
    let x = x0 * c + a * s;
    // d/dt (e^{-zwt} C0) = -z w C - beta2 S, d/dt (e^{-zwt} S0) = C - z w S.
    let v = x0 * (-z * w * c - beta2 * s) + a * (c - z * w * s);
    (x, v)
}
