//! The joint calibration of simulated multi-camera ETL rigs against their truth.

use etl_calib::request::{CalibrationRequest, EivPriors, EstimatorChoice};
use etl_calib::rig_calibration::{calibrate_rig, JointSystem, LinearSolver, RigCalibration, RigCalibrationOptions};
use etl_core::calib::jacobian::to_params;
use etl_core::model::CameraModel;
use etl_formats::rig::relative_pose;
use etl_sim::multi_camera::{simulate_multi_camera, truth_rig, MultiCameraDesign, MultiCameraSimulation};
use etl_sim::simulate::NoiseModel;

/// Noise-free: the pixel noise is given (nothing to estimate it from).
fn noise_free_options(estimator: EstimatorChoice, solver: LinearSolver) -> RigCalibrationOptions {
    let priors = EivPriors { sigma_px: Some(0.2), ..EivPriors::default() };
    let request = CalibrationRequest { estimator: Some(estimator), priors, ..CalibrationRequest::default() };
    RigCalibrationOptions { request, solver, ..Default::default() }
}

/// Every number of `m` against `truth`, relative to the number: `rtol`, but 100 `rtol`
/// for the distortion's a_i (Eq. 18: each coefficient a w^2 + b w + c over the narrow
/// range of w = 1/f of the views, so a, b, c are nearly collinear: with the pixels fitted
/// to 1e-12 px, the constant terms move by up to 7e-8 of themselves along that valley,
/// which moves no pixel by more than 1e-9 px).
fn assert_numbers_close(m: &CameraModel, truth: &CameraModel, rtol: f64, what: &str) {
    let (x, t) = (to_params(m), to_params(truth));
    let names: Vec<&str> = truth.layout().names().collect();
    for (i, name) in names.iter().enumerate() {
        let scale = t[i].abs().max(1e-12);
        let tol = if name.starts_with('a') { 100.0 * rtol } else { rtol };
        let rel = (x[i] - t[i]).abs() / scale;
        assert!(rel <= tol, "{what} {name}: {} vs {} (rel {rel:e})", x[i], t[i]);
    }
}

/// The largest pixel distance between `m`'s and `truth`'s projections of the rig's
/// points of camera k at their recorded settings.
fn max_pixel_difference(sim: &MultiCameraSimulation, k: usize, m: &CameraModel) -> f64 {
    let obs = sim.dataset.camera_observations(k).observations;
    let mut worst: f64 = 0.0;
    for v in &obs.views {
        for p in &v.points {
            let (a, b) = (
                m.project(p.world_mm, v.e_com_ma.unwrap()).unwrap(),
                sim.truths[k].project(p.world_mm, v.e_com_ma.unwrap()).unwrap(),
            );
            worst = worst.max((a[0] - b[0]).hypot(a[1] - b[1]));
        }
    }
    worst
}

fn extrinsics_error(rig: &RigCalibration, sim: &MultiCameraSimulation, k: usize) -> [f64; 6] {
    let pose = |m: &CameraModel| (m.rotation_rodrigues, m.translation_mm);
    let (om, t) = relative_pose(pose(&sim.truths[0]), pose(&sim.truths[k]));
    let e = rig.extrinsics.iter().find(|e| e.camera == k).unwrap();
    core::array::from_fn(|i| if i < 3 { e.rotation_rodrigues[i] - om[i] } else { e.translation_mm[i - 3] - t[i - 3] })
}

