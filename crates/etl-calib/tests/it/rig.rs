//! The rig at run time (`etl_calib::rig`) against the synthetic two-camera rig of
//! `etl_sim::stereo_rig` (known models, pose and moving centres): the pose at settings and
//! the triangulated point against a direct construction (each camera placed in a world
//! frame, its centre moved by its own model, Eq. C2), the covariances against Monte Carlo,
//! rectified rows and maps against the rectified projection, and every bad input.

use std::path::Path;

use etl_calib::rig::{CalibrationPart, Rig, RigAt, RigSetting};
use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::model::projection::project_camera_point;
use etl_core::model::rotation::{mat_t_vec, mat_vec, rodrigues_to_matrix};
use etl_core::model::{CameraModel, DistortionModel};
use etl_formats::calibration::Calibration;
use etl_formats::rig::RigFile;
use etl_formats::Trust;
use etl_sim::stereo_rig;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

fn rig(family: DistortionModel) -> Rig {
    Rig::from_file(stereo_rig::rig_file(family), Path::new(".")).unwrap()
}

fn at(rig: &Rig, e_in_ma: [f64; 2], t_c: [f64; 2]) -> RigAt {
    rig.at(&e_in_ma.map(RigSetting::of), &t_c, Trust::Refuse).unwrap()
}

/// The direct construction: camera c placed in a world frame (camera 0's frame at its
/// reference setting) by its model's own pose, T_c(E) = T_c + dz_c(E_ref) e_z - dz_c(E) e_z
/// (Eq. C2 through `CameraModel::project`), so that at the reference settings the pose is
/// the rig file's.
fn placed(family: DistortionModel) -> [CameraModel; 2] {
    let [mut m0, mut m1] = stereo_rig::models(family);
    let [r0, r1] = stereo_rig::REFERENCE_SETTING_MA;
    let dz = |m: &CameraModel, e: f64| m.centre.unwrap().dz_mm_at(e);
    (m0.rotation_rodrigues, m0.translation_mm) = ([0.0; 3], [0.0, 0.0, dz(&m0, r0)]);
    let t = stereo_rig::translation_mm();
    (m1.rotation_rodrigues, m1.translation_mm) = (stereo_rig::ROTATION_RODRIGUES, [t[0], t[1], t[2] + dz(&m1, r1)]);
    [m0, m1]
}

/// At random settings and temperatures: the pose of camera 1 is the world poses' (R_1 R_0^T,
/// t_1 - R t_0 at the settings), and noise-free pixels give the point back to 1e-6 mm.
#[test]
fn rig_triangulates_the_truth_at_random_settings() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // How far the pose moved from the file's: the test would pass for a constant pose
    // were it not checked.
    let mut moved = 0.0f64;
    for family in [DistortionModel::OpenCv, DistortionModel::Paper] {
        let rig = rig(family);
        let world = placed(family);
        for _ in 0..6 {
            let e_in = [rng.random_range(100.0..200.0), rng.random_range(100.0..200.0)];
            let t_c = [rng.random_range(28.0..36.0), rng.random_range(28.0..36.0)];
            let a = at(&rig, e_in, t_c);
            let e = [a.cameras()[0].e_com_ma(), a.cameras()[1].e_com_ma()];
            // The pose from the world poses: X_c = R_c W + t_c(E_c).
            let (t0, t1) = (world[0].translation_at(e[0]), world[1].translation_at(e[1]));
            let r = rodrigues_to_matrix(stereo_rig::ROTATION_RODRIGUES);
            let rt0 = mat_vec(&r, t0);
            let pose = a.poses()[1];
            for i in 0..3 {
                assert!((pose.translation_mm[i] - (t1[i] - rt0[i])).abs() < 1e-9, "{e:?}: {pose:?}");
            }
            let file_t = stereo_rig::translation_mm();
            moved = moved.max((0..3).map(|i| (pose.translation_mm[i] - file_t[i]).abs()).sum::<f64>());
            for _ in 0..3 {
                let w =
                    [rng.random_range(-60.0..140.0), rng.random_range(-80.0..80.0), rng.random_range(400.0..1500.0)];
                let pixels = [Some(world[0].project(w, e[0]).unwrap()), Some(world[1].project(w, e[1]).unwrap())];
                let tri = a.triangulate(&pixels, 0.1, CalibrationPart::PixelOnly).unwrap();
                let truth = world[0].world_to_camera_at(w, e[0]);
                for i in 0..3 {
                    assert!(
                        (tri.point_mm[i] - truth[i]).abs() < 1e-6,
                        "{family:?} {w:?}: {:?} {truth:?}",
                        tri.point_mm
                    );
                }
                assert!(tri.from_calibration.is_none() && tri.covariance_mm2 == tri.from_pixels && !tri.extrapolated);
            }
        }
    }
    assert!(moved > 0.1, "{moved}");
}

