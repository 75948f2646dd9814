//! The temperature-calibration procedure (section 4.1) against the virtual lens, driven by
//! the real client through a pseudo-terminal, and the synthetic camera seeing through the
//! virtual lens's true state: the fitted E_T surface against the lens's true one.
use std::time::Duration;

use etl_calib::thermal_calibration::{run_procedure, ProcedureOptions};
use etl_core::thermal::ThermalSurface;
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
use etl_sim::virtual_rig::{surface_error_ma, VirtualCamera, VirtualClimate};

#[test]
fn the_procedure_recovers_the_virtual_lens_surface() {
    let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
    let mut client =
        LensClient::open(device.path(), OpenOptions { timeout: Duration::from_millis(500), ..Default::default() })
            .unwrap();
    let mut camera = VirtualCamera::new(&device);
    camera.image_size = [480, 360];
    camera.aperture_mm = 10.0;
    let mut climate = VirtualClimate(&device);
    // A coarser grid than the paper's (5 x 5 instead of 11 x 11) keeps the test short; the
    // command line runs the paper's grid.
    let options = ProcedureOptions {
        e_in_grid_ma: vec![40.0, 90.0, 140.0, 190.0, 240.0],
        temperatures_c: vec![27.0, 29.5, 32.0, 34.5, 37.0],
        ..ProcedureOptions::default()
    };
    let r = run_procedure(&mut client, &mut camera, &mut climate, &options, &etl_core::progress::NoProgress).unwrap();
    assert_eq!(r.samples.len(), 25);
    let (referenced, absolute) =
        surface_error_ma(&r, &ThermalSurface::PAPER, [40.0, 240.0], [27.0, 37.0], 27.0).unwrap();
    println!("fit RMS {:.3} mA; surface error {referenced:.3} mA (referenced to 27 degC), {absolute:.3} mA (absolute); {} frames", r.rms_ma, r.frames);
    assert!(referenced < 0.3, "{referenced} mA");
    // Every commanded current stayed inside the driver's limits.
    let [lo, hi] = device.limits_ma();
    assert!(r.samples.iter().all(|s| (lo..=hi).contains(&s.e_in_ma)));
}

#[test]
fn bad_options_are_refused_before_any_command() {
    let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
    let mut client = LensClient::open(device.path(), OpenOptions::default()).unwrap();
    let mut camera = VirtualCamera::new(&device);
    let mut climate = VirtualClimate(&device);
    let commands_before = device.received().commands;
    for options in [
        ProcedureOptions { temperatures_c: vec![27.0], ..ProcedureOptions::default() },
        ProcedureOptions { e_in_grid_ma: vec![], ..ProcedureOptions::default() },
        ProcedureOptions { search_half_width_ma: 0.0, ..ProcedureOptions::default() },
    ] {
        assert!(
            run_procedure(&mut client, &mut camera, &mut climate, &options, &etl_core::progress::NoProgress).is_err()
        );
    }
    assert_eq!(device.received().commands, commands_before);
}

/// The procedure on a virtual lens with the published dynamics (fixtures/lens-dynamics):
/// frames grabbed as soon as the current is read back see the lens still moving, and the
/// first refocus runs off its window; a camera that waits 50 ms (model time) for the lens
/// to settle refocuses and recovers the surface, to within the loop's hysteresis and the
/// creep the procedure does not yet handle (docs/RESULTS.md, "The lens's dynamics").
#[test]
fn a_lens_with_dynamics_needs_the_camera_to_wait_for_it() {
    use etl_core::physics::dynamics::LensDynamics;
    use etl_sim::virtual_rig::{run_virtual_procedure, VirtualRigLens};
    let options = ProcedureOptions {
        e_in_grid_ma: vec![40.0, 107.0, 173.0, 240.0],
        temperatures_c: vec![27.0, 30.0, 33.0, 36.0],
        ..ProcedureOptions::default()
    };
    let no_progress = &etl_core::progress::NoProgress;
    let hasty = VirtualRigLens { dynamics: Some(LensDynamics::PUBLISHED), settle_s: 0.0 };
    let e = run_virtual_procedure(&options, &hasty, no_progress).unwrap_err().to_string();
    assert!(e.contains("ended at the edge of its window"), "{e}");
    let patient = VirtualRigLens { settle_s: 0.05, ..hasty };
    let v = run_virtual_procedure(&options, &patient, no_progress).unwrap();
    assert_eq!(v.result.samples.len(), 16);
    assert!(v.surface_error_ma < 1.0, "{} mA", v.surface_error_ma);
    let bad = VirtualRigLens { settle_s: -1.0, ..hasty };
    let e = run_virtual_procedure(&options, &bad, no_progress).unwrap_err().to_string();
    assert!(e.contains("settle_s -1 s must lie in 0..=10 s"), "{e}");
}