#[test]
fn noise_free_rigs_are_recovered_to_solver_precision() {
    for (cameras, solver) in [(2, LinearSolver::Dense), (3, LinearSolver::Sparse)] {
        let design = MultiCameraDesign { baseline_mm: 90.0, ..MultiCameraDesign::new(cameras) };
        let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 5).unwrap();
        let rig = calibrate_rig(&sim.dataset, &noise_free_options(EstimatorChoice::Eiv, solver)).unwrap();
        assert_eq!(rig.sparse, solver == LinearSolver::Sparse);
        for k in 0..cameras {
            let m = rig.model(k).unwrap();
            assert_numbers_close(&m, &sim.truths[k], 1e-9, &format!("{cameras} cameras, camera {k}"));
            assert!(max_pixel_difference(&sim, k, &m) < 1e-9);
            assert!(rig.cameras[k].rms_px < 1e-9, "rms {}", rig.cameras[k].rms_px);
        }
        for k in 1..cameras {
            let e = extrinsics_error(&rig, &sim, k);
            assert!(
                e[..3].iter().all(|x| x.abs() < 1e-11) && e[3..].iter().all(|x| x.abs() < 1e-9),
                "camera {k}: {e:?}"
            );
            assert!((rig.baseline_mm(k).unwrap() - 90.0).abs() < 1e-9);
        }
        let dir = tempfile::tempdir().unwrap();
        rig.save(&dir.path().join("rig.json")).unwrap();
        let back = etl_formats::rig::RigFile::load(&dir.path().join("rig.json")).unwrap();
        assert_eq!(back.calibrations.len(), cameras);
        assert_eq!(back.file.extrinsics, rig.extrinsics);
        assert_eq!(truth_rig(&sim).extrinsics.len(), cameras - 1);
    }
}

/// The paper's estimator separates: the joint result is each camera's own calibration, to
/// the precision at which the single-camera solve stops (its ftol 1e-10 leaves a number
/// within a few 1e-6 of its standard deviation of the minimum: the joint solve, which
/// goes on to 1e-14, moves none by more than 1e-4 of it).
#[test]
fn with_the_paper_estimator_the_joint_result_is_each_cameras_own() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &noise, 11).unwrap();
    let request = CalibrationRequest { estimator: Some(EstimatorChoice::Paper), ..CalibrationRequest::default() };
    let rig = calibrate_rig(&sim.dataset, &RigCalibrationOptions { request, ..Default::default() }).unwrap();
    assert_eq!(rig.estimator, "paper");
    for c in &rig.cameras {
        let (joint, own) = (to_params(&c.calibration.model().unwrap()), to_params(&c.own.model().unwrap()));
        let layout = c.own.layout().unwrap();
        let std = c.own.std.to_params(&layout).unwrap();
        for (i, s) in std.iter().take(layout.len()).enumerate() {
            let d = (joint[i] - own[i]).abs();
            assert!(d <= 1e-4 * s, "{} number {i}: {} vs {} (std {s})", c.name, joint[i], own[i]);
        }
    }
    // The shared stage errors still correlate the cameras' estimates.
    let (o1, p1) = (rig.offsets[1], rig.cameras[1].calibration.layout().unwrap().len());
    let cross = rig.covariance.view((0, o1), (rig.offsets[1], p1)).iter().map(|x| x.abs()).fold(0.0, f64::max);
    assert!(cross > 0.0);
}

/// With the paper's noise, the extrinsics lie within 3 propagated standard deviations of
/// the truth, and the joint errors-in-variables estimate of the stage errors follows the
/// simulated ones.
#[test]
fn noisy_extrinsics_lie_within_three_standard_deviations() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &noise, 7).unwrap();
    let rig = calibrate_rig(&sim.dataset, &RigCalibrationOptions::default()).unwrap();
    assert_eq!(rig.estimator, "eiv");
    let e = extrinsics_error(&rig, &sim, 1);
    let cov = rig.extrinsics[0].covariance.unwrap();
    for i in 0..6 {
        let std = cov[i][i].sqrt();
        assert!(std > 0.0 && e[i].abs() <= 3.0 * std, "component {i}: error {} vs std {std}", e[i]);
    }
    assert!(rig.cost[1] <= rig.cost[0]);
    let truth = truth_rig(&sim);
    assert_eq!(truth.cameras.len(), 2);
    // The writer refuses a rig whose calibration is missing, and writes nothing.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig.json");
    let mut file = rig.rig_file();
    file.cameras[1].calibration = None;
    let e = file.save(&path).unwrap_err().to_string();
    assert!(e.contains("cameras[1]: give exactly one of calibration and calibration_path"), "{e}");
    assert_eq!(e.lines().count(), 1);
    assert!(!path.exists());
}