/// The standard deviations of the point over 2000 noisy triangulations against
/// sqrt(diag(sigma^2 (J^T J)^-1)): within 10 %.
#[test]
fn rig_pixel_covariance_matches_monte_carlo() {
    let rig = rig(DistortionModel::OpenCv);
    let a = at(&rig, [150.0, 170.0], [30.0, 32.0]);
    let world = placed(DistortionModel::OpenCv);
    let e = [a.cameras()[0].e_com_ma(), a.cameras()[1].e_com_ma()];
    let w = [40.0, -20.0, 700.0];
    let clean = [world[0].project(w, e[0]).unwrap(), world[1].project(w, e[1]).unwrap()];
    let sigma = 0.3;
    let predicted = a.triangulate(&clean.map(Some), sigma, CalibrationPart::PixelOnly).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let n = 2000;
    let samples: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let noisy = clean.map(|p| {
                let dx: f64 = StandardNormal.sample(&mut rng);
                let dy: f64 = StandardNormal.sample(&mut rng);
                Some([p[0] + sigma * dx, p[1] + sigma * dy])
            });
            a.triangulate(&noisy, sigma, CalibrationPart::PixelOnly).unwrap().point_mm
        })
        .collect();
    let std = spread(&samples);
    for i in 0..3 {
        let ratio = std[i] / predicted.std_mm()[i];
        assert!((ratio - 1.0).abs() < 0.1, "axis {i}: Monte Carlo {} predicted {}", std[i], predicted.std_mm()[i]);
    }
}

fn spread(samples: &[[f64; 3]]) -> [f64; 3] {
    let n = samples.len() as f64;
    let mean: [f64; 3] = std::array::from_fn(|i| samples.iter().map(|s| s[i]).sum::<f64>() / n);
    std::array::from_fn(|i| (samples.iter().map(|s| (s[i] - mean[i]).powi(2)).sum::<f64>() / (n - 1.0)).sqrt())
}

/// The calibration's part: the true pixels triangulated through 400 rigs whose model
/// numbers and pose are drawn from their covariances; the spread of the points against
/// sqrt(diag(Cov_calibration)): within 15 % (400 draws: about 3.5 % sampling error).
#[test]
fn rig_calibration_covariance_matches_monte_carlo() {
    let family = DistortionModel::OpenCv;
    let file = stereo_rig::rig_file(family);
    let rig = Rig::from_file(file.clone(), Path::new(".")).unwrap();
    let (e_in, t_c) = ([130.0, 180.0], [31.0, 29.0]);
    let a = at(&rig, e_in, t_c);
    let world = placed(family);
    let e = [a.cameras()[0].e_com_ma(), a.cameras()[1].e_com_ma()];
    let w = [30.0, 10.0, 600.0];
    let pixels = [Some(world[0].project(w, e[0]).unwrap()), Some(world[1].project(w, e[1]).unwrap())];
    let predicted = a.triangulate(&pixels, 0.0, CalibrationPart::Include).unwrap();
    let from_cal = predicted.from_calibration.unwrap();
    assert_eq!(predicted.from_pixels, [[0.0; 3]; 3]);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut draw = |s: f64| -> f64 {
        let z: f64 = StandardNormal.sample(&mut rng);
        s * z
    };
    let samples: Vec<[f64; 3]> = (0..400)
        .map(|_| {
            let mut f = file.clone();
            for cam in &mut f.cameras {
                let cal = cam.calibration.as_mut().unwrap();
                let (m, layout) = (cal.model().unwrap(), cal.layout().unwrap());
                let std = cal.std.to_params(&layout).unwrap();
                let mut theta = to_params(&m);
                for (t, s) in theta.iter_mut().zip(std).take(layout.len()) {
                    *t += draw(s);
                }
                let drawn = Calibration::from_model(&from_params(&layout, &theta), cal.image_size, cal.e_com_range_ma);
                **cal = Calibration { thermal: cal.thermal.clone(), ..drawn };
            }
            let x = &mut f.extrinsics[0];
            let cov = x.covariance.unwrap();
            for i in 0..3 {
                x.rotation_rodrigues[i] += draw(cov[i][i].sqrt());
                x.translation_mm[i] += draw(cov[3 + i][3 + i].sqrt());
            }
            let r = Rig::from_file(f, Path::new(".")).unwrap();
            at(&r, e_in, t_c).triangulate(&pixels, 0.0, CalibrationPart::PixelOnly).unwrap().point_mm
        })
        .collect();
    let std = spread(&samples);
    for i in 0..3 {
        let predicted_std = from_cal[i][i].sqrt();
        let ratio = std[i] / predicted_std;
        assert!((ratio - 1.0).abs() < 0.15, "axis {i}: Monte Carlo {} predicted {predicted_std}", std[i]);
    }
    // And it adds to the pixels' part.
    let both = a.triangulate(&pixels, 0.2, CalibrationPart::Include).unwrap();
    let pixel_only = a.triangulate(&pixels, 0.2, CalibrationPart::PixelOnly).unwrap();
    for i in 0..3 {
        let sum = pixel_only.covariance_mm2[i][i] + both.from_calibration.unwrap()[i][i];
        assert!((both.covariance_mm2[i][i] - sum).abs() < 1e-9 * sum);
    }
}

