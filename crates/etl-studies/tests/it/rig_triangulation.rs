//! The rig-triangulation study's code path on a few trials (the 200-trial figures of
//! docs/RESULTS.md come from its example in release mode), and its measurements exact on
//! noise-free pixels through the true rig.

use std::path::Path;

use etl_calib::rig::{CalibrationCovariance, CalibrationPart, Rig, RigSetting};
use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::model::CameraModel;
use etl_core::runtime::Trust;
use etl_core::thermal::ThermalSurface;
use etl_formats::rig::JointCovariance;
use etl_formats::ThermalRef;
use etl_sim::multi_camera::{simulate_multi_camera, truth_rig, MultiCameraDesign};
use etl_sim::rig::PAPER_TEMPERATURE_C;
use etl_sim::simulate::NoiseModel;
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
            assert!(p.z_scores[i].abs() < 4.0 && p.z_scores_independent[i].abs() < 4.0, "{p:?}");
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

/// The oracle: the point triangulated from `pixels` through `models` at `e_com_ma` (camera
/// 1's pose from the models' poses to the world, at the settings by Eq. R2), in camera
/// 0's frame at its setting: etl-core's triangulation on the models directly, not through
/// the rig files the study reads.
fn triangulate_models(models: &[CameraModel; 2], e_com_ma: [f64; 2], pixels: [[f64; 2]; 2]) -> [f64; 3] {
    etl_studies::rig_traced::world::triangulate_models(models, e_com_ma, pixels).unwrap()
}

#[test]
fn the_oracle_triangulates_noise_free_pixels_exactly() {
    for moving_centre in [false, true] {
        let (_, truths) = true_rig(moving_centre);
        let (w, e) = ([5.0, -3.0, 40.0], [110.0, 170.0]);
        let pixels = [0, 1].map(|k| truths[k].project(w, e[k]).unwrap());
        let x = triangulate_models(&[truths[0], truths[1]], e, pixels);
        let truth = truths[0].world_to_camera_at(w, e[0]);
        assert!((0..3).all(|i| (x[i] - truth[i]).abs() < 1e-6), "moving {moving_centre}: {x:?} {truth:?}");
    }
}

/// A made-up joint covariance over both true cameras' numbers, cross terms within each
/// camera and between the cameras.
fn made_up_joint(truths: &[CameraModel]) -> Vec<Vec<f64>> {
    let n: usize = truths.iter().map(|m| m.layout().len()).sum();
    // Standard deviations: 1e-5 of each number (1e-6 for a zero).
    let sd: Vec<f64> = truths
        .iter()
        .flat_map(|m| to_params(m)[..m.layout().len()].to_vec())
        .map(|v| if v == 0.0 { 1e-6 } else { 1e-5 * v.abs() })
        .collect();
    // Correlation 0.5^|i - j| over the concatenation (the AR(1) matrix: positive
    // definite), so neighbours across the cameras' boundary correlate too.
    let mut m = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..n {
            let rho = 0.5f64.powi((i as i32 - j as i32).abs());
            m[i][j] = rho * sd[i] * sd[j];
        }
    }
    m
}

/// With the joint covariance, the library's calibration part is J Sigma J^T with J the
/// derivative of the re-triangulated point through perturbed models (the oracle above),
/// to the finite differences' accuracy.
#[test]
fn the_joint_path_equals_a_direct_propagation() {
    for moving_centre in [false, true] {
        let design = MultiCameraDesign { moving_centre, ..MultiCameraDesign::new(2) };
        let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 3).unwrap();
        let truths = [sim.truths[0], sim.truths[1]];
        let mut file = truth_rig(&sim);
        for c in &mut file.cameras {
            c.calibration.as_mut().unwrap().thermal = Some(ThermalRef::paper());
        }
        let matrix = made_up_joint(&truths);
        file.joint_covariance = Some(JointCovariance { cameras: vec![0, 1], matrix: matrix.clone() });
        let rig = Rig::from_file(file, Path::new(".")).unwrap();
        let (w, e) = ([5.0, -3.0, 40.0], [110.0, 170.0]);
        let pixels = [0, 1].map(|k| truths[k].project(w, e[k]).unwrap());
        let t = PAPER_TEMPERATURE_C;
        let settings: Vec<RigSetting> =
            e.iter().map(|&e| RigSetting::of(ThermalSurface::PAPER.e_in_for_e_com(e, t).unwrap())).collect();
        let at = rig.at(&settings, &[t; 2], Trust::Refuse).unwrap();
        let got = at.triangulate(&pixels.map(Some), 0.2, CalibrationPart::Include).unwrap();
        assert_eq!(got.calibration_covariance, Some(CalibrationCovariance::Joint));
        let got = got.from_calibration.unwrap();
        // The oracle's J by central differences over every number.
        let mut jac = vec![];
        for k in 0..2 {
            let layout = truths[k].layout();
            let theta = to_params(&truths[k]);
            for i in 0..layout.len() {
                let h = 1e-3 * matrix[jac.len()][jac.len()].sqrt();
                let moved = |d: f64| {
                    let mut x = theta;
                    x[i] += d;
                    let mut m = truths;
                    m[k] = from_params(&layout, &x);
                    triangulate_models(&m, e, pixels)
                };
                let (p, m) = (moved(h), moved(-h));
                jac.push(std::array::from_fn::<f64, 3, _>(|a| (p[a] - m[a]) / (2.0 * h)));
            }
        }
        let mut want = [[0.0; 3]; 3];
        for (a, ja) in jac.iter().enumerate() {
            for (b, jb) in jac.iter().enumerate() {
                for p in 0..3 {
                    for q in 0..3 {
                        want[p][q] += ja[p] * matrix[a][b] * jb[q];
                    }
                }
            }
        }
        let scale = (0..3).map(|i| want[i][i]).fold(0.0, f64::max);
        assert!(scale > 1e-8, "moving {moving_centre}: {want:?}");
        for p in 0..3 {
            for q in 0..3 {
                assert!((got[p][q] - want[p][q]).abs() < 1e-4 * scale, "moving {moving_centre}: {got:?} {want:?}");
            }
        }
    }
}

#[test]
fn a_moving_centre_trial_runs() {
    let t = trial(&RigTriangulationDesign { moving_centre: true, noise: NOISE }, 8).unwrap();
    assert!(t.point.z_scores.iter().all(|z| z.abs() < 4.0), "{t:?}");
    assert!(t.moves.triangulated_refocused_um.abs() < 6.0, "{t:?}");
}
