//! Free views in the joint calibration of a rig: the board in free poses (no stage) seen
//! by the cameras at their own settings, on a simulated rig with known truth.

use etl_calib::request::{CalibrationRequest, EivPriors, EstimatorChoice};
use etl_calib::rig_calibration::{calibrate_rig, LinearSolver, RigCalibration, RigCalibrationOptions};
use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_formats::rig::relative_pose;
use etl_formats::rig_dataset::{RigDataset, RigFreeView, RigShot};
use etl_sim::multi_camera::{
    corner_mm, simulate_multi_camera, MultiCameraDesign, MultiCameraSimulation, STAGE_TRAVEL_MM,
};
use etl_sim::simulate::NoiseModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The board's corners of the simulated rig (its frame: `corner_mm`, Z = 0).
const CORNERS: usize = 41 * 33;

/// `n` free board poses (board to world): the board's centre at world (0, 0, z) over the
/// middle of the stage's travel, tilted by 10-25 degrees about axes around it.
fn free_poses(n: usize) -> Vec<([f64; 3], [f64; 3])> {
    let mid = 0.5 * (STAGE_TRAVEL_MM[0] + STAGE_TRAVEL_MM[1]);
    (0..n)
        .map(|f| {
            let phi = 2.0 * std::f64::consts::PI * f as f64 / n as f64;
            let tilt = (10.0 + 15.0 * (f % 2) as f64).to_radians();
            let om = [tilt * phi.cos(), tilt * phi.sin(), 0.05 * f as f64];
            (om, [0.0, 0.0, mid - 12.0 + 8.0 * (f % 3) as f64])
        })
        .collect()
}

/// The simulated rig's dataset with free views at `poses`: each camera at the setting and
/// temperature of its stage view nearest in depth (its recorded E_com, which is the true
/// current here: the free views carry no current error), pixels of its true model plus
/// Gaussian noise `sigma_px`, the corners inside its image.
fn with_free_views(
    sim: &MultiCameraSimulation,
    poses: &[([f64; 3], [f64; 3])],
    sigma_px: f64,
    seed: u64,
) -> RigDataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_px.max(1e-300)).unwrap();
    let mut d = sim.dataset.clone();
    for (om, t) in poses {
        let r = rodrigues_to_matrix(*om);
        let mut cameras = vec![];
        for (k, truth) in sim.truths.iter().enumerate() {
            let nearest =
                d.views.iter().filter_map(|v| v.cameras.iter().find(|s| s.camera == k).map(|s| (v.z_w_mm, s)));
            let (_, shot) = nearest.min_by(|a, b| (a.0 - t[2]).abs().total_cmp(&(b.0 - t[2]).abs())).unwrap();
            let e = shot.e_com_ma.unwrap();
            let [w, h] = d.cameras[k].image_size.map(f64::from);
            let mut points = vec![];
            for i in 0..CORNERS {
                let [x, y] = corner_mm(i);
                let p = mat_vec(&r, [x, y, 0.0]);
                let Ok(px) = truth.project([p[0] + t[0], p[1] + t[1], p[2] + t[2]], e) else { continue };
                if (0.0..w).contains(&px[0]) && (0.0..h).contains(&px[1]) {
                    let n = if sigma_px > 0.0 { [noise.sample(&mut rng), noise.sample(&mut rng)] } else { [0.0; 2] };
                    points.push([px[0] + n[0], px[1] + n[1], x, y]);
                }
            }
            if points.len() >= 12 {
                cameras.push(RigShot { camera: k, image: None, points: Some(points), ..shot.clone() });
            }
        }
        d.free_views.push(RigFreeView { cameras });
    }
    d
}

fn options(sigma_px: Option<f64>, solver: LinearSolver) -> RigCalibrationOptions {
    let priors = EivPriors { sigma_px, ..EivPriors::default() };
    let request = CalibrationRequest { estimator: Some(EstimatorChoice::Eiv), priors, ..CalibrationRequest::default() };
    RigCalibrationOptions { request, solver, ..Default::default() }
}

fn extrinsics_error(rig: &RigCalibration, sim: &MultiCameraSimulation) -> [f64; 6] {
    let pose = |m: &etl_core::model::CameraModel| (m.rotation_rodrigues, m.translation_mm);
    let (om, t) = relative_pose(pose(&sim.truths[0]), pose(&sim.truths[1]));
    let e = &rig.extrinsics[0];
    core::array::from_fn(|i| if i < 3 { e.rotation_rodrigues[i] - om[i] } else { e.translation_mm[i - 3] - t[i - 3] })
}

