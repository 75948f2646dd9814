//! The lens's dynamics (`etl_core::physics::dynamics`, D1-D3) against independent
//! solutions: the textbook step response of a damped oscillator, a fine Runge-Kutta
//! integration of (D2)-(D3), the play operator's loop width; the ZV shaper against a plain
//! step (`etl_core::physics::shaping`).

use etl_core::physics::dynamics::{LensDynamics, LensResponse};
use etl_core::physics::shaping::ZvShaper;
use etl_core::Error;

/// The published defaults with neither creep nor hysteresis: (D3) alone.
fn membrane_only(damping: f64) -> LensDynamics {
    LensDynamics { damping, creep_fraction: 0.0, hysteresis_ma: 0.0, ..LensDynamics::PUBLISHED }
}

/// (D2)-(D3) integrated by classical RK4 in steps of `h` s from rest at 0 after a command
/// step to `c` (no hysteresis): (y, y') at `t`.
fn rk4(d: &LensDynamics, c: f64, t: f64, h: f64) -> (f64, f64) {
    let (w, z, a, tau) = (d.omega(), d.damping, d.creep_fraction, d.creep_tau_s);
    let f = |s: [f64; 3]| {
        let r = c - a * (c - s[2]);
        [s[1], w * w * (r - s[0]) - 2.0 * z * w * s[1], (c - s[2]) / tau]
    };
    let mut s = [0.0; 3];
    let n = (t / h).round() as usize;
    for _ in 0..n {
        let k1 = f(s);
        let k2 = f(core::array::from_fn(|i| s[i] + 0.5 * h * k1[i]));
        let k3 = f(core::array::from_fn(|i| s[i] + 0.5 * h * k2[i]));
        let k4 = f(core::array::from_fn(|i| s[i] + h * k3[i]));
        s = core::array::from_fn(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    (s[0], s[1])
}

/// The response `t` s after a step from rest at 0 to `c`.
fn step(d: &LensDynamics, c: f64, t: f64) -> LensResponse {
    let mut lens = LensResponse::at_rest(0.0);
    lens.command(c, d);
    lens.advance(t, d);
    lens
}

#[test]
fn an_underdamped_step_follows_the_textbook_response() {
    let d = membrane_only(0.28);
    let (w, z) = (d.omega(), d.damping);
    let wd = w * (1.0 - z * z).sqrt();
    for t in [1e-4, 1e-3, 3.3e-3, 7e-3, 0.015, 0.05] {
        let exact = 1.0 - (-z * w * t).exp() * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin());
        let y = step(&d, 50.0, t).effective_ma();
        assert!((y - 50.0 * exact).abs() < 1e-9, "t = {t}: {y} against {}", 50.0 * exact);
    }
}

#[test]
fn every_damping_and_the_creep_agree_with_a_fine_runge_kutta() {
    for zeta in [0.05, 0.28, 0.999_999, 1.0, 1.000_001, 3.0] {
        let d = LensDynamics { damping: zeta, hysteresis_ma: 0.0, creep_fraction: 0.2, ..LensDynamics::PUBLISHED };
        for t in [0.002, 0.02, 0.5] {
            let lens = step(&d, 40.0, t);
            let (y, v) = rk4(&d, 40.0, t, 1e-6);
            assert!((lens.effective_ma() - y).abs() < 1e-7, "zeta {zeta}, t {t}: {} against {y}", lens.effective_ma());
            assert!(
                (lens.rate_ma_per_s() - v).abs() < 1e-4,
                "zeta {zeta}, t {t}: {} against {v}",
                lens.rate_ma_per_s()
            );
        }
    }
}

#[test]
fn advancing_in_pieces_equals_advancing_at_once_and_long_intervals_stay_finite() {
    let d = LensDynamics::PUBLISHED;
    let once = step(&d, 60.0, 0.37);
    let mut pieces = step(&d, 60.0, 0.0);
    for _ in 0..37 {
        pieces.advance(0.01, &d);
    }
    assert!((once.effective_ma() - pieces.effective_ma()).abs() < 1e-9);
    assert!((once.rate_ma_per_s() - pieces.rate_ma_per_s()).abs() < 1e-6);
    for zeta in [0.28, 1.0, 5.0] {
        let far = step(&LensDynamics { damping: zeta, ..d }, 60.0, 1e6);
        assert_eq!(far.effective_ma(), far.resting_ma(), "zeta {zeta}");
        assert_eq!(far.rate_ma_per_s(), 0.0, "zeta {zeta}");
    }
}

#[test]
fn a_level_approached_from_below_and_from_above_differs_by_the_loop_width() {
    let d = LensDynamics::PUBLISHED;
    let settle = |from: f64| {
        let mut lens = LensResponse::at_rest(from);
        lens.command(150.0, &d);
        lens.advance(100.0, &d);
        lens.effective_ma()
    };
    let (below, above) = (settle(100.0), settle(200.0));
    assert!((above - below - d.hysteresis_ma).abs() < 1e-9, "{below} {above}");
    assert!((below - (150.0 - d.hysteresis_ma / 2.0)).abs() < 1e-9);
    // Rate-independent: a command inside the loop moves nothing.
    let mut lens = LensResponse::at_rest(150.0);
    lens.command(150.0 + 0.4 * d.hysteresis_ma, &d);
    lens.advance(10.0, &d);
    assert!((lens.effective_ma() - 150.0).abs() < 1e-12);
}

#[test]
fn the_creep_brings_its_fraction_with_its_time_constant() {
    let d = LensDynamics { hysteresis_ma: 0.0, ..LensDynamics::PUBLISHED };
    let left = |t: f64| 50.0 - step(&d, 50.0, t).effective_ma();
    // Once the membrane has rung down, what is left decays as a 50 e^{-t/tau}.
    for t in [0.2, 1.0, 4.0] {
        let expected = d.creep_fraction * 50.0 * (-t / d.creep_tau_s).exp();
        assert!((left(t) - expected).abs() < 1e-3 * expected, "t {t}: {} against {expected}", left(t));
    }
}

/// The first time after which the response stays within `tol_ma` of `target`, sampled
/// every 0.05 ms over 200 ms of a response `at(t)`.
fn settling_s(at: impl Fn(f64) -> f64, target: f64, tol_ma: f64) -> f64 {
    let mut last_out = 0.0;
    for k in 0..4000 {
        let t = k as f64 * 5e-5;
        if (at(t) - target).abs() > tol_ma {
            last_out = t + 5e-5;
        }
    }
    last_out
}

#[test]
fn the_published_step_settles_in_about_15_ms_and_the_shaped_step_more_than_twice_as_fast() {
    let d = LensDynamics::PUBLISHED;
    // A 50 mA step, from a level reached from below (the loop's lower branch), to 2 %.
    let start = || {
        let mut lens = LensResponse::at_rest(100.0);
        lens.command(100.0, &d);
        lens
    };
    let target = 150.0 - d.hysteresis_ma / 2.0;
    let plain = |t: f64| {
        let mut lens = start();
        lens.command(150.0, &d);
        lens.advance(t, &d);
        lens.effective_ma()
    };
    let zv = ZvShaper::of(&d).unwrap();
    let shaped = |t: f64| {
        let mut lens = start();
        lens.command(zv.command_ma(100.0, 150.0, 0.0), &d);
        lens.advance(t.min(zv.delay_s), &d);
        lens.command(zv.command_ma(100.0, 150.0, t.max(zv.delay_s)), &d);
        lens.advance(t - t.min(zv.delay_s), &d);
        lens.effective_ma()
    };
    let (t_plain, t_shaped) = (settling_s(plain, target, 1.0), settling_s(shaped, target, 1.0));
    assert!((0.010..0.017).contains(&t_plain), "plain step: {t_plain} s");
    assert!(t_shaped <= zv.delay_s + 1e-4 && 2.0 * t_shaped < t_plain, "shaped {t_shaped} s, plain {t_plain} s");
    assert!((zv.delay_s - 0.5 / (150.0 * (1.0f64 - 0.28 * 0.28).sqrt())).abs() < 1e-12);
    assert!(ZvShaper::of(&LensDynamics { damping: 1.0, ..d }).is_none());
}

#[test]
fn bad_numbers_are_refused_naming_the_field() {
    let d = LensDynamics::PUBLISHED;
    let cases = [
        (LensDynamics { natural_frequency_hz: 0.0, ..d }, "natural_frequency_hz"),
        (LensDynamics { damping: -0.1, ..d }, "damping"),
        (LensDynamics { creep_fraction: 0.9, ..d }, "creep_fraction"),
        (LensDynamics { creep_tau_s: f64::NAN, ..d }, "creep_tau_s"),
        (LensDynamics { creep_tau_s: 1e-3, ..d }, "creep_tau_s"),
        (LensDynamics { hysteresis_ma: -1.0, ..d }, "hysteresis_ma"),
        (LensDynamics { thermal_tau_s: f64::INFINITY, ..d }, "thermal_tau_s"),
        (LensDynamics { self_heating_c_per_ma: 2.0, ..d }, "self_heating_c_per_ma"),
    ];
    for (bad, field) in cases {
        match bad.validate() {
            Err(Error::OutOfRange { what, .. } | Error::NotFinite { what }) => assert_eq!(what, field),
            other => panic!("{field}: {other:?}"),
        }
    }
}
