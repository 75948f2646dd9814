//! The virtual lens with dynamics (`etlcal.lens-dynamics/1`): the optics lag a command by
//! the membrane's step response, settle on the branch of the loop they came from, creep,
//! and the lens heats as the dynamics say; without dynamics nothing changes. The model's
//! clock is nearly stopped (time scale 1e-6) and driven by `advance_s`, so wall time does
//! not enter.

use std::time::Duration;

use etl_core::physics::dynamics::{LensDynamics, LensResponse};
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{ThermalModel, VirtualDevice, VirtualLensConfig, VirtualTransport};
use etl_hw::HwError;

fn open(dynamics: Option<LensDynamics>) -> (VirtualDevice, LensClient<VirtualTransport>) {
    let config = VirtualLensConfig { dynamics, time_scale: 1e-6, ..VirtualLensConfig::default() };
    let device = VirtualDevice::new(config).unwrap();
    let options = OpenOptions { timeout: Duration::from_millis(200), handshake: true, ..OpenOptions::default() };
    let client = LensClient::from_transport(device.transport(), options).unwrap();
    (device, client)
}

#[test]
fn the_optics_lag_a_step_as_the_core_model_says() {
    let d = LensDynamics::PUBLISHED;
    let (device, client) = open(Some(d));
    client.set_current_ma(100.0).unwrap();
    device.settle();
    let from = device.state().e_in_ma;
    client.set_current_ma(150.0).unwrap();
    let to = device.state().e_in_ma;
    // The same commands through the core model alone.
    let mut core = LensResponse::at_rest(0.0);
    core.command(from, &d);
    core.settle();
    core.command(to, &d);
    let mut elapsed = 0.0;
    for t in [0.0, 0.001, 0.004, 0.015, 0.1, 3.0] {
        device.advance_s(t - elapsed);
        core.advance(t - elapsed, &d);
        elapsed = t;
        let s = device.state();
        assert!(
            (s.effective_ma - core.effective_ma()).abs() < 1e-6,
            "t {t}: {} {}",
            s.effective_ma,
            core.effective_ma()
        );
        assert_eq!(s.e_in_ma, to);
        let e_t = etl_core::thermal::ThermalSurface::PAPER.e_t_ma(s.effective_ma, s.temperature_c).unwrap();
        assert!((s.e_com_ma - (s.effective_ma - e_t)).abs() < 1e-12);
    }
    // Right after the step the lens is still near the old level; 1 ms later on its way.
    device.settle();
    client.set_current_ma(100.0).unwrap();
    assert!((device.state().effective_ma - to).abs() < 0.5);
    device.advance_s(0.001);
    let mid = device.state().effective_ma;
    assert!(mid < to - 5.0 && mid > from + 5.0, "{mid}");
}

#[test]
fn a_current_approached_from_above_and_from_below_settles_the_loop_width_apart() {
    let d = LensDynamics { hysteresis_ma: 2.0, ..LensDynamics::PUBLISHED };
    let (device, client) = open(Some(d));
    let mut settled = vec![];
    for from in [100.0, 200.0] {
        client.set_current_ma(from).unwrap();
        device.settle();
        client.set_current_ma(150.0).unwrap();
        device.advance_s(60.0);
        settled.push(device.state().effective_ma);
    }
    let e_in = device.state().e_in_ma;
    assert!((settled[1] - settled[0] - 2.0).abs() < 1e-9, "{settled:?}");
    assert!((settled[0] - (e_in - 1.0)).abs() < 1e-9, "{settled:?} at {e_in}");
}

#[test]
fn the_lens_heats_by_the_dynamics_self_heating_and_time_constant() {
    let d = LensDynamics { self_heating_c_per_ma: 0.02, thermal_tau_s: 10.0, ..LensDynamics::PUBLISHED };
    let config = VirtualLensConfig {
        dynamics: Some(d),
        time_scale: 1e-6,
        thermal: ThermalModel { ambient_c: 25.0, ..ThermalModel::default() },
        ..VirtualLensConfig::default()
    };
    let device = VirtualDevice::new(config).unwrap();
    let client = LensClient::from_transport(device.transport(), OpenOptions::default()).unwrap();
    client.set_current_ma(200.0).unwrap();
    let e = device.state().e_in_ma;
    device.advance_s(10.0);
    // One time constant: 1 - 1/e of the rise.
    let rise = 0.02 * e;
    let expected = 25.0 + rise * (1.0 - (-1.0f64).exp());
    assert!((device.state().temperature_c - expected).abs() < 1e-9, "{} {expected}", device.state().temperature_c);
    device.set_target_temperature_c(40.0);
    device.settle();
    assert!((device.state().temperature_c - 40.0).abs() < 1e-9);
}

#[test]
fn without_dynamics_the_optics_follow_the_command_at_once() {
    let (device, client) = open(None);
    client.set_current_ma(150.0).unwrap();
    let s = device.state();
    assert_eq!(s.effective_ma, s.e_in_ma);
    let e_t = etl_core::thermal::ThermalSurface::PAPER.e_t_ma(s.e_in_ma, s.temperature_c).unwrap();
    assert_eq!(s.e_com_ma, s.e_in_ma - e_t);
}

#[test]
fn bad_dynamics_are_refused_naming_the_field() {
    let d = LensDynamics { damping: 0.0, ..LensDynamics::PUBLISHED };
    let e = VirtualDevice::new(VirtualLensConfig { dynamics: Some(d), ..VirtualLensConfig::default() }).err().unwrap();
    assert!(matches!(&e, HwError::Core(etl_core::Error::OutOfRange { what: "damping", .. })), "{e:?}");
    assert!(e.to_string().contains("damping"), "{e}");
}

/// Focal-power mode holds the power as the lens warms, as the firmware does from the
/// sensor's readings, to the stated residual: with r = 0.04 the power drifts 4 % of what a
/// fixed current drifts over the same warming, with r = 0 not beyond the code's steps.
#[test]
fn focal_power_mode_holds_the_power_to_the_firmware_s_residual() {
    use etl_hw::virtual_lens::FocalPowerCompensation;
    let drift = |fp: Option<f64>| {
        let config = VirtualLensConfig {
            time_scale: 1e-6,
            fp_compensation: FocalPowerCompensation { residual_fraction: fp.unwrap_or(0.04), reference_c: 25.0 },
            ..VirtualLensConfig::default()
        };
        let device = VirtualDevice::new(config).unwrap();
        let client = LensClient::from_transport(device.transport(), OpenOptions::default()).unwrap();
        device.set_target_temperature_c(25.0);
        device.settle();
        if fp.is_some() {
            client.enter_focal_power_mode(50.0, 20.0).unwrap();
            client.set_focal_power_dpt(12.5).unwrap();
        } else {
            client.set_current_ma(100.0).unwrap();
        }
        let before = device.state().focal_power_dpt;
        device.set_target_temperature_c(40.0);
        device.settle();
        device.advance_s(0.2); // two readings of the sensor at the new temperature
        device.state().focal_power_dpt - before
    };
    let fixed_current = drift(None);
    let (residual, perfect) = (drift(Some(0.04)), drift(Some(0.0)));
    assert!(fixed_current.abs() > 0.3, "{fixed_current} dpt");
    assert!((residual / fixed_current - 0.04).abs() < 0.01, "{residual} of {fixed_current} dpt");
    assert!(perfect.abs() < 0.01, "{perfect} dpt");
}
