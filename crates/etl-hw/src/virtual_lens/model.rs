//! The physical model behind the virtual lens: the liquid lens of the paper (Eq. 1-10)
//! driven at E_com = E_in - E_T(T, E_in) (Eq. 8), a first-order thermal model (ambient,
//! coil heating, a heater/Peltier element, one time constant) and the lens's digital
//! sensor (1/16 degC steps, a new value every 0.1 s).
//!
//! With dynamics ([`LensDynamics`], `etlcal.lens-dynamics/1`) the optics follow the
//! commanded current through the membrane's step response, creep and hysteresis
//! ([`etl_core::physics::dynamics`], D1-D3): the state's `effective_ma` is what they follow,
//! and E_com = y - E_T(T, y) of it. The lens then heats linearly with the current
//! (T_eq = ambient + s |E_in| + R_th P_heater, time constant `thermal_tau_s`) instead of the
//! coil's I^2 R. Without dynamics the optics follow the command at once, as before.

use etl_core::physics::dynamics::{LensDynamics, LensResponse};
use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;

use crate::codec::scaling::{current_code, current_ma, temperature_raw};
use crate::codec::Mode;

/// The thermal model: dT/dt = (T_eq - T) / tau with
/// T_eq = ambient + R_th (I^2 R_coil + P_heater).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalModel {
    /// Ambient temperature, degC.
    pub ambient_c: f64,
    /// Thermal resistance lens -> ambient, K/W.
    pub thermal_resistance_k_per_w: f64,
    /// Coil resistance, ohm (the coil's I^2 R heats the lens).
    pub coil_resistance_ohm: f64,
    /// Time constant, s.
    pub tau_s: f64,
}

impl Default for ThermalModel {
    /// 25 degC ambient, 8 K/W, a 12 ohm coil (+5.5 K at 240 mA), tau = 60 s.
    fn default() -> Self {
        ThermalModel { ambient_c: 25.0, thermal_resistance_k_per_w: 8.0, coil_resistance_ohm: 12.0, tau_s: 60.0 }
    }
}

/// How the virtual driver's firmware compensates temperature in focal-power mode.
///
/// A real driver reads the lens's EEPROM and re-computes the current for the commanded
/// power at each new reading of the lens's sensor. The virtual one does the same with a
/// model of the lens that misses a fraction of the thermal drift since the EEPROM's
/// reference temperature: it takes E_T_fw(T, E) = E_T(T, E) - r (E_T(T, E) - E_T(T_ref, E)),
/// so the power held drifts by r times what it would drift at a fixed current.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalPowerCompensation {
    /// r, the fraction of the drift left (0: perfect compensation).
    pub residual_fraction: f64,
    /// T_ref, where the firmware's model is exact, degC.
    pub reference_c: f64,
}

impl FocalPowerCompensation {
    /// The driver current the firmware sets for compensated current `e_com_ma` at sensor
    /// reading `t_c` on a lens whose true surface is `surface`: E_in = E_com + E_T_fw(T,
    /// E_in) by fixed-point iteration from the true surface's answer (|dE_T/dE| is a few
    /// hundredths: it converges at once). The lens then runs at E_in - E_T(T, E_in), off
    /// `e_com_ma` by r (E_T(T, E_in) - E_T(T_ref, E_in)). None out of the surface's reach.
    pub fn firmware_e_in_ma(&self, surface: &ThermalSurface, e_com_ma: f64, t_c: f64) -> Option<f64> {
        let FocalPowerCompensation { residual_fraction: r, reference_c: t_ref } = *self;
        let mut e_in = surface.e_in_for_e_com(e_com_ma, t_c).ok()?;
        for _ in 0..20 {
            let (now, at_ref) = (surface.e_t_ma(e_in, t_c).ok()?, surface.e_t_ma(e_in, t_ref).ok()?);
            e_in = e_com_ma + now - r * (now - at_ref);
        }
        e_in.is_finite().then_some(e_in)
    }
}

impl Default for FocalPowerCompensation {
    /// r = 0.04 at T_ref = 25 degC: Optotune states a reproducibility of typically 0.1 dpt
    /// over 10..50 degC with compensation (MAN16 section 4.3), where an EL-10-30 drifts
    /// about 0.067 dpt/degC uncompensated, 2.7 dpt over that range: 0.1 / 2.7 = 4 %.
    fn default() -> Self {
        FocalPowerCompensation { residual_fraction: 0.04, reference_c: 25.0 }
    }
}

