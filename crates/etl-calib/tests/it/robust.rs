//! Robust calibration against gross corner outliers.

use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_calib::robust::OUTLIER_FLOOR_PX;
use etl_formats::observations::Observations;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, NoiseModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Replaces `k` distinct random corners of the ETL views by uniformly random pixels of
/// the image; returns their (view, point) indices.
fn corrupt(obs: &mut Observations, k: usize, seed: u64) -> Vec<(usize, usize)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let all: Vec<(usize, usize)> =
        obs.views.iter().enumerate().flat_map(|(v, w)| (0..w.points.len()).map(move |p| (v, p))).collect();
    let mut picked = vec![];
    while picked.len() < k {
        let c = all[rng.random_range(0..all.len())];
        if !picked.contains(&c) {
            picked.push(c);
        }
    }
    let [w, h] = obs.image_size;
    for &(v, p) in &picked {
        obs.views[v].points[p].pixel = [rng.random_range(0.0..w as f64), rng.random_range(0.0..h as f64)];
    }
    picked.sort_unstable();
    picked
}

/// The outlier sweep of the acceptance: k = 1..23 of the paper rig's 2311 corners replaced by
/// random pixels (one seed per k); every calibration succeeds, finds each replaced corner
/// that moved by more than twice the outlier floor (a random pixel can land near the true
/// one), reports no
/// clean corner, and keeps the principal point within 1 px of the clean result.
#[test]
fn outlier_sweep_succeeds_with_the_principal_point_within_1_px() {
    let th = ThermalRef::paper();
    let sim = paper_rig(&NoiseModel::PAPER, 7);
    let n: usize = sim.observations.views.iter().map(|v| v.points.len()).sum();
    assert_eq!(n, 2311);
    let clean = calibrate(&sim.observations, &sim.a0, Some(&th), &CalibrateOptions::default()).unwrap();
    assert!(clean.calibration.outliers.is_empty(), "{:?}", clean.calibration.outliers);
    assert!(clean.calibration.warnings.is_empty(), "{:?}", clean.calibration.warnings);
    let pp0 = clean.calibration.principal_point;
    let mut worst = 0.0f64;
    for k in 1..=23usize {
        let mut obs = sim.observations.clone();
        let bad = corrupt(&mut obs, k, 1000 + k as u64);
        let r = calibrate(&obs, &sim.a0, Some(&th), &CalibrateOptions::default())
            .unwrap_or_else(|e| panic!("k = {k}: {e}"));
        let pp = r.calibration.principal_point;
        let off = (pp[0] - pp0[0]).hypot(pp[1] - pp0[1]);
        worst = worst.max(off);
        let found: Vec<(usize, usize)> = r.calibration.outliers.iter().map(|o| (o.view, o.point)).collect();
        for &(v, p) in &bad {
            let moved = {
                let (a, b) = (obs.views[v].points[p].pixel, sim.observations.views[v].points[p].pixel);
                (a[0] - b[0]).hypot(a[1] - b[1])
            };
            assert!(
                moved < 2.0 * OUTLIER_FLOOR_PX || found.contains(&(v, p)),
                "k = {k}: corner ({v}, {p}) moved {moved} px, not found"
            );
        }
        assert!(found.iter().all(|c| bad.contains(c)), "k = {k}: clean corners reported: {found:?} vs {bad:?}");
        assert!(off < 1.0, "k = {k}: principal point {off} px from the clean result");
        assert!(r.calibration.warnings.iter().any(|w| w.contains("outliers")), "{:?}", r.calibration.warnings);
    }
    println!("worst principal point shift {worst:.4} px");
}

/// Permuted current labels (two views' currents swapped) calibrate, but with a warning
/// naming the current corrections, not silently.
#[test]
fn permuted_current_labels_warn() {
    let th = ThermalRef::paper();
    let sim = paper_rig(&NoiseModel::PAPER, 7);
    let mut obs = sim.observations.clone();
    let (a, b) = (obs.views[3].e_com_ma, obs.views[9].e_com_ma);
    obs.views[3].e_com_ma = b;
    obs.views[9].e_com_ma = a;
    let r = calibrate(&obs, &sim.a0, Some(&th), &CalibrateOptions::default()).unwrap();
    println!("rms {} warnings {:?}", r.calibration.rms_reprojection_px, r.calibration.warnings);
    assert!(r.calibration.warnings.iter().any(|w| w.contains("current correction")), "{:?}", r.calibration.warnings);
}

/// The homography screen on a view with a quarter of its corners replaced: exactly those
/// are set aside; too few points or mismatched counts set nothing aside.
#[test]
fn the_homography_screen_finds_a_quarter_of_a_view_wrong() {
    use etl_calib::robust::homography_inliers;
    let sim = paper_rig(&NoiseModel::PAPER, 3);
    let v = &sim.observations.views[7];
    let board: Vec<[f64; 2]> = v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect();
    let mut pixels: Vec<[f64; 2]> = v.points.iter().map(|p| p.pixel).collect();
    let bad: Vec<usize> = (0..pixels.len()).step_by(4).collect();
    for &i in &bad {
        pixels[i] = [pixels[i][0] + 40.0 + i as f64, pixels[i][1] - 25.0];
    }
    let inliers = homography_inliers(&board, &pixels);
    let out: Vec<usize> = (0..inliers.len()).filter(|&i| !inliers[i]).collect();
    assert_eq!(out, bad);
    assert!(homography_inliers(&board[..11], &pixels[..11]).iter().all(|&k| k));
    assert!(homography_inliers(&board, &pixels[1..]).iter().all(|&k| k));
}
