//! A simulated 2-camera rig rendered as images, detected ([`detect_rig`]) and calibrated
//! jointly: its extrinsics against the truth and against the calibration from the true
//! pixels of the same corners; the refusals of a missing image and of a camera whose
//! board is never found.

use std::path::Path;

use etl_calib::pipeline::dataset::default_detector;
use etl_calib::rig_calibration::{calibrate_rig, detect_rig, RigCalibration, RigCalibrationOptions};
use etl_core::model::CameraModel;
use etl_core::progress::NoProgress;
use etl_formats::rig::relative_pose;
use etl_formats::rig_dataset::RigDataset;
use etl_sim::multi_camera::images::{dataset_truths, render_multi_camera};
use etl_sim::multi_camera::{simulate_multi_camera, stage_position_mm, MultiCameraDesign, MultiCameraSimulation};
use etl_sim::render::{BitDepth, Image};
use etl_sim::rig::{charuco_frame, LENS_OFF_CHARUCO};
use etl_sim::simulate::images::ImageOptions;
use etl_sim::simulate::{lens_off_poses, NoiseModel};

/// `points` with every pixel replaced by its true one: the corner's projection by the
/// true camera (in the rendered dataset's frame) at the true stage position and current
/// of its view, lens-off corners by the true lens-off pose.
fn true_pixels(points: &RigDataset, sim: &MultiCameraSimulation, truths: &[CameraModel]) -> RigDataset {
    let mut out = points.clone();
    let designed = sim.true_dz_mm.len();
    for v in &mut out.views {
        let j = (0..designed).find(|&j| stage_position_mm(j, designed) == v.z_w_mm).unwrap();
        for s in &mut v.cameras {
            let e = s.e_com_ma.unwrap() + sim.true_de_ma[s.camera][j].unwrap();
            for p in s.points.as_mut().unwrap() {
                let q = truths[s.camera].project([p[2], p[3], v.z_w_mm + sim.true_dz_mm[j]], e).unwrap();
                (p[0], p[1]) = (q[0], q[1]);
            }
        }
    }
    for (i, v) in out.offstate_views.iter_mut().enumerate() {
        for s in &mut v.cameras {
            let pose = charuco_frame(&lens_off_poses(&sim.truths[s.camera])[i], LENS_OFF_CHARUCO.square_mm);
            for p in s.points.as_mut().unwrap() {
                let q = pose.project([p[2], p[3], 0.0], 0.0).unwrap();
                (p[0], p[1]) = (q[0], q[1]);
            }
        }
    }
    out
}

/// The pose (rotation, translation) and its standard deviations of camera 1 from camera 0.
fn pose_and_std(rig: &RigCalibration) -> ([f64; 6], [f64; 6]) {
    let e = &rig.extrinsics[0];
    let c = e.covariance.unwrap();
    let x = core::array::from_fn(|i| if i < 3 { e.rotation_rodrigues[i] } else { e.translation_mm[i - 3] });
    (x, core::array::from_fn(|i| c[i][i].sqrt()))
}

fn write_grey_png(path: &Path, [width, height]: [u32; 2]) {
    let image = Image { width, height, bit_depth: BitDepth::Eight, data: vec![128; (width * height) as usize] };
    image.save_png(path).unwrap();
}

#[test]
fn a_rendered_rig_is_calibrated_from_its_images() {
    let design = MultiCameraDesign { views: 5, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&design, &NoiseModel::PAPER, 4).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let rendered = render_multi_camera(&sim, dir.path(), &ImageOptions::default(), 4, &NoProgress).unwrap();
    let path = dir.path().join("rig_dataset.json");
    rendered.save(&path).unwrap();
    let loaded = RigDataset::load(&path).unwrap();
    let (points, summary) = detect_rig(&loaded, &path, &default_detector(), &NoProgress).unwrap();
    // Every image looked at; a view whose board is not found is dropped for its camera
    // only, and said.
    let looked: usize = summary.cameras.iter().map(|(_, s)| s.images).sum();
    assert_eq!(looked, loaded.images().count());
    for (k, (name, s)) in summary.cameras.iter().enumerate() {
        assert_eq!(name, &format!("cam{k}"));
        let kept = points.views.iter().flat_map(|v| &v.cameras).filter(|c| c.camera == k).count();
        assert_eq!(kept, s.views_detected, "{name}");
        assert_eq!(s.detected + s.skipped.len(), s.images, "{name}");
    }
    let options = RigCalibrationOptions::default();
    let from_images = calibrate_rig(&points, &options).unwrap();
    let truths = dataset_truths(&sim);
    let (om, t) = relative_pose(
        (truths[0].rotation_rodrigues, truths[0].translation_mm),
        (truths[1].rotation_rodrigues, truths[1].translation_mm),
    );
    let (x, std) = pose_and_std(&from_images);
    for i in 0..6 {
        let truth = if i < 3 { om[i] } else { t[i - 3] };
        assert!((x[i] - truth).abs() <= 3.0 * std[i], "pose[{i}]: {} vs truth {truth} (std {})", x[i], std[i]);
    }
    // The same corners at their true pixels: the stage and current errors are the same,
    // so the two calibrations differ by what the detector's pixel errors move. Both are
    // weighed by the detector's noise (the larger camera's RMS: true pixels have none to
    // estimate), whose propagated std bounds the difference.
    let sigma_px = from_images.cameras.iter().map(|c| c.rms_px).fold(0.0, f64::max);
    let mut weighed = options.clone();
    weighed.request.priors.sigma_px = Some(sigma_px);
    let from_truth = calibrate_rig(&true_pixels(&points, &sim, &truths), &weighed).unwrap();
    let (y, _) = pose_and_std(&from_truth);
    let (x, std) = pose_and_std(&calibrate_rig(&points, &weighed).unwrap());
    for i in 0..6 {
        assert!(
            (x[i] - y[i]).abs() <= 3.0 * std[i],
            "pose[{i}]: images {} vs true pixels {} (std {})",
            x[i],
            y[i],
            std[i]
        );
    }
    for c in &from_images.cameras {
        // The detector's noise: well under the points simulation's 0.2 px.
        assert!(c.rms_px > 0.0 && c.rms_px < 0.1, "{}: {}", c.name, c.rms_px);
    }

    // A camera whose board is never found is refused, named, in one line.
    let grey = dir.path().join("grey.png");
    write_grey_png(&grey, loaded.cameras[1].image_size);
    let mut blind = loaded.clone();
    for s in blind.views.iter_mut().flat_map(|v| &mut v.cameras).filter(|s| s.camera == 1) {
        s.image = Some(grey.clone());
    }
    let e = detect_rig(&blind, &path, &default_detector(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("camera 1 (cam1): ") && e.contains("the board was found in 0 of"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");

    // A missing image is named before any detection.
    let mut missing = loaded.clone();
    missing.views[1].cameras[0].image = Some("images/cam0/nowhere.png".into());
    let e = detect_rig(&missing, &path, &default_detector(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("images/cam0/nowhere.png") && e.lines().count() == 1, "{e}");
}