/// A snapshot of the virtual lens's true state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensState {
    /// Model time since spawn, s (wall time x time scale, plus explicit advances).
    pub model_time_s: f64,
    /// The current the driver outputs (after its clamping and quantisation), mA.
    pub e_in_ma: f64,
    /// The current code the driver outputs.
    pub current_code: i16,
    /// The current the optics follow, mA: `e_in_ma` itself without dynamics, else where
    /// the membrane's response to the commands has got to (D1-D3).
    pub effective_ma: f64,
    /// True lens temperature, degC.
    pub temperature_c: f64,
    /// What the lens's sensor reports, degC (quantised, updated every sensor period).
    pub sensor_c: f64,
    /// E_T(T, E) of the configured surface at the effective current, mA (NaN outside its
    /// domain).
    pub e_t_ma: f64,
    /// E_com = E - E_T at the effective current E, mA: the current the optics respond to.
    pub e_com_ma: f64,
    /// Focal length of the liquid lens f_liq(E_com) (Eq. 5), mm (NaN outside the model's range).
    pub f_liq_mm: f64,
    /// Focal length of the ETL group f_com(E_com) (Eq. 10), mm.
    pub f_com_mm: f64,
    /// Focal power of the liquid lens 1000 / f_liq, dioptres.
    pub focal_power_dpt: f64,
    /// Heater power (negative: a Peltier element cooling), W.
    pub heater_w: f64,
    /// Operation mode.
    pub mode: Mode,
}

/// The device's registers and physics.
#[derive(Debug, Clone)]
pub(crate) struct Model {
    pub physics: LensPhysics,
    pub surface: ThermalSurface,
    pub thermal: ThermalModel,
    pub sensor_period_s: f64,
    pub has_sensor: bool,
    pub max_current_centi_ma: i16,
    pub upper_limit_code: i16,
    pub lower_limit_code: i16,
    pub time_s: f64,
    pub temperature_c: f64,
    pub sensor_raw: i16,
    pub code: i16,
    pub heater_w: f64,
    pub mode: Mode,
    pub fp_code: i16,
    pub temperature_limits_x16: Option<(i16, i16)>,
    /// The membrane's dynamics and its state (None: the optics follow the command at once).
    pub dynamics: Option<(LensDynamics, LensResponse)>,
    /// The firmware's temperature compensation in focal-power mode.
    pub fp_compensation: FocalPowerCompensation,
    /// The focal power commanded in focal-power mode, dpt (None: none yet).
    pub fp_target_dpt: Option<f64>,
}

impl Model {
    pub fn max_current_ma(&self) -> f64 {
        f64::from(self.max_current_centi_ma) / 100.0
    }

    pub fn e_in_ma(&self) -> f64 {
        current_ma(self.code, self.max_current_ma())
    }

    fn thermal_tau_s(&self) -> f64 {
        self.dynamics.as_ref().map_or(self.thermal.tau_s, |(d, _)| d.thermal_tau_s)
    }

    /// The power that heats the lens at the present current, W: the coil's I^2 R, or with
    /// dynamics their linear self-heating expressed through the thermal resistance.
    fn coil_power_w(&self) -> f64 {
        match &self.dynamics {
            Some((d, _)) => d.self_heating_c_per_ma * self.e_in_ma().abs() / self.thermal.thermal_resistance_k_per_w,
            None => {
                let i_a = self.e_in_ma() / 1000.0;
                i_a * i_a * self.thermal.coil_resistance_ohm
            }
        }
    }

    fn t_eq_c(&self) -> f64 {
        self.thermal.ambient_c + self.thermal.thermal_resistance_k_per_w * (self.coil_power_w() + self.heater_w)
    }

    fn temperature_after(&self, dt_s: f64) -> f64 {
        let t_eq = self.t_eq_c();
        t_eq + (self.temperature_c - t_eq) * (-dt_s / self.thermal_tau_s()).exp()
    }