/// The dense and the sparse paths give the same step.
#[test]
fn the_dense_and_sparse_steps_agree() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let sim = simulate_multi_camera(&MultiCameraDesign::new(4), &noise, 2).unwrap();
    // A start off the truth: the step is not zero.
    let models: Vec<CameraModel> = sim
        .truths
        .iter()
        .map(|m| CameraModel { principal_point: [m.principal_point[0] + 2.0, m.principal_point[1]], ..*m })
        .collect();
    let system = JointSystem::new(&sim.dataset, &models, 0.2, (0.01, 0.4)).unwrap();
    assert_eq!(system.camera_count(), 4);
    for lambda in [0.0, 1e-3] {
        let dense = system.step(LinearSolver::Dense, lambda).unwrap();
        let sparse = system.step(LinearSolver::Sparse, lambda).unwrap();
        let scale = dense.iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert!(scale > 1e-6);
        for (i, (a, b)) in dense.iter().zip(&sparse).enumerate() {
            assert!((a - b).abs() <= 1e-9 * scale.max(a.abs()), "entry {i}: {a} vs {b}");
        }
    }
}

/// A rig whose cameras' centres move with their settings, noise-free: `--centre moving`
/// recovers every camera's numbers (the centre's too) and the extrinsics at E = 0.
#[test]
fn a_noise_free_rig_with_moving_centres_is_recovered() {
    let design = MultiCameraDesign { moving_centre: true, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 9).unwrap();
    let mut options = noise_free_options(EstimatorChoice::Eiv, LinearSolver::Auto);
    options.request.centre = Some(etl_calib::request::CentreChoice::Moving);
    let rig = calibrate_rig(&sim.dataset, &options).unwrap();
    for k in 0..2 {
        let m = rig.model(k).unwrap();
        assert!(m.centre.is_some());
        assert!(max_pixel_difference(&sim, k, &m) < 1e-7, "camera {k}");
        let dz = m.centre.unwrap().dz_mm[0];
        let dz_true = sim.truths[k].centre.unwrap().dz_mm[0];
        assert!((dz - dz_true).abs() < 1e-6 * dz_true.abs(), "camera {k}: dz1 {dz} vs {dz_true}");
    }
    let e = extrinsics_error(&rig, &sim, 1);
    assert!(e[..3].iter().all(|x| x.abs() < 1e-8) && e[3..].iter().all(|x| x.abs() < 1e-6), "{e:?}");
    assert_eq!(rig.extrinsics[0].reference_setting, Some([0.0, 0.0]));
}

/// A rig whose numbers its views do not fix is refused naming them: fx(E) of degree 5
/// for a camera seen at 3 settings (6 coefficients, 3 values) leaves the joint system
/// singular along that camera's focal coefficients.
#[test]
fn an_undetermined_rig_is_refused_naming_its_weakest_numbers() {
    let design = MultiCameraDesign { views: 3, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 5).unwrap();
    let mut models = sim.truths.clone();
    let pad = |p: &etl_core::model::FocalPoly| {
        let mut c = p.coefficients().to_vec();
        c.resize(6, 0.0);
        etl_core::model::FocalPoly::new(&c).unwrap()
    };
    (models[1].kf_x, models[1].kf_y) = (pad(&models[1].kf_x), pad(&models[1].kf_y));
    let system = JointSystem::new(&sim.dataset, &models, 0.2, (0.01, 0.4)).unwrap();
    let e = system.covariance().unwrap_err().to_string();
    assert!(
        e.contains(
            "the rig's numbers are not determined by its views: the joint system is singular along camera 1's kf"
        ),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1);
}
