//! The calibration solvers on the paper rig (docs/METHOD.md): noise-free recovery, the
//! paper's noise model with the plain and the errors-in-variables bundle adjustment, and
//! bad inputs.

use super::common;

use common::{as_views, paper_rig, Noise, NO_NOISE, PAPER_NOISE};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise, rac::rac, BundleAdjustOptions, Estimator, Point, ViewScratch, A0,
};
use etl_core::model::CameraModel;
use etl_core::Error;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Max relative error of fx(E) and fy(E) over 80..225 mA.
fn curve_error(est: &CameraModel) -> (f64, f64) {
    let truth = CameraModel::paper_rig();
    let (mut ex, mut ey) = (0.0f64, 0.0f64);
    for k in 0..=145 {
        let e = 80.0 + k as f64;
        let (fx, fy) = truth.focal_lengths(e);
        let (gx, gy) = est.focal_lengths(e);
        ex = ex.max(((gx - fx) / fx).abs());
        ey = ey.max(((gy - fy) / fy).abs());
    }
    (ex, ey)
}

fn calibrate(pts: &[Vec<Point>], e: &[f64], a0: &A0, estimator: Estimator) -> etl_core::calib::BundleAdjustReport {
    let views = as_views(pts, e);
    let init = initialise(&views, a0).unwrap();
    let opts = BundleAdjustOptions { estimator, ..BundleAdjustOptions::default() };
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    bundle_adjust(&views, &init, &opts, &mut scratch).unwrap()
}

#[test]
fn noise_free_paper_rig_is_recovered_exactly() {
    let (pts, e, a0) = paper_rig(&NO_NOISE, 1);
    assert_eq!(pts.iter().map(Vec::len).sum::<usize>(), 2311, "docs/METHOD.md: 2311 of 2520 corners remain");
    let r = calibrate(&pts, &e, &a0, Estimator::Paper);
    let truth = etl_core::calib::jacobian::to_params(&CameraModel::paper_rig());
    let got = etl_core::calib::jacobian::to_params(&r.model);
    for i in 0..25 {
        let tol = if i >= 16 { 1e-6 } else { 1e-8 };
        let rel = ((got[i] - truth[i]) / truth[i]).abs();
        assert!(rel < tol, "{}: {} vs {} (rel {rel:e})", etl_core::calib::Layout::PAPER.name(i), got[i], truth[i]);
    }
    assert!(r.iterations <= 10, "{} iterations", r.iterations);
    assert!(r.rms_px < 1e-6);
}

#[test]
fn errors_in_variables_beats_the_plain_estimator_under_the_paper_noise() {
    let trials = 12;
    let (mut plain, mut eiv) = (0.0, 0.0);
    let (mut pp_plain, mut pp_eiv) = (0.0, 0.0);
    for seed in 0..trials {
        let (pts, e, a0) = paper_rig(&PAPER_NOISE, 100 + seed);
        let rp = calibrate(&pts, &e, &a0, Estimator::Paper);
        let re = calibrate(&pts, &e, &a0, Estimator::EIV_PAPER);
        plain += curve_error(&rp.model).0;
        eiv += curve_error(&re.model).0;
        let pp = |m: &CameraModel| (m.principal_point[0] - 900.0).hypot(m.principal_point[1] - 550.0);
        pp_plain += pp(&rp.model);
        pp_eiv += pp(&re.model);
        assert!((rp.rms_px - 0.2 * 2f64.sqrt()).abs() < 0.2, "plain rms {}", rp.rms_px);
    }
    let n = trials as f64;
    println!(
        "mean max rel fx(E) error: plain {:.3} %, eiv {:.3} %; principal point: plain {:.2} px, eiv {:.2} px",
        100.0 * plain / n,
        100.0 * eiv / n,
        pp_plain / n,
        pp_eiv / n
    );
    assert!(eiv < 0.5 * plain, "EIV must lower the fx(E) curve error clearly: {eiv} vs {plain}");
}

