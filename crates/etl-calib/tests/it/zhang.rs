//! Zhang's method on the simulated lens-off views of the paper rig (docs/METHOD.md: 10 views of an
//! 11 x 8 board with 4 mm squares, tilted up to ~25 degrees, at E = 0).

use super::common;

use etl_calib::pipeline::a0_from_offstate;
use etl_calib::zhang::{zhang, PlanarView};
use etl_core::model::CameraModel;
use etl_sim::simulate::{paper_rig, NoiseModel};

#[test]
fn noise_free_lens_off_views_give_the_exact_intrinsics() {
    let sim = paper_rig(&NoiseModel::NONE, 3);
    let z = a0_from_offstate(&sim.observations).unwrap();
    let t = CameraModel::paper_rig();
    let [k1, p1, p2, ..] = *t.distortion(0.0).unwrap().padded();
    let (kf0x, kf0y) = (t.kf_x.coefficients()[0], t.kf_y.coefficients()[0]);
    assert!((z.fx / kf0x - 1.0).abs() < 1e-8 && (z.fy / kf0y - 1.0).abs() < 1e-8, "{} {}", z.fx, z.fy);
    assert!((z.u0 - 900.0).abs() < 1e-6 && (z.v0 - 550.0).abs() < 1e-6);
    let [zk1, zp1, zp2, ..] = z.coefficients;
    assert!((zk1 / k1 - 1.0).abs() < 1e-6 && (zp1 / p1 - 1.0).abs() < 1e-6 && (zp2 / p2 - 1.0).abs() < 1e-6);
    assert!(z.rms_px < 1e-6);
}

#[test]
fn noisy_lens_off_views_meet_the_acceptance_levels() {
    // Issue 5 asks for fx, fy within 0.1 % and the principal point within 0.5 px. The focal
    // lengths meet it. The principal point cannot: at a 5400 px focal length it is nearly
    // confounded with the decentering terms p1, p2 estimated with it, and the Cramer-Rao
    // bound of this design (the formal std of the maximum-likelihood estimate) is about
    // 3 px in u0 and 2 px in v0; more tilt does not help (45 degrees over 20 views: 2.4 and
    // 1.7 px). Asserted: the bound exceeds the target, and the errors are the bound's size
    // (within 4 sigma in every seed, RMS z-score near 1): the estimator is efficient, the
    // target is below what the data allow.
    let mut worst = [0.0f64; 2];
    let mut z2 = 0.0;
    for seed in 0..10 {
        let sim = paper_rig(&NoiseModel::PAPER, 200 + seed);
        let z = a0_from_offstate(&sim.observations).unwrap();
        let f = ((z.fx / 5380.0 - 1.0).abs()).max((z.fy / 5430.0 - 1.0).abs());
        let pp = (z.u0 - 900.0).hypot(z.v0 - 550.0);
        worst = [worst[0].max(f), worst[1].max(pp)];
        assert!((z.rms_px - 0.2 * 2f64.sqrt()).abs() < 0.05, "rms {}", z.rms_px);
        assert!(z.std[2] > 0.5 && z.std[3] > 0.5, "bound {:?}", &z.std[2..4]);
        let (zu, zv) = ((z.u0 - 900.0) / z.std[2], (z.v0 - 550.0) / z.std[3]);
        assert!(zu.abs() < 4.0 && zv.abs() < 4.0, "z-scores {zu} {zv}");
        z2 += zu * zu + zv * zv;
    }
    let z_rms = (z2 / 20.0).sqrt();
    println!(
        "worst over 10 seeds: focal {:.4} %, principal point {:.3} px; RMS z-score {z_rms:.2}",
        100.0 * worst[0],
        worst[1]
    );
    assert!(worst[0] < 1e-3 && worst[1] < 8.0, "{worst:?}");
    assert!(z_rms > 0.5 && z_rms < 1.6, "RMS z-score {z_rms}");
}

#[test]
fn too_few_or_parallel_views_are_errors() {
    let sim = paper_rig(&NoiseModel::NONE, 3);
    let views: Vec<PlanarView> = sim
        .observations
        .offstate_views
        .iter()
        .map(|v| PlanarView {
            board_mm: v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect(),
            pixels: v.points.iter().map(|p| p.pixel).collect(),
        })
        .collect();
    let e = zhang(&views[..2], [1936, 1458]).unwrap_err().to_string();
    assert!(e.contains("at least 3 views"), "{e}");
    // The same view three times: no information on the intrinsics.
    let same = vec![views[1].clone(), views[1].clone(), views[1].clone()];
    assert!(zhang(&same, [1936, 1458]).is_err());
    let mut short = views.clone();
    short[0].pixels.truncate(2);
    short[0].board_mm.truncate(2);
    assert!(zhang(&short, [1936, 1458]).unwrap_err().to_string().contains("at least 4 points"));
}