    /// Advances the model by `dt_s` at constant inputs; the sensor samples the true
    /// temperature at each multiple of its period.
    pub fn advance(&mut self, dt_s: f64) {
        if !(dt_s > 0.0) {
            return;
        }
        let p = self.sensor_period_s;
        let ticks_before = (self.time_s / p).floor();
        let ticks_after = ((self.time_s + dt_s) / p).floor();
        if ticks_after > ticks_before {
            let to_last_tick = ticks_after * p - self.time_s;
            self.sensor_raw = temperature_raw(self.temperature_after(to_last_tick));
        }
        self.temperature_c = self.temperature_after(dt_s);
        self.time_s += dt_s;
        if ticks_after > ticks_before {
            self.hold_focal_power();
        }
        if let Some((d, r)) = &mut self.dynamics {
            r.advance(dt_s, d);
        }
    }

    /// Jumps to thermal equilibrium at the present inputs (the sensor follows at once), and
    /// the membrane to rest where the present command leaves it.
    pub fn settle(&mut self) {
        if let Some((_, r)) = &mut self.dynamics {
            r.settle();
        }
        self.temperature_c = self.t_eq_c();
        self.sensor_raw = temperature_raw(self.temperature_c);
    }

    /// The heater power that makes the equilibrium temperature `t_c` at the present current.
    pub fn heater_for_c(&self, t_c: f64) -> f64 {
        (t_c - self.thermal.ambient_c) / self.thermal.thermal_resistance_k_per_w - self.coil_power_w()
    }

    /// Sets the output code as the firmware does: clamped to +-4095 and to the software
    /// limits.
    pub fn apply_code(&mut self, code: i16) {
        self.code = code.clamp(-4095, 4095).clamp(self.lower_limit_code, self.upper_limit_code);
        let e_in_ma = self.e_in_ma();
        if let Some((d, r)) = &mut self.dynamics {
            r.command(e_in_ma, d);
        }
    }

    /// In focal-power mode with a power commanded: the firmware sets the current that holds
    /// it at the sensor's reading, by its own model of the lens ([`FocalPowerCompensation`]).
    /// A power out of reach leaves the current as it is.
    pub fn hold_focal_power(&mut self) {
        let (Mode::Controlled, Some(dpt)) = (self.mode, self.fp_target_dpt) else { return };
        if let Some(e_in) = self.e_com_for_power(dpt).and_then(|e_com| self.firmware_e_in_ma(e_com)) {
            self.apply_code(current_code(e_in, self.max_current_ma()));
        }
    }

    /// The driver current the firmware's model says gives `e_com_ma` at the sensor's
    /// reading ([`FocalPowerCompensation::firmware_e_in_ma`]).
    fn firmware_e_in_ma(&self, e_com_ma: f64) -> Option<f64> {
        self.fp_compensation.firmware_e_in_ma(&self.surface, e_com_ma, self.sensor_c())
    }

    /// The current the optics follow now, mA (the command itself without dynamics).
    pub fn effective_ma(&self) -> f64 {
        self.dynamics.as_ref().map_or(self.e_in_ma(), |(_, r)| r.effective_ma())
    }

    pub fn sensor_c(&self) -> f64 {
        f64::from(self.sensor_raw) / 16.0
    }

    /// Focal power of the liquid lens at compensated current `e_com_ma` (NaN outside the
    /// physics model's range; [`LensPhysics::power_dpt`]).
    pub fn power_dpt_at(&self, e_com_ma: f64) -> f64 {
        self.physics.power_dpt(e_com_ma)
    }

    /// The compensated current that gives focal power `dpt` over [0, upper limit]
    /// ([`LensPhysics::current_for_power_ma`]); None if out of reach.
    pub fn e_com_for_power(&self, dpt: f64) -> Option<f64> {
        let hi = current_ma(self.upper_limit_code, self.max_current_ma());
        self.physics.current_for_power_ma(dpt, [0.0, hi])
    }