#[test]
fn bad_inputs_name_the_problem() {
    let (pts, e, a0) = paper_rig(&NO_NOISE, 2);
    // Fewer than 3 distinct currents.
    let two: Vec<f64> = e.iter().enumerate().map(|(i, _)| if i % 2 == 0 { 80.0 } else { 90.0 }).collect();
    let err = initialise(&as_views(&pts, &two), &a0).unwrap_err();
    assert!(matches!(err, Error::TooFew { needed: 3, .. }), "{err}");
    // Fewer than 7 points for RAC.
    let few = [pts[0][..5].to_vec()];
    let err = rac(&as_views(&few, &e[..1]), [900.0, 550.0]).unwrap_err();
    assert!(matches!(err, Error::TooFew { needed: 7, got: 5, .. }), "{err}");
    // All points on one plane (a single stage position) where RAC needs depth.
    let flat = [pts[2].clone()];
    let err = rac(&as_views(&flat, &e[2..3]), [900.0, 550.0]).unwrap_err();
    assert!(matches!(err, Error::Degenerate { .. }), "{err}");
    // NaN in a point, and an empty view.
    let mut nan = pts.clone();
    nan[3][4].pixel[0] = f64::NAN;
    assert!(matches!(initialise(&as_views(&nan, &e), &a0).unwrap_err(), Error::NotFinite { .. }));
    let mut empty = pts.clone();
    empty[5].clear();
    assert!(matches!(initialise(&as_views(&empty, &e), &a0).unwrap_err(), Error::InvalidArgument { .. }));
    // NaN in A0.
    let bad_a0 = A0 { u0: f64::NAN, ..a0 };
    assert!(matches!(initialise(&as_views(&pts, &e), &bad_a0).unwrap_err(), Error::NotFinite { .. }));
}

/// Board points (board frame, Z = 0) visible at stage position `z` and current `e`, with
/// their pixels seen through the true rig (plus pixel noise `px`).
fn board_view(z: f64, e: f64, px: f64, rng: &mut ChaCha8Rng) -> (Vec<[f64; 3]>, Vec<[f64; 2]>) {
    let cam = CameraModel::paper_rig();
    let g = |s: f64, rng: &mut ChaCha8Rng| if s > 0.0 { Normal::new(0.0, s).unwrap().sample(rng) } else { 0.0 };
    let (mut b, mut p) = (vec![], vec![]);
    for j in 0..12 {
        for i in 0..14 {
            let w = [1.5 * i as f64, 1.5 * j as f64];
            let q = cam.project([w[0], w[1], z], e).unwrap();
            if (0.0..=1935.0).contains(&q[0]) && (0.0..=1457.0).contains(&q[1]) {
                b.push([w[0], w[1], 0.0]);
                p.push([q[0] + g(px, rng), q[1] + g(px, rng)]);
            }
        }
    }
    (b, p)
}

#[test]
fn pnp_noise_free_pose_is_exact() {
    let cam = CameraModel::paper_rig();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (z, e) in [(75.0, 80.0), (22.0, 150.0), (2.0, 225.0)] {
        let (b, p) = board_view(z, e, 0.0, &mut rng);
        let pose = etl_core::pnp::solve_pnp(&cam, e, &b, &p).unwrap();
        let t = cam.world_to_camera([0.0, 0.0, z]);
        for k in 0..3 {
            assert!((pose.translation_mm[k] - t[k]).abs() < 1e-9, "t{k}: {} vs {}", pose.translation_mm[k], t[k]);
            assert!((pose.rotation_rodrigues[k] - cam.rotation_rodrigues[k]).abs() < 1e-9);
        }
    }
}