/// Issue 5: on a real image set (fixtures/zhang, 25 views of a 9x6 board), the same
/// numbers as OpenCV's calibrateCamera with k2 = k3 = 0 to 0.5 %. The reference values are
/// OpenCV 5.0.0's on its own corners (findChessboardCorners + cornerSubPix 11x11) and on
/// etlcal's corners, from `benches/zhang_opencv.py`: with the same corners the two
/// calibrations agree to 3e-5 (the models differ only in k1's normalisation when
/// fx != fy); end to end the difference is the detectors' (etlcal's RMS is lower).
#[test]
fn real_image_set_agrees_with_opencv() {
    let images = common::fixture_jpegs("zhang");
    assert_eq!(images.len(), 25);
    let board = etl_formats::Board::checkerboard([9, 6], 1.0).unwrap();
    let found = etl_calib::pipeline::detect_views(&images, &board, &etl_core::progress::NoProgress).unwrap();
    let (views, size) = (found.views, found.image_size);
    assert_eq!((views.len(), size), (25, [640, 512]));
    let z = zhang(&views, size).unwrap();
    // OpenCV end to end, and OpenCV on etlcal's corners.
    let opencv = [520.5071683788558, 520.9965012276165, 314.7340743388873, 248.61725959522127];
    let same_corners = [520.20, 520.64, 313.58, 249.18];
    let got = [z.fx, z.fy, z.u0, z.v0];
    for k in 0..4 {
        assert!((got[k] / opencv[k] - 1.0).abs() < 0.005, "{k}: {} vs OpenCV {}", got[k], opencv[k]);
        assert!(
            (got[k] - same_corners[k]).abs() < 0.02,
            "{k}: {} vs OpenCV on the same corners {}",
            got[k],
            same_corners[k]
        );
    }
    assert!(z.rms_px < 0.16, "rms {} (OpenCV's own corners: 0.160 px)", z.rms_px);
}

/// Issue 19: gross outliers in the lens-off views (corners replaced by pixels far off)
/// are set aside by the robust homographies and reported, and A0 is what the clean views
/// without those corners give (to 1e-6 relative).
#[test]
fn lens_off_outliers_are_reported_and_leave_a0_unmoved() {
    let sim = paper_rig(&NoiseModel::PAPER, 5);
    let clean = a0_from_offstate(&sim.observations).unwrap();
    assert!(clean.outliers.is_empty(), "{:?}", clean.outliers);
    let bad = [(0usize, 3usize), (0, 50), (4, 17), (9, 70)];
    let (mut obs, mut without) = (sim.observations.clone(), sim.observations.clone());
    for (k, &(v, p)) in bad.iter().enumerate() {
        let px = &mut obs.offstate_views[v].points[p].pixel;
        *px = [px[0] + 150.0 + 40.0 * k as f64, px[1] - 90.0];
    }
    for &(v, p) in bad.iter().rev() {
        without.offstate_views[v].points.remove(p);
    }
    let z = a0_from_offstate(&obs).unwrap();
    let found: Vec<(usize, usize)> = z.outliers.iter().map(|o| (o.view, o.point)).collect();
    assert_eq!(found, bad);
    assert!(z.outliers.iter().all(|o| o.residual_px > 100.0), "{:?}", z.outliers);
    let want = a0_from_offstate(&without).unwrap();
    for (got, want, name) in
        [(z.fx, want.fx, "fx"), (z.fy, want.fy, "fy"), (z.u0, want.u0, "u0"), (z.v0, want.v0, "v0")]
    {
        assert!((got / want - 1.0).abs() < 1e-6, "{name}: {got} vs {want} without the outliers");
    }
    assert!((z.rms_px / want.rms_px - 1.0).abs() < 1e-6, "rms {} vs {}", z.rms_px, want.rms_px);
}

