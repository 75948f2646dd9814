//! Live temperature compensation (section 2.2.1 iii): hold a wanted E_com while the lens
//! temperature changes: read T, solve E_in from E_in - E_T(T, E_in) = E_com (etl-core's
//! inverse), send it; at a fixed rate.

use std::time::{Duration, Instant};

use etl_core::lens::{Lens, LensError, LensErrorKind};
use etl_core::thermal::ThermalCalibration;

/// How to hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldConfig {
    /// The E_com to hold, mA.
    pub e_com_ma: f64,
    /// Loop rate, Hz (each step reads T and sends one current): 0 for as fast as the link
    /// allows, else within [`RATE_RANGE_HZ`].
    pub rate_hz: f64,
    /// Stop after this long (None: until the observer stops it).
    pub duration: Option<Duration>,
}

/// The loop rates [`hold`] accepts besides 0 (as fast as possible), Hz: a period of at
/// most 1000 s, at least 0.1 ms (faster than any serial link answers).
pub const RATE_RANGE_HZ: [f64; 2] = [1e-3, 1e4];

/// The longest hold [`duration_from_s`] accepts, s (about 115 days).
pub const MAX_DURATION_S: f64 = 1e7;

/// How far the commanded current may lie from the one the compensation asks for, mA,
/// before [`hold`] stops with [`HoldError::Unreachable`]: a few DAC steps of the Lens
/// Driver 4 (one is 292.84 / 4095 = 0.0715 mA), so rounding passes and clamping to the
/// driver's limits does not.
pub const CLAMP_TOLERANCE_MA: f64 = 0.25;

/// A hold duration of `seconds`, which must lie in 0..=[`MAX_DURATION_S`] (finite): the
/// checked conversion callers use instead of `Duration::from_secs_f64`, which panics on
/// huge values.
///
/// ```
/// use etl_hw::hold::duration_from_s;
/// assert_eq!(duration_from_s(1.5).unwrap().as_millis(), 1500);
/// assert!(duration_from_s(1e30).is_err() && duration_from_s(f64::NAN).is_err());
/// ```
pub fn duration_from_s(seconds: f64) -> Result<Duration, etl_core::Error> {
    let bad = etl_core::Error::InvalidArgument { what: "hold duration must lie in 0..=1e7 s" };
    if !(0.0..=MAX_DURATION_S).contains(&seconds) {
        return Err(bad);
    }
    Duration::try_from_secs_f64(seconds).map_err(|_| bad)
}

/// The loop period of `rate_hz`: None for 0 (as fast as possible), else 1 / rate for a
/// rate within [`RATE_RANGE_HZ`].
fn period(rate_hz: f64) -> Result<Option<Duration>, etl_core::Error> {
    if rate_hz == 0.0 {
        return Ok(None);
    }
    let bad =
        etl_core::Error::InvalidArgument { what: "hold rate must be 0 (as fast as possible) or lie in 1e-3..=1e4 Hz" };
    if !(RATE_RANGE_HZ[0]..=RATE_RANGE_HZ[1]).contains(&rate_hz) {
        return Err(bad);
    }
    Duration::try_from_secs_f64(1.0 / rate_hz).map(Some).map_err(|_| bad)
}

/// `period` x `steps`, None without a period or on overflow.
fn p_checked(period: Option<Duration>, steps: u32) -> Option<Duration> {
    period?.checked_mul(steps)
}

/// One loop step, passed to the observer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldStep {
    /// Step number from 0.
    pub index: u64,
    /// The current commanded (after the driver's clamping and quantisation), mA.
    pub e_in_ma: f64,
    /// The temperature read, degC.
    pub temperature_c: f64,
    /// E_com the surface predicts for (T, commanded E_in), mA.
    pub e_com_ma: f64,
    /// |predicted E_com - wanted|, mA: quantisation and clamping.
    pub error_ma: f64,
    /// (E_in, T) lies outside the surface's calibrated range.
    pub extrapolated: bool,
}

/// What a hold did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldReport {
    /// Current commands sent.
    pub commands_sent: u64,
    /// Wall time spent.
    pub elapsed: Duration,
    /// commands_sent / elapsed, Hz.
    pub achieved_rate_hz: f64,
    /// Worst |predicted E_com - wanted| over the steps, mA.
    pub worst_e_com_error_ma: f64,
    /// [min, max] temperature read, degC.
    pub temperature_range_c: [f64; 2],
    /// Steps outside the calibrated range.
    pub extrapolated_steps: u64,
    /// The last step.
    pub last: Option<HoldStep>,
}

