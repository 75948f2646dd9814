//! The rig-triangulation study's code path on a few trials (the 200-trial figures of
//! docs/RESULTS.md come from its example in release mode), and its measurements exact on
//! noise-free pixels through the true rig.

use std::path::Path;

use etl_calib::rig::Rig;
use etl_formats::ThermalRef;
use etl_sim::multi_camera::{simulate_multi_camera, truth_rig, MultiCameraDesign};
use etl_sim::rig::PAPER_TEMPERATURE_C;
use etl_sim::simulate::NoiseModel;
use etl_studies::rig_triangulation::joint::triangulate_models;
use etl_studies::rig_triangulation::moves::move_errors;
use etl_studies::rig_triangulation::{rig_triangulation, trial, RigTriangulationDesign, NOISE};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn each_trial_lies_within_four_sigma_and_measures_the_move_within_microns() {
    let design = RigTriangulationDesign { moving_centre: false, noise: NOISE };
    let r = rig_triangulation(&design, 2, 31);
    assert!(r.failed.is_empty(), "{:?}", r.failed);
    for t in &r.results {
        let p = &t.point;
        for i in 0..3 {
            assert!(p.z_scores[i].abs() < 4.0 && p.z_scores_joint[i].abs() < 4.0, "{p:?}");
            // The calibration's part dominates: tens to hundreds of um per axis.
            assert!(p.std_mm[i] > 1e-3 && p.std_mm[i] < 2.0, "{p:?}");
        }
        assert!(p.d2.is_finite() && p.d2_pixels_only >= p.d2, "{p:?}");
        let m = &t.moves;
        assert!(m.corners >= 12, "{m:?}");
        // 200 trials: RMS 1.0 um, max 4.4 um by triangulation; PnP about 4 um RMS.
        assert!(m.triangulated_refocused_um.abs() < 6.0 && m.triangulated_fixed_um.abs() < 6.0, "{m:?}");
        assert!(m.pnp_refocused_um.abs() < 20.0 && m.pnp_fixed_um.abs() < 20.0, "{m:?}");
    }
    assert!(r.markdown().contains("| triangulated, refocused |"));
}

/// The true rig (the paper's thermal surface, as the simulation records E_in) and its
/// simulation.
fn true_rig(moving_centre: bool) -> (Rig, Vec<etl_core::model::CameraModel>) {
    let design = MultiCameraDesign { moving_centre, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 3).unwrap();
    let mut file = truth_rig(&sim);
    for c in &mut file.cameras {
        c.calibration.as_mut().unwrap().thermal = Some(ThermalRef::paper());
    }
    (Rig::from_file(file, Path::new(".")).unwrap(), sim.truths)
}

#[test]
fn the_noise_free_move_through_the_true_rig_is_exact() {
    for moving_centre in [false, true] {
        let (rig, truths) = true_rig(moving_centre);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let m = move_errors(&rig, &truths, PAPER_TEMPERATURE_C, 30.0, 0.0, &mut rng).unwrap();
        // 1e-6 mm = 1e-3 um.
        for e in [m.triangulated_refocused_um, m.triangulated_fixed_um, m.pnp_refocused_um, m.pnp_fixed_um] {
            assert!(e.abs() < 1e-3, "moving {moving_centre}: {m:?}");
        }
    }
}

#[test]
fn the_joint_diagnosis_triangulates_noise_free_pixels_exactly() {
    for moving_centre in [false, true] {
        let (_, truths) = true_rig(moving_centre);
        let (w, e) = ([5.0, -3.0, 40.0], [110.0, 170.0]);
        let pixels = [0, 1].map(|k| truths[k].project(w, e[k]).unwrap());
        let x = triangulate_models(&[truths[0], truths[1]], e, pixels).unwrap();
        let truth = truths[0].world_to_camera_at(w, e[0]);
        assert!((0..3).all(|i| (x[i] - truth[i]).abs() < 1e-6), "moving {moving_centre}: {x:?} {truth:?}");
    }
}

#[test]
fn a_moving_centre_trial_runs() {
    let t = trial(&RigTriangulationDesign { moving_centre: true, noise: NOISE }, 8).unwrap();
    assert!(t.point.z_scores.iter().all(|z| z.abs() < 4.0), "{t:?}");
    assert!(t.moves.triangulated_refocused_um.abs() < 6.0, "{t:?}");
}