    pub fn state(&self) -> LensState {
        let (e_in_ma, effective_ma) = (self.e_in_ma(), self.effective_ma());
        let e_t_ma = self.surface.e_t_ma(effective_ma, self.temperature_c).unwrap_or(f64::NAN);
        let e_com_ma = effective_ma - e_t_ma;
        let f_liq_mm = self.physics.f_liq_mm(e_com_ma).unwrap_or(f64::NAN);
        let f_com_mm = self.physics.f_com_mm(e_com_ma).unwrap_or(f64::NAN);
        LensState {
            model_time_s: self.time_s,
            e_in_ma,
            current_code: self.code,
            effective_ma,
            temperature_c: self.temperature_c,
            sensor_c: self.sensor_c(),
            e_t_ma,
            e_com_ma,
            f_liq_mm,
            f_com_mm,
            focal_power_dpt: 1000.0 / f_liq_mm,
            heater_w: self.heater_w,
            mode: self.mode,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Model {
        Model {
            physics: LensPhysics::paper(),
            surface: ThermalSurface::PAPER,
            thermal: ThermalModel::default(),
            sensor_period_s: 0.1,
            has_sensor: true,
            max_current_centi_ma: 29284,
            upper_limit_code: 4095,
            lower_limit_code: -4095,
            time_s: 0.0,
            temperature_c: 25.0,
            sensor_raw: 400,
            code: 0,
            heater_w: 0.0,
            mode: Mode::Current,
            fp_code: 0,
            temperature_limits_x16: None,
            dynamics: None,
            fp_compensation: FocalPowerCompensation::default(),
            fp_target_dpt: None,
        }
    }

    /// First-order response: after one time constant 63.2 % of the step.
    #[test]
    fn thermal_step_response() {
        let mut m = model();
        m.heater_w = 1.0; // +8 K at equilibrium
        m.advance(60.0);
        assert!((m.temperature_c - (25.0 + 8.0 * (1.0 - (-1.0f64).exp()))).abs() < 1e-9);
        // Coil heating: 240 mA in 12 ohm at 8 K/W is +5.53 K.
        let mut m = model();
        m.apply_code(crate::codec::scaling::current_code(240.0, 292.84));
        m.settle();
        let i = m.e_in_ma() / 1000.0;
        assert!((m.temperature_c - (25.0 + 8.0 * 12.0 * i * i)).abs() < 1e-12);
        assert!((m.heater_for_c(30.0) - (5.0 / 8.0 - 12.0 * i * i)).abs() < 1e-12);
    }

    /// The sensor holds the value sampled at the last 0.1 s tick, in 1/16 degC steps.
    #[test]
    fn sensor_quantises_and_samples() {
        let mut m = model();
        m.heater_w = 1.0;
        m.advance(0.05);
        assert_eq!(m.sensor_raw, 400); // no tick yet
        m.advance(0.06); // tick at 0.1 s
        let at_tick = 25.0 + 8.0 * (1.0 - (-0.1f64 / 60.0).exp());
        assert_eq!(m.sensor_raw, (at_tick * 16.0).round() as i16);
        assert_eq!(m.sensor_c() * 16.0, f64::from(m.sensor_raw));
    }

    /// E_com = E_in - E_T(T, E_in) drives the optics (Eq. 8): at 37 degC the focal power
    /// at a fixed E_in is that of E_com at 27 degC-ish.
    #[test]
    fn state_follows_eq_8_and_10() {
        let mut m = model();
        m.apply_code(crate::codec::scaling::current_code(150.0, 292.84));
        m.temperature_c = 37.0;
        let s = m.state();
        let e_t = ThermalSurface::PAPER.e_t_ma(s.e_in_ma, 37.0).unwrap();
        assert!((s.e_com_ma - (s.e_in_ma - e_t)).abs() < 1e-12);
        assert!((s.f_liq_mm - LensPhysics::paper().f_liq_mm(s.e_com_ma).unwrap()).abs() < 1e-12);
        assert!((s.f_com_mm - LensPhysics::paper().f_com_mm(s.e_com_ma).unwrap()).abs() < 1e-12);
        // The inverse used by controlled mode.
        let dpt = m.power_dpt_at(120.0);
        assert!((m.e_com_for_power(dpt).unwrap() - 120.0).abs() < 1e-9);
        assert!(m.e_com_for_power(100.0).is_none());
    }

    /// The firmware clamps to +-4095 and to the software limits.
    #[test]
    fn firmware_clamps_codes() {
        let mut m = model();
        m.upper_limit_code = 3000;
        m.lower_limit_code = -100;
        m.apply_code(i16::MAX);
        assert_eq!(m.code, 3000);
        m.apply_code(i16::MIN);
        assert_eq!(m.code, -100);
    }
}
