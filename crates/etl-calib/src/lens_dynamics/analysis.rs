//! What the characterisation reads off its samples: a settling time, the creep's
//! exponential, and the membrane's natural frequency and damping. Pure functions of
//! (time s, current mA) samples, so that they are tested on exact curves.

use etl_core::physics::dynamics::{LensDynamics, LensResponse};

/// A sample: time since the command (s) and the current the optics follow (mA, as the
/// frames measure it).
pub type Sample = (f64, f64);

/// The mean of the last `fraction` of the samples' values (at least one).
pub fn final_level(samples: &[Sample], fraction: f64) -> f64 {
    let n = ((samples.len() as f64 * fraction).ceil() as usize).clamp(1, samples.len().max(1));
    let tail = &samples[samples.len().saturating_sub(n)..];
    tail.iter().map(|s| s.1).sum::<f64>() / tail.len().max(1) as f64
}

/// The settling time: the time of the first sample after which every sample stays within
/// `tolerance_ma` of `level` (0 when all do; the last sample's time when none settles).
pub fn settling_s(samples: &[Sample], level: f64, tolerance_ma: f64) -> f64 {
    match samples.iter().rposition(|s| (s.1 - level).abs() > tolerance_ma) {
        None => 0.0,
        Some(k) => samples.get(k + 1).map_or(samples[k].0, |s| s.0),
    }
}

/// The least-squares fit of y = a + b e^{-t/tau} + c t to `samples` (the exponential and
/// a linear drift beside it): (a, b, c, tau), tau found on a log grid over `tau_range` and
/// refined by golden section (a, b and c are linear given tau). None with fewer than four
/// samples or a singular fit.
pub fn exponential_fit(samples: &[Sample], tau_range: [f64; 2]) -> Option<(f64, f64, f64, f64)> {
    if samples.len() < 4 || !(tau_range[0] > 0.0 && tau_range[1] > tau_range[0]) {
        return None;
    }
    let sse = |tau: f64| linear_given_tau(samples, tau).map_or(f64::INFINITY, |(_, e)| e);
    let (lo, hi) = (tau_range[0].ln(), tau_range[1].ln());
    let grid = 200;
    let best = (0..=grid)
        .map(|k| lo + (hi - lo) * k as f64 / grid as f64)
        .min_by(|a, b| sse(a.exp()).total_cmp(&sse(b.exp())))?;
    let step = (hi - lo) / grid as f64;
    let tau = golden_min(|x| sse(x.exp()), best - step, best + step, 60).exp();
    linear_given_tau(samples, tau).map(|(x, _)| (x[0], x[1], x[2], tau))
}

/// ([a, b, c], SSE) of y = a + b e^{-t/tau} + c t, by the 3 x 3 normal equations.
fn linear_given_tau(samples: &[Sample], tau: f64) -> Option<([f64; 3], f64)> {
    let basis = |t: f64| [1.0, (-t / tau).exp(), t];
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    let mut r = nalgebra::Vector3::<f64>::zeros();
    for &(t, y) in samples {
        let g = nalgebra::Vector3::from(basis(t));
        m += g * g.transpose();
        r += g * y;
    }
    let x = m.cholesky()?.solve(&r);
    let sse = samples.iter().map(|&(t, y)| (y - nalgebra::Vector3::from(basis(t)).dot(&x)).powi(2)).sum();
    x.iter().all(|v| v.is_finite()).then_some(([x[0], x[1], x[2]], sse))
}

/// The minimum of a unimodal `f` on [a, b] by `steps` golden-section steps.
fn golden_min(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, steps: usize) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..steps {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - g * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

/// The membrane's step response (D3 alone) normalised to a unit step, at `t_s`.
fn unit_step(natural_frequency_hz: f64, damping: f64, t_s: f64) -> f64 {
    let d = LensDynamics {
        natural_frequency_hz,
        damping,
        creep_fraction: 0.0,
        hysteresis_ma: 0.0,
        ..LensDynamics::PUBLISHED
    };
    let mut r = LensResponse::at_rest(0.0);
    r.command(1.0, &d);
    r.advance(t_s, &d);
    r.effective_ma()
}

/// The natural frequency (Hz) and damping whose unit step response fits the step
/// `samples` (from `from_ma` towards `level`) best in least squares: a grid over
/// 10..5000 Hz (log) and damping 0.02..3 (log), then the best cell refined by coordinate
/// golden sections.
pub fn second_order_fit(samples: &[Sample], from_ma: f64, level: f64) -> Option<(f64, f64)> {
    let span = level - from_ma;
    if samples.len() < 4 || !(span.abs() > 0.0) {
        return None;
    }
    let sse = |ln_f: f64, ln_z: f64| {
        let (f, z) = (ln_f.exp(), ln_z.exp());
        samples.iter().map(|&(t, y)| ((y - from_ma) / span - unit_step(f, z, t)).powi(2)).sum::<f64>()
    };
    let (fs, zs) = ([10f64.ln(), 5000f64.ln()], [0.02f64.ln(), 3f64.ln()]);
    let n = 60;
    let at = |r: [f64; 2], k: usize| r[0] + (r[1] - r[0]) * k as f64 / n as f64;
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (at(fs, i), at(zs, j));
            let e = sse(x, y);
            if e < best.0 {
                best = (e, x, y);
            }
        }
    }
    let (mut x, mut y) = (best.1, best.2);
    let (hx, hy) = ((fs[1] - fs[0]) / n as f64, (zs[1] - zs[0]) / n as f64);
    for _ in 0..4 {
        x = golden_min(|v| sse(v, y), x - hx, x + hx, 40);
        y = golden_min(|v| sse(x, v), y - hy, y + hy, 40);
    }
    Some((x.exp(), y.exp()))
}
