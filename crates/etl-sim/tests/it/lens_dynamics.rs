//! `etl_calib::lens_dynamics::characterise` on the virtual lens with known dynamics,
//! framed by `etl_sim::lens_camera::SimLensCamera`: the settling times within 10 % of the
//! model's own (same tolerance, same window), the loop's width within 10 %, the creep's
//! time constant within 20 %, measured from rendered frames alone; the shaped step at
//! least twice as fast as the plain one.

use std::time::Duration;

use etl_calib::lens_dynamics::analysis::{final_level, settling_s};
use etl_calib::lens_dynamics::{characterise, CharacteriseOptions};
use etl_core::physics::dynamics::{LensDynamics, LensResponse};
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{VirtualDevice, VirtualLensConfig};
use etl_sim::lens_camera::SimLensCamera;

/// The model's settling time for a step `from` -> `to` (at rest before), sampled finely
/// over `window_s`, by the characterisation's own definition.
fn true_settling_s(d: &LensDynamics, from: f64, to: f64, window_s: f64, tolerance: f64) -> f64 {
    let mut r = LensResponse::at_rest(from);
    r.command(to, d);
    let dt = 1e-5;
    let samples: Vec<(f64, f64)> = (1..=(window_s / dt).round() as usize)
        .map(|k| {
            r.advance(dt, d);
            (k as f64 * dt, r.effective_ma())
        })
        .collect();
    settling_s(&samples, final_level(&samples, 0.1), tolerance * (to - from).abs())
}

#[test]
fn characterise_recovers_the_virtual_lens_s_dynamics_from_frames() {
    // The mechanical dynamics alone: a lens that warms with its current drifts between
    // the readings of a level by more than the loop is wide (0.023 degC/mA over 10 s of
    // rest moves E_T by tenths of a mA), which the procedure does not correct.
    let d = LensDynamics { self_heating_c_per_ma: 0.0, ..LensDynamics::PUBLISHED };
    let config = VirtualLensConfig { dynamics: Some(d), time_scale: 1e-6, ..VirtualLensConfig::default() };
    let device = VirtualDevice::new(config).unwrap();
    let options = OpenOptions { timeout: Duration::from_millis(500), ..OpenOptions::default() };
    let mut lens = LensClient::from_transport(device.transport(), options).unwrap();
    let mut camera = SimLensCamera::new(device.clone(), 2000.0).unwrap();
    let o = CharacteriseOptions { steps_ma: vec![20.0, 50.0], ..CharacteriseOptions::default() };
    let c = characterise(&mut lens, &mut camera, &o, &etl_core::progress::NoProgress).unwrap();
    let truth = [
        true_settling_s(&d, 100.0, 150.0, o.window_s, o.tolerance_fraction),
        true_settling_s(&d, 150.0, 100.0, o.window_s, o.tolerance_fraction),
    ];
    let summary = format!(
        "settling {:?} s (truth {truth:?}), hysteresis {} mA, repeatability {} mA, creep {} s x {}, f {} Hz, zeta {}",
        c.settling_s,
        c.hysteresis_ma,
        c.repeatability_ma,
        c.creep_tau_s,
        c.creep_fraction,
        c.natural_frequency_hz,
        c.damping
    );
    println!("{summary}");
    for k in 0..2 {
        assert!((c.settling_s[k] / truth[k] - 1.0).abs() < 0.1, "{summary}");
    }
    assert!((c.hysteresis_ma / d.hysteresis_ma - 1.0).abs() < 0.1, "{summary}");
    assert!((c.creep_tau_s / d.creep_tau_s - 1.0).abs() < 0.2, "{summary}");
    assert!((c.creep_fraction / d.creep_fraction - 1.0).abs() < 0.2, "{summary}");
    assert!((c.natural_frequency_hz / d.natural_frequency_hz - 1.0).abs() < 0.1, "{summary}");
    assert!((c.damping / d.damping - 1.0).abs() < 0.15, "{summary}");
    assert!(c.repeatability_ma < 0.1, "{summary}");
    // The zero-vibration shaper of the fitted membrane settles the 50 mA step at least
    // twice as fast, measured in frames.
    let shaped = c.shaped_settling_s.unwrap();
    println!("shaped settling {shaped:?} s");
    assert!(2.0 * shaped[0] <= c.settling_s[0] && 2.0 * shaped[1] <= c.settling_s[1], "{shaped:?} {summary}");
}