/// Why a hold stopped early.
#[derive(Debug, thiserror::Error)]
pub enum HoldError<E: std::fmt::Display + std::fmt::Debug> {
    /// The lens failed (communication, no sensor).
    #[error("lens: {0}")]
    Lens(E),
    /// The compensation refused (wanted E_com unreachable, T outside the domain).
    #[error("compensation: {0}")]
    Core(etl_core::Error),
    /// The current the compensation asks for lies beyond the driver's limits: the lens
    /// clamped it, so the wanted E_com is not held (the lens stays at the clamped current).
    #[error(
        "E_com {e_com_ma:.3} mA needs E_in {wanted_e_in_ma:.3} mA at {temperature_c:.2} degC, beyond the driver's limits: it commanded {commanded_e_in_ma:.3} mA"
    )]
    Unreachable {
        /// The E_com to hold, mA.
        e_com_ma: f64,
        /// The current the compensation asks for, mA.
        wanted_e_in_ma: f64,
        /// The current the lens commanded (clamped), mA.
        commanded_e_in_ma: f64,
        /// The temperature read, degC.
        temperature_c: f64,
    },
}

/// The lens's kind for a lens failure; a refused compensation is invalid input (the wanted
/// E_com or the temperature is outside what the calibration covers). Callers act on
/// `kind()` without matching the variants.
impl<E: LensError> LensError for HoldError<E> {
    fn kind(&self) -> LensErrorKind {
        match self {
            HoldError::Lens(e) => e.kind(),
            HoldError::Core(e) => e.kind(),
            HoldError::Unreachable { .. } => LensErrorKind::InvalidInput,
        }
    }
}

/// Runs the hold loop until `config.duration` passes or `observe` returns false.
///
/// Errors: a non-finite wanted E_com or a rate outside 0 or [`RATE_RANGE_HZ`]
/// ([`HoldError::Core`]); the lens or the compensation failing in a step (the loop stops
/// there); a commanded current more than [`CLAMP_TOLERANCE_MA`] from the wanted one, i.e.
/// clamped to the driver's limits ([`HoldError::Unreachable`], after that one command).
///
/// ```
/// use etl_hw::hold::{hold, HoldConfig};
/// use etl_hw::virtual_lens::{VirtualDevice, VirtualLensConfig};
/// use etl_core::thermal::ThermalCalibration;
/// let mut lens = VirtualDevice::new(VirtualLensConfig::default()).unwrap();
/// let cfg = HoldConfig { e_com_ma: 120.0, rate_hz: 0.0, duration: None };
/// let report = hold(&mut lens, &ThermalCalibration::PAPER, &cfg, |s| s.index < 9).unwrap();
/// assert_eq!(report.commands_sent, 10);
/// assert!(report.worst_e_com_error_ma < 0.04); // half a DAC step
/// ```
pub fn hold<L: Lens>(
    lens: &mut L,
    calibration: &ThermalCalibration,
    config: &HoldConfig,
    mut observe: impl FnMut(&HoldStep) -> bool,
) -> Result<HoldReport, HoldError<L::Error>> {
    etl_core::error::finite(config.e_com_ma, "e_com_ma").map_err(HoldError::Core)?;
    let period = period(config.rate_hz).map_err(HoldError::Core)?;
    let start = Instant::now();
    let mut report = HoldReport {
        commands_sent: 0,
        elapsed: Duration::ZERO,
        achieved_rate_hz: 0.0,
        worst_e_com_error_ma: 0.0,
        temperature_range_c: [f64::INFINITY, f64::NEG_INFINITY],
        extrapolated_steps: 0,
        last: None,
    };
    let mut index = 0u64;
    loop {
        let t_c = lens.temperature_c().map_err(HoldError::Lens)?;
        let want = calibration.e_in_for_e_com(config.e_com_ma, t_c).map_err(HoldError::Core)?;
        let e_in_ma = lens.set_current_ma(want.e_in_ma).map_err(HoldError::Lens)?;
        report.commands_sent += 1;
        if (e_in_ma - want.e_in_ma).abs() > CLAMP_TOLERANCE_MA {
            return Err(HoldError::Unreachable {
                e_com_ma: config.e_com_ma,
                wanted_e_in_ma: want.e_in_ma,
                commanded_e_in_ma: e_in_ma,
                temperature_c: t_c,
            });
        }
        let got = calibration.compensate(e_in_ma, t_c).map_err(HoldError::Core)?;
        let step = HoldStep {
            index,
            e_in_ma,
            temperature_c: t_c,
            e_com_ma: got.e_com_ma,
            error_ma: (got.e_com_ma - config.e_com_ma).abs(),
            extrapolated: got.extrapolated,
        };
        report.worst_e_com_error_ma = report.worst_e_com_error_ma.max(step.error_ma);
        report.temperature_range_c = [report.temperature_range_c[0].min(t_c), report.temperature_range_c[1].max(t_c)];
        report.extrapolated_steps += u64::from(step.extrapolated);
        report.last = Some(step);
        let go_on = observe(&step);
        index += 1;
        let done = !go_on || config.duration.is_some_and(|d| start.elapsed() >= d);
        if done {
            break;
        }
        // Checked: no overflow however long the hold runs (a step beyond u32 steps of the
        // period, about 136 years at 1 Hz, just does not wait).
        let next = u32::try_from(index).ok().and_then(|i| p_checked(period, i)).and_then(|d| start.checked_add(d));
        if let Some(next) = next {
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
        }
    }
    report.elapsed = start.elapsed();
    report.achieved_rate_hz = report.commands_sent as f64 / report.elapsed.as_secs_f64().max(1e-9);
    Ok(report)
}