/// Both families: a world point's rectified pixels (P R X in each camera) lie on one row
/// to 1e-6 px, Q turns (x, y, disparity) back into the point, and each map, at its
/// rectified pixel, is the model's projection of the point (the map's entries at the grid
/// pixels are that construction to f32 rounding).
#[test]
fn rig_rectification_rows_agree_and_maps_are_the_model() {
    for family in [DistortionModel::OpenCv, DistortionModel::Paper] {
        let rig = rig(family);
        let a = at(&rig, [120.0, 190.0], [30.0, 34.0]);
        let rect = a.stereo_rectify(0, 1, -1.0).unwrap();
        let x = &rect.rectification;
        let poses = [a.poses()[0], a.poses()[1]];
        let (rots, ps) = ([x.r1, x.r2], [x.p1, x.p2]);
        let maps = a.stereo_rectify_maps(&rect).unwrap();
        for w in [[20.0, -30.0, 650.0], [90.0, 60.0, 1200.0], [-30.0, 5.0, 450.0]] {
            let mut rectified = [[0.0; 2]; 2];
            for c in 0..2 {
                let xc = poses[c].apply(w);
                let q = mat_vec(&rots[c], xc);
                let p = ps[c];
                rectified[c] = [p[0][0] * q[0] / q[2] + p[0][2], p[1][1] * q[1] / q[2] + p[1][2]];
                // The map's construction at that (non-grid) rectified pixel: the model's
                // pixel of the point.
                let ray = mat_t_vec(
                    &rots[c],
                    [(rectified[c][0] - p[0][2]) / p[0][0], (rectified[c][1] - p[1][2]) / p[1][1], 1.0],
                );
                let cam = &a.cameras()[c];
                let via_map = project_camera_point(ray, cam.intrinsics(), cam.distortion()).unwrap();
                let observed = cam.project_camera_point(xc).unwrap();
                assert!((via_map[0] - observed[0]).abs() < 1e-6 && (via_map[1] - observed[1]).abs() < 1e-6);
                // The stored maps at the nearest grid pixel against the construction there.
                let (gx, gy) = (rectified[c][0].round(), rectified[c][1].round());
                let m = if c == 0 { &maps.left } else { &maps.right };
                let i = gy as usize * m.width_px() + gx as usize;
                let ray = mat_t_vec(&rots[c], [(gx - p[0][2]) / p[0][0], (gy - p[1][2]) / p[1][1], 1.0]);
                let want = project_camera_point(ray, cam.intrinsics(), cam.distortion()).unwrap();
                assert!((m.map_x()[i] as f64 - want[0]).abs() < 1e-3 && (m.map_y()[i] as f64 - want[1]).abs() < 1e-3);
            }
            assert!((rectified[0][1] - rectified[1][1]).abs() < 1e-6, "{family:?} {w:?}: {rectified:?}");
            // Q (u, v, d, 1) is the point in the rectified left frame.
            let d = rectified[0][0] - rectified[1][0];
            let h: [f64; 4] = std::array::from_fn(|r| {
                let v = [rectified[0][0], rectified[0][1], d, 1.0];
                (0..4).map(|k| x.q[r][k] * v[k]).sum()
            });
            let back = [h[0] / h[3], h[1] / h[3], h[2] / h[3]];
            let truth = mat_vec(&x.r1, w);
            assert!((0..3).all(|i| (back[i] - truth[i]).abs() < 1e-6 * truth[2]), "{back:?} {truth:?}");
        }
        assert!((rect.baseline_mm() - 100.0).abs() < 1.0, "{}", rect.baseline_mm());
    }
}

