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
    /// Loop rate, Hz (each step reads T and sends one current); 0 or infinite: as fast as
    /// the link allows.
    pub rate_hz: f64,
    /// Stop after this long (None: until the observer stops it).
    pub duration: Option<Duration>,
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
}

/// The lens's kind for a lens failure; a refused compensation is invalid input (the wanted
/// E_com or the temperature is outside what the calibration covers). Callers act on
/// `kind()` without matching the variants.
impl<E: LensError> LensError for HoldError<E> {
    fn kind(&self) -> LensErrorKind {
        match self {
            HoldError::Lens(e) => e.kind(),
            HoldError::Core(e) => e.kind(),
        }
    }
}

/// Runs the hold loop until `config.duration` passes or `observe` returns false.
///
/// Errors: a non-finite wanted E_com or rate ([`HoldError::Core`]); the lens or the
/// compensation failing in a step (the loop stops there).
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
    if config.rate_hz.is_nan() || config.rate_hz < 0.0 {
        return Err(HoldError::Core(etl_core::Error::InvalidArgument { what: "hold rate must be >= 0 Hz" }));
    }
    let period = if config.rate_hz > 0.0 && config.rate_hz.is_finite() {
        Some(Duration::from_secs_f64(1.0 / config.rate_hz))
    } else {
        None
    };
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
        if let Some(p) = period {
            let next = start + p.mul_f64(index as f64);
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