#[test]
fn pnp_measures_a_2_mm_stage_move_under_the_paper_noise() {
    let trials = 6;
    let mut rows = vec![];
    for (z, e) in [(75.0, 80.0), (22.0, 150.0), (2.0, 225.0)] {
        let (mut err_plain, mut err_eiv) = (0.0, 0.0);
        for seed in 0..trials {
            let (pts, cur, a0) = paper_rig(&PAPER_NOISE, 300 + seed);
            let plain = calibrate(&pts, &cur, &a0, Estimator::Paper).model;
            let eiv = calibrate(&pts, &cur, &a0, Estimator::EIV_PAPER).model;
            let mut rng = ChaCha8Rng::seed_from_u64(900 + seed);
            let (b0, p0) = board_view(z, e, 0.2, &mut rng);
            let (b1, p1) = board_view(z + 2.0, e, 0.2, &mut rng);
            for (m, acc) in [(&plain, &mut err_plain), (&eiv, &mut err_eiv)] {
                let a = etl_core::pnp::solve_pnp(m, e, &b0, &p0).unwrap();
                let b = etl_core::pnp::solve_pnp(m, e, &b1, &p1).unwrap();
                let d = etl_core::pnp::displacement_mm(&a, &b);
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                *acc += 1000.0 * (len - 2.0).abs() / trials as f64;
            }
        }
        println!("2 mm move at {e} mA: mean |error| plain {err_plain:.1} um, eiv {err_eiv:.1} um");
        rows.push((e, err_plain, err_eiv));
    }
    // The paper measured < 20 um at ~250 mA with its method.
    let (_, _, eiv_225) = rows[2];
    assert!(eiv_225 < 20.0, "errors-in-variables PnP error at 225 mA: {eiv_225} um");
}

#[test]
fn pnp_bad_inputs() {
    let cam = CameraModel::paper_rig();
    let e = |r: Result<etl_core::pnp::BoardPose, Error>| r.unwrap_err();
    let b = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let p = [[900.0, 550.0], [950.0, 550.0], [900.0, 600.0]];
    assert!(matches!(e(etl_core::pnp::solve_pnp(&cam, 100.0, &b, &p)), Error::TooFew { needed: 4, .. }));
    let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
    let lp = [[900.0, 550.0], [950.0, 550.0], [1000.0, 550.0], [1050.0, 550.0]];
    assert!(matches!(e(etl_core::pnp::solve_pnp(&cam, 100.0, &line, &lp)), Error::Degenerate { .. }));
    let off = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let op = [[900.0, 550.0], [950.0, 550.0], [900.0, 600.0], [950.0, 600.0]];
    assert!(matches!(e(etl_core::pnp::solve_pnp(&cam, 100.0, &off, &op)), Error::InvalidArgument { .. }));
    assert!(matches!(e(etl_core::pnp::solve_pnp(&cam, f64::NAN, &line, &lp)), Error::NotFinite { .. }));
}