/// Noise-free free views: every camera, the extrinsics and each free board pose are
/// recovered to solver precision, with fixed and moving centres, by both linear paths
/// (which agree).
#[test]
fn noise_free_free_views_and_their_poses_are_recovered() {
    for moving_centre in [false, true] {
        let design = MultiCameraDesign { moving_centre, ..MultiCameraDesign::new(2) };
        let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 5).unwrap();
        let poses = free_poses(4);
        let d = with_free_views(&sim, &poses, 0.0, 1);
        assert!(d.free_views.iter().all(|v| v.cameras.len() == 2), "both cameras see every free view");
        let mut results = vec![];
        for solver in [LinearSolver::Dense, LinearSolver::Sparse] {
            let mut options = options(Some(0.2), solver);
            if moving_centre {
                options.request.centre = Some(etl_calib::request::CentreChoice::Moving);
            }
            let rig = calibrate_rig(&d, &options).unwrap();
            let e = extrinsics_error(&rig, &sim);
            let rms: Vec<f64> = rig.cameras.iter().map(|c| c.rms_px).collect();
            let what = format!(
                "moving {moving_centre} {solver:?}: rms {rms:?} iterations {} cost {:?}",
                rig.iterations, rig.cost
            );
            assert!(e[..3].iter().all(|x| x.abs() < 1e-10) && e[3..].iter().all(|x| x.abs() < 1e-8), "{what} {e:?}");
            assert_eq!(rig.free_view_poses.len(), 4);
            for (got, want) in rig.free_view_poses.iter().zip(&poses) {
                for i in 0..3 {
                    assert!((got.0[i] - want.0[i]).abs() < 1e-10, "om {got:?} vs {want:?}");
                    assert!((got.1[i] - want.1[i]).abs() < 1e-8, "t {got:?} vs {want:?}");
                }
            }
            assert!(rig.cameras.iter().all(|c| c.rms_px < 1e-9));
            results.push(rig.extrinsics[0].clone());
        }
        let (a, b) = (&results[0], &results[1]);
        for i in 0..3 {
            assert!((a.rotation_rodrigues[i] - b.rotation_rodrigues[i]).abs() < 1e-12);
            assert!((a.translation_mm[i] - b.translation_mm[i]).abs() < 1e-10);
        }
    }
}

/// With the paper's noise, free views tighten the extrinsics (their propagated standard
/// deviations), and the truth stays within 3 of them.
#[test]
fn free_views_tighten_the_extrinsics_which_cover_the_truth() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &noise, 7).unwrap();
    let d = with_free_views(&sim, &free_poses(6), noise.px, 3);
    let stage_only = calibrate_rig(&sim.dataset, &options(None, LinearSolver::Auto)).unwrap();
    let rig = calibrate_rig(&d, &options(None, LinearSolver::Auto)).unwrap();
    let (c0, c1) = (stage_only.extrinsics[0].covariance.unwrap(), rig.extrinsics[0].covariance.unwrap());
    let e = extrinsics_error(&rig, &sim);
    for i in 0..6 {
        let (s0, s1) = (c0[i][i].sqrt(), c1[i][i].sqrt());
        eprintln!("extrinsic {i}: std {s0:.3e} stage only, {s1:.3e} with free views, error {:.3e}", e[i]);
        assert!(s1 < 0.8 * s0, "component {i}: std {s1} with free views, {s0} without");
        assert!(e[i].abs() <= 3.0 * s1, "component {i}: error {} vs std {s1}", e[i]);
    }
}

/// Bad free views: the paper's estimator with free views, and a free view too sparse for
/// its pose, each refused in one line naming `free_views`.
#[test]
fn bad_free_views_are_refused_naming_them() {
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &NoiseModel::NONE, 5).unwrap();
    let d = with_free_views(&sim, &free_poses(2), 0.0, 1);
    let request = CalibrationRequest { estimator: Some(EstimatorChoice::Paper), ..CalibrationRequest::default() };
    let e = calibrate_rig(&d, &RigCalibrationOptions { request, ..Default::default() }).unwrap_err().to_string();
    assert!(e.contains("free_views: the paper's estimator calibrates each camera alone"), "{e}");
    assert_eq!(e.lines().count(), 1);
    let mut sparse = d.clone();
    for s in &mut sparse.free_views[1].cameras {
        s.points.as_mut().unwrap().truncate(3);
    }
    let e = calibrate_rig(&sparse, &options(Some(0.2), LinearSolver::Auto)).unwrap_err().to_string();
    assert!(e.contains("free_views[1]: the board's pose cannot be found"), "{e}");
    assert_eq!(e.lines().count(), 1);
}

/// A detector that reads each image's corners from a table (the images are empty files):
/// the board not found where the table has none.
struct TableDetector(std::collections::HashMap<std::path::PathBuf, etl_calib::pipeline::dataset::Detection>);

impl etl_calib::pipeline::dataset::CornerDetector for TableDetector {
    fn detect(
        &self,
        path: &std::path::Path,
        _board: &etl_formats::board::Board,
    ) -> etl_formats::Result<etl_calib::pipeline::dataset::Detection> {
        self.0.get(path).cloned().ok_or_else(|| etl_formats::Error::BoardNotFound("no corners in the table".into()))
    }
}