/// Every bad input: one line naming what is wrong.
#[test]
fn rig_refuses_bad_inputs_in_one_line() {
    let rig = rig(DistortionModel::OpenCv);
    let one_line = |e: etl_formats::Error, needle: &str| {
        let m = e.to_string();
        assert!(m.contains(needle), "{m}");
        assert_eq!(m.lines().count(), 1, "{m}");
    };
    let s = [RigSetting::of(150.0), RigSetting::of(150.0)];
    one_line(rig.at(&s[..1], &[30.0, 30.0], Trust::Refuse).unwrap_err(), "settings: the rig has 2 cameras, got 1");
    one_line(rig.at(&s, &[30.0], Trust::Refuse).unwrap_err(), "temperatures_c: the rig has 2 cameras, got 1");
    let dpt: RigSetting = "12.5dpt".parse().unwrap();
    one_line(
        rig.at(&[s[0], dpt], &[30.0, 30.0], Trust::Refuse).unwrap_err(),
        "camera 1 (right): invalid input: a focal_power setting (dpt) for a calibration whose setting is current (mA)",
    );
    assert!("150mA".parse::<RigSetting>().is_ok() && "fast".parse::<RigSetting>().is_err());
    one_line(rig.at(&s, &[30.0, 80.0], Trust::Refuse).unwrap_err(), "camera 1 (right): temperature_c = 80");
    let a = at(&rig, [150.0, 150.0], [30.0, 30.0]);
    one_line(a.stereo_rectify(0, 2, -1.0).unwrap_err(), "pair: camera 2 is not one of the rig's cameras 0..1");
    one_line(a.stereo_rectify(1, 1, -1.0).unwrap_err(), "cannot be paired with itself");
    one_line(a.stereo_rectify(0, 1, 0.5).unwrap_err(), "alpha 0.5: only -1");
    one_line(
        a.triangulate(&[Some([900.0, 700.0])], 0.1, CalibrationPart::PixelOnly).unwrap_err(),
        "pixels: the rig has 2 cameras, got 1",
    );
    one_line(
        a.triangulate(&[Some([900.0, 700.0]), None], 0.1, CalibrationPart::PixelOnly).unwrap_err(),
        "too few cameras seeing the point",
    );
    // A calibration without its covariance: refused unless pixel-only.
    let mut f = stereo_rig::rig_file(DistortionModel::OpenCv);
    f.cameras[1].calibration.as_mut().unwrap().covariance = None;
    let bare = at(&Rig::from_file(f, Path::new(".")).unwrap(), [150.0, 150.0], [30.0, 30.0]);
    let px = [Some([1000.0, 700.0]), Some([900.0, 720.0])];
    one_line(bare.triangulate(&px, 0.1, CalibrationPart::Include).unwrap_err(), "camera 1 (right): pass pixel-only");
    assert!(bare.triangulate(&px, 0.1, CalibrationPart::PixelOnly).is_ok());
    let mut f = stereo_rig::rig_file(DistortionModel::OpenCv);
    f.extrinsics[0].covariance = None;
    let bare = at(&Rig::from_file(f, Path::new(".")).unwrap(), [150.0, 150.0], [30.0, 30.0]);
    one_line(
        bare.triangulate(&px, 0.1, CalibrationPart::Include).unwrap_err(),
        "its pose in the rig file has no covariance",
    );
}

/// `fixtures/rig/` is the opencv-family synthetic rig, calibrations by path (the CLI's and
/// Python's tests read it); `ETLCAL_WRITE_FIXTURES=1` writes it.
#[test]
fn rig_fixture_is_the_synthetic_rig() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/rig");
    let mut file = stereo_rig::rig_file(DistortionModel::OpenCv);
    let names = ["left.json", "right.json"];
    let cals: Vec<Calibration> = file.cameras.iter_mut().map(|c| *c.calibration.take().unwrap()).collect();
    for (c, name) in file.cameras.iter_mut().zip(names) {
        c.calibration_path = Some(name.into());
    }
    if std::env::var_os("ETLCAL_WRITE_FIXTURES").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        for (cal, name) in cals.iter().zip(names) {
            cal.save(&dir.join(name)).unwrap();
        }
        file.save(&dir.join("rig.json")).unwrap();
    }
    let loaded = RigFile::load(&dir.join("rig.json")).unwrap();
    assert_eq!(loaded.file, file);
    assert_eq!(loaded.calibrations, cals);
}