/// Statistical efficiency: with pixel noise of 0.2 px only, the Monte Carlo spread
/// of each of the 25 estimates matches its Cramer-Rao bound. With T trials the spread is
/// itself uncertain by about 1/sqrt(2T) (4 % at T = 300), so the 10 % tolerance is 2.5 of
/// those standard errors.
#[test]
fn bundle_adjustment_reaches_the_cramer_rao_bound() {
    let noise = Noise { px: 0.2, ..NO_NOISE };
    let trials = 300u64;
    let (pts0, e, a0) = paper_rig(&NO_NOISE, 0);
    let truth = CameraModel::paper_rig();
    let truth_x = etl_core::calib::jacobian::to_params(&truth);
    let cov = etl_core::calib::crlb::crlb_covariance(&as_views(&pts0, &e), &truth, 0.2).unwrap();
    let run = |seeds: std::ops::Range<u64>| -> Vec<[f64; etl_core::calib::params::MAX_PARAMS]> {
        seeds
            .map(|s| {
                let (pts, e, _) = paper_rig(&noise, 10_000 + s);
                etl_core::calib::jacobian::to_params(&calibrate(&pts, &e, &a0, Estimator::Paper).model)
            })
            .collect()
    };
    let est: Vec<[f64; etl_core::calib::params::MAX_PARAMS]> = std::thread::scope(|sc| {
        let h = sc.spawn(|| run(0..trials / 2));
        let mut b = run(trials / 2..trials);
        let mut a = h.join().unwrap();
        a.append(&mut b);
        a
    });
    let n = est.len() as f64;
    let mut worst = (0.0f64, "");
    for i in 0..25 {
        let mean = est.iter().map(|x| x[i]).sum::<f64>() / n;
        let sd = (est.iter().map(|x| (x[i] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let bound = cov[i][i].sqrt();
        let ratio = bound / sd;
        println!(
            "{:5} truth {:+.4e} crlb {:.3e} mc {:.3e} efficiency {:.3} bias/crlb {:+.2}",
            etl_core::calib::Layout::PAPER.name(i),
            truth_x[i],
            bound,
            sd,
            ratio,
            (mean - truth_x[i]) / bound
        );
        if (ratio - 1.0).abs() > worst.0 {
            worst = ((ratio - 1.0).abs(), etl_core::calib::Layout::PAPER.name(i));
        }
    }
    assert!(worst.0 < 0.10, "spread of {} differs from its CRLB by {:.1} %", worst.1, 100.0 * worst.0);
}

#[test]
fn hold_a0_keeps_the_lens_off_intrinsics() {
    let (pts, e, a0) = paper_rig(&PAPER_NOISE, 41);
    let views = as_views(&pts, &e);
    let init = initialise(&views, &a0).unwrap();
    let opts = BundleAdjustOptions { hold: init.layout().a0_mask(), ..BundleAdjustOptions::default() };
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let r = bundle_adjust(&views, &init, &opts, &mut scratch).unwrap();
    assert!(
        (r.model.kf_x.coefficients()[0] - a0.kf0x).abs() < 1e-4
            && (r.model.kf_y.coefficients()[0] - a0.kf0y).abs() < 1e-4
    );
    assert!((r.model.principal_point[0] - a0.u0).abs() < 1e-4 && (r.model.principal_point[1] - a0.v0).abs() < 1e-4);
    assert!(r.std[6] < 1e-3 && r.std[14] < 1e-3, "held numbers have ~0 spread: {} {}", r.std[6], r.std[14]);
    // The free numbers still moved from the linear start.
    assert!((r.model.kf_x.coefficients()[1] - init.kf_x.coefficients()[1]).abs() > 0.0);
}

#[test]
fn robust_loss_resists_bad_corners() {
    let (clean, e, a0) = paper_rig(&Noise { px: 0.2, ..NO_NOISE }, 42);
    let reference = calibrate(&clean, &e, &a0, Estimator::Paper).model;
    // The same data with 30 corners misdetected by 18 px.
    let mut pts = clean.clone();
    for k in 0..30 {
        let v = k % 15;
        let i = (k * 7) % pts[v].len();
        pts[v][i].pixel[0] += 15.0;
        pts[v][i].pixel[1] -= 10.0;
    }
    let views = as_views(&pts, &e);
    let init = initialise(&views, &a0).unwrap();
    let run = |robust| {
        let opts = BundleAdjustOptions { robust, ..BundleAdjustOptions::default() };
        let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
        bundle_adjust(&views, &init, &opts, &mut scratch).unwrap().model
    };
    // Distance of an estimate from the clean-data estimate: max relative fx(E) difference.
    let dist = |m: &CameraModel| {
        (0..=145)
            .map(|k| {
                let x = 80.0 + k as f64;
                ((m.focal_lengths(x).0 - reference.focal_lengths(x).0) / reference.focal_lengths(x).0).abs()
            })
            .fold(0.0f64, f64::max)
    };
    let plain = dist(&run(None));
    let huber = dist(&run(Some(etl_core::calib::RobustLoss::Huber { k_px: 1.0 })));
    let cauchy = dist(&run(Some(etl_core::calib::RobustLoss::Cauchy { k_px: 1.0 })));
    println!("fx(E) shift caused by 30 bad corners: least squares {plain:.2e}, Huber {huber:.2e}, Cauchy {cauchy:.2e}");
    assert!(huber < 0.2 * plain && cauchy < 0.2 * plain, "{plain} {huber} {cauchy}");
}