/// A rig dataset of images with free views: each camera's detected free views come back
/// as its points (board coordinates of the detection, the setting of the entry), a free
/// view whose board one camera did not find keeps the other camera, one no camera found is
/// dropped.
#[test]
fn free_views_of_images_are_detected_per_camera() {
    let sim = simulate_multi_camera(&MultiCameraDesign::new(2), &NoiseModel::NONE, 5).unwrap();
    let points = with_free_views(&sim, &free_poses(3), 0.0, 1);
    let dir = tempfile::tempdir().unwrap();
    let (mut images, mut table) = (points.clone(), std::collections::HashMap::new());
    images.offstate_views.clear();
    let [x0, y0] = corner_mm(0);
    let mut name = |shot: &mut RigShot, tag: String, found: bool| {
        let rel = std::path::PathBuf::from(format!("c{}_{tag}.png", shot.camera));
        std::fs::write(dir.path().join(&rel), b"").unwrap();
        let rows = shot.points.take().unwrap();
        let corners = rows.iter().map(|p| {
            let (col, row) = (((p[2] - x0) / 1.5).round() as u32, ((p[3] - y0) / 1.5).round() as u32);
            (row * 41 + col, [p[0], p[1]])
        });
        let detection =
            etl_calib::pipeline::dataset::Detection { image_size: [1936, 1458], corners: corners.collect() };
        if found {
            table.insert(dir.path().join(&rel), detection);
        }
        shot.image = Some(rel);
    };
    for (j, v) in images.views.iter_mut().enumerate() {
        v.cameras.iter_mut().for_each(|s| name(s, format!("v{j}"), true));
    }
    for (f, v) in images.free_views.iter_mut().enumerate() {
        // Free view 0: camera 1 misses the board; free view 2: both do.
        v.cameras.iter_mut().for_each(|s| {
            let found = !(f == 2 || (f == 0 && s.camera == 1));
            name(s, format!("f{f}"), found)
        });
    }
    let path = dir.path().join("rig_dataset.json");
    images.save(&path).unwrap();
    let (got, _) =
        etl_calib::rig_calibration::detect_rig(&images, &path, &TableDetector(table), &etl_core::progress::NoProgress)
            .unwrap();
    assert_eq!(got.free_views.len(), 2, "free view 2 (no camera found it) is dropped");
    assert_eq!(got.free_views[0].cameras.iter().map(|s| s.camera).collect::<Vec<_>>(), vec![0]);
    assert_eq!(got.free_views[1].cameras.len(), 2);
    for (g, want) in [
        (&got.free_views[0].cameras[0], &points.free_views[0].cameras[0]),
        (&got.free_views[1].cameras[1], &points.free_views[1].cameras[1]),
    ] {
        assert_eq!((g.e_in_ma, g.e_com_ma, g.temperature_c), (want.e_in_ma, want.e_com_ma, want.temperature_c));
        let (a, b) = (g.points.as_ref().unwrap(), want.points.as_ref().unwrap());
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(b) {
            assert_eq!([p[0], p[1]], [q[0], q[1]]);
            assert!((p[2] - (q[2] - x0)).abs() < 1e-9 && (p[3] - (q[3] - y0)).abs() < 1e-9, "{p:?} {q:?}");
        }
    }
}

/// With `setting_views: joint` each camera's own calibration (the joint solve's start)
/// takes the rig's free views as its tilted views: with moving centres and the paper's
/// noise, each camera's own dz(E) move from 80 to 200 mA is closer to the truth than from
/// its stage views alone.
#[test]
fn the_free_views_serve_each_cameras_own_calibration_as_tilted_views() {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    let design = MultiCameraDesign { moving_centre: true, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&design, &noise, 3).unwrap();
    let d = with_free_views(&sim, &free_poses(8), noise.px, 4);
    let move_mm =
        |m: &etl_core::model::CameraModel| m.centre.unwrap().dz_mm_at(200.0) - m.centre.unwrap().dz_mm_at(80.0);
    let mut errors = vec![];
    for joint in [false, true] {
        let mut o = options(None, LinearSolver::Auto);
        o.request.centre = Some(etl_calib::request::CentreChoice::Moving);
        if joint {
            o.request.setting_views = Some(etl_calib::pipeline::SettingViews::Joint);
        }
        let rig = calibrate_rig(&d, &o).unwrap();
        let own: Vec<f64> =
            (0..2).map(|k| (move_mm(&rig.cameras[k].own.model().unwrap()) - move_mm(&sim.truths[k])).abs()).collect();
        errors.push(own);
    }
    eprintln!("own move error, mm, stage views alone {:?}, with the free views {:?}", errors[0], errors[1]);
    for k in 0..2 {
        assert!(
            errors[1][k] < errors[0][k],
            "camera {k}: own move error {} with tilted views, {} without",
            errors[1][k],
            errors[0][k]
        );
    }
}