/// One seed's lens-off Zhang calibration against the truth: per test pixel and axis,
/// (re-projection - truth, predicted std) in mrcal's sense (the point held in the boards'
/// frames, mapped through the estimated poses: `ZhangResult::projection_std`).
fn zhang_projection_trial(seed: u64, tests: &[([f64; 2], Option<f64>)]) -> Vec<(f64, f64)> {
    use etl_core::model::rotation::{mat_t_vec, mat_vec, rodrigues_to_matrix};
    let sim = paper_rig(&NoiseModel::PAPER, seed);
    let z = a0_from_offstate(&sim.observations).unwrap();
    let mut truth = CameraModel::paper_rig();
    truth.rotation_rodrigues = [0.0; 3];
    truth.translation_mm = [0.0; 3];
    let poses = etl_sim::simulate::lens_off_poses(&CameraModel::paper_rig());
    assert_eq!(z.poses.len(), poses.len());
    let est = z.camera();
    let mut out = vec![];
    for &(q, distance) in tests {
        let ray = truth.ray(q, 0.0).unwrap();
        let p = distance.map_or(ray.direction, |s| ray.at(s));
        // Through each view's board frame: the true pose in, the estimated pose out.
        let mut mean = [0.0; 3];
        for (t, e) in poses.iter().zip(&z.poses) {
            let (rt, tt) = (rodrigues_to_matrix(t.rotation_rodrigues), t.translation_mm);
            let rel = if distance.is_some() { [p[0] - tt[0], p[1] - tt[1], p[2] - tt[2]] } else { p };
            let board = mat_t_vec(&rt, rel);
            let back = mat_vec(&rodrigues_to_matrix(e.0), board);
            for c in 0..3 {
                mean[c] += (back[c] + if distance.is_some() { e.1[c] } else { 0.0 }) / poses.len() as f64;
            }
        }
        let got = est.project(mean, 0.0).unwrap();
        let s = z.projection_std(q, distance).unwrap();
        for axis in 0..2 {
            out.push((got[axis] - q[axis], s.std_px[axis]));
        }
    }
    out
}

/// `ZhangResult::projection_std` is honest on simulated monofocal sets with a known
/// camera (the paper rig's 10 lens-off views, 0.2 px and 1 um corner noise, 300 seeds): at
/// the centre, the corners and an edge of the image, at the views' distance and at
/// infinity, the spread of the re-projection over its median predicted std is within
/// 0.8-1.25 and the one-sigma intervals cover the truth 68 % +- 5 % of the time (pooled).
#[test]
fn zhangs_projection_std_matches_the_monte_carlo_spread() {
    use rayon::prelude::*;
    let [w, h] = [CameraModel::PAPER_IMAGE_SIZE[0] as f64, CameraModel::PAPER_IMAGE_SIZE[1] as f64];
    let pixels = [[w / 2.0, h / 2.0], [40.0, 40.0], [w - 40.0, h - 40.0], [40.0, h - 40.0], [w - 40.0, h / 2.0]];
    let tests: Vec<([f64; 2], Option<f64>)> = pixels.iter().flat_map(|&q| [(q, Some(125.0)), (q, None)]).collect();
    let runs: Vec<Vec<(f64, f64)>> =
        (0..300u64).into_par_iter().map(|s| zhang_projection_trial(700 + s, &tests)).collect();
    let (mut inside, mut n) = (0usize, 0usize);
    for k in 0..runs[0].len() {
        let errs: Vec<f64> = runs.iter().map(|t| t[k].0).collect();
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        let spread = (errs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (errs.len() - 1) as f64).sqrt();
        let mut stds: Vec<f64> = runs.iter().map(|t| t[k].1).collect();
        stds.sort_by(f64::total_cmp);
        let ratio = spread / stds[stds.len() / 2];
        let (q, d) = tests[k / 2];
        eprintln!(
            "pixel {q:?} at {d:?} mm, axis {}: spread {spread:.4} px, std {:.4} px, ratio {ratio:.3}",
            k % 2,
            stds[stds.len() / 2]
        );
        assert!((0.8..=1.25).contains(&ratio), "pixel {q:?} at {d:?}: spread / std {ratio:.3}");
        inside += runs.iter().filter(|t| t[k].0.abs() <= t[k].1).count();
        n += runs.len();
    }
    let cover = inside as f64 / n as f64;
    eprintln!("coverage {cover:.3}");
    assert!((cover - 0.6827).abs() <= 0.05, "coverage {cover:.3}");
}
