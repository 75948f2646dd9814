//! The simulated N-camera rig: every camera sees the board in enough views at enough
//! currents, the truth's extrinsics put each camera at the design's baseline, and the
//! stage error is one per view.

use etl_formats::rig::relative_pose;
use etl_sim::multi_camera::{simulate_multi_camera, truth_rig, MultiCameraDesign};
use etl_sim::simulate::NoiseModel;

#[test]
fn every_camera_sees_the_board_and_stands_at_its_baseline() {
    for (cameras, baseline_mm) in [(2, 60.0), (3, 150.0)] {
        let design = MultiCameraDesign { cameras, baseline_mm, ..MultiCameraDesign::new(cameras) };
        let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 1).unwrap();
        sim.dataset.validate().unwrap();
        for k in 0..cameras {
            let obs = sim.dataset.camera_observations(k).observations;
            let currents: Vec<f64> = obs.views.iter().filter_map(|v| v.e_com_ma).collect();
            assert!(obs.views.len() >= 8, "camera {k} of {cameras}: {} views", obs.views.len());
            let spread = currents.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - currents.iter().cloned().fold(f64::INFINITY, f64::min);
            assert!(spread > 50.0, "camera {k}: currents span {spread} mA");
            assert!(obs.views.iter().all(|v| v.points.len() >= 12));
            assert_eq!(obs.offstate_views.len(), 10);
            // Noise-free: every pixel is the truth's projection at the recorded setting.
            let v = &obs.views[0];
            let p = sim.truths[k].project(v.points[0].world_mm, v.e_com_ma.unwrap()).unwrap();
            assert!((p[0] - v.points[0].pixel[0]).abs() < 1e-9 && (p[1] - v.points[0].pixel[1]).abs() < 1e-9);
        }
        let rig = truth_rig(&sim);
        for e in &rig.extrinsics {
            let t = e.translation_mm;
            let b = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            assert!((b - baseline_mm).abs() < 1e-9, "camera {}: baseline {b} mm", e.camera);
            let pose = |m: &etl_core::model::CameraModel| (m.rotation_rodrigues, m.translation_mm);
            let (om, _) = relative_pose(pose(&sim.truths[0]), pose(&sim.truths[e.camera]));
            assert_eq!(om, e.rotation_rodrigues);
        }
        let dir = tempfile::tempdir().unwrap();
        rig.save(&dir.path().join("truth.json")).unwrap();
    }
}

#[test]
fn the_stage_error_is_shared_and_the_current_errors_are_each_cameras() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &noise, 3).unwrap();
    assert_eq!(sim.true_dz_mm.len(), 15);
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    assert!(rms(&sim.true_dz_mm) > 0.003 && rms(&sim.true_dz_mm) < 0.03);
    let both: Vec<(f64, f64)> = (0..15).filter_map(|j| Some((sim.true_de_ma[0][j]?, sim.true_de_ma[1][j]?))).collect();
    assert!(both.len() >= 5);
    assert!(both.iter().all(|(a, b)| a != b));
}
