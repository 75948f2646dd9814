//! The fixed-focus pair (`etl_calib::stereo`) against synthetic ground truth: two
//! distorted cameras 120 mm apart, turned 8 degrees towards each other, 12 synchronised
//! views of a 9 x 6 board of 30 mm squares. Noise-free: R, T and (joint) both cameras'
//! intrinsics come back to rounding; with pixel noise: within a few of their standard
//! deviations, which themselves cover the errors over repeated trials.

use etl_calib::stereo::{stereo_calibrate, StereoMode, StereoOptions, StereoPair, StereoResult};
use etl_calib::zhang::{PlanarView, ZhangOptions};
use etl_core::model::rotation::{mat_vec, matrix_to_rodrigues, rodrigues_to_matrix};
use etl_core::model::{CameraModel, DistortionA, DistortionModel, FocalPoly, OpenCvFlags};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const SIZE: [u32; 2] = [1280, 960];
/// The truth's relative pose: left frame to right frame.
const OM: [f64; 3] = [0.01, -0.14, 0.005];
const T_MM: [f64; 3] = [-120.0, 1.5, 4.0];
const OPENCV: ZhangOptions = ZhangOptions { model: DistortionModel::OpenCv, flags: OpenCvFlags::NONE };
const PAPER: ZhangOptions = ZhangOptions { model: DistortionModel::Paper, flags: OpenCvFlags::NONE };

/// A camera of the family of `options` at a pose: intrinsics [fx, fy, u0, v0] and the
/// family's coefficients (each the constant term of its Eq. 18 quadratic).
fn camera(model: DistortionModel, k: [f64; 4], coefficients: &[f64], om: [f64; 3], t: [f64; 3]) -> CameraModel {
    let mut a = DistortionA::zero(model);
    for (c, &v) in coefficients.iter().enumerate() {
        a.as_mut_slice()[3 * c + 2] = v;
    }
    CameraModel {
        rotation_rodrigues: om,
        translation_mm: t,
        kf_x: FocalPoly::cubic([k[0], 0.0, 0.0, 0.0]),
        kf_y: FocalPoly::cubic([k[1], 0.0, 0.0, 0.0]),
        principal_point: [k[2], k[3]],
        distortion_a: a,
        centre: None,
    }
}

/// The two cameras' truth: intrinsics and coefficients of each.
struct Truth {
    model: DistortionModel,
    k: [[f64; 4]; 2],
    coefficients: [Vec<f64>; 2],
}

fn truth(model: DistortionModel) -> Truth {
    let coefficients = match model {
        DistortionModel::OpenCv => [vec![-0.21, 0.09, 4e-4, -3e-4, -0.01], vec![-0.18, 0.07, -2e-4, 5e-4, 0.0]],
        DistortionModel::Paper => [vec![-2.0e-8, 1e-6, -2e-6], vec![-1.6e-8, -1.5e-6, 1e-6]],
    };
    Truth { model, k: [[1010.0, 1005.0, 645.0, 478.0], [995.0, 992.0, 630.0, 486.0]], coefficients }
}

/// 12 views (board poses in the left camera), 550..700 mm away, tilted up to ~25 degrees.
fn board_poses() -> Vec<([f64; 3], [f64; 3])> {
    let centre = [120.0, 75.0, 0.0];
    (0..12)
        .map(|k| {
            let phi = k as f64 * std::f64::consts::TAU / 12.0;
            let tilt = [0.45, 0.3, 0.15][k % 3];
            let om = [tilt * phi.cos(), tilt * phi.sin(), 0.08 * (k as f64 - 5.5) / 5.5];
            let c = mat_vec(&rodrigues_to_matrix(om), centre);
            let aim = [60.0 + 110.0 * phi.sin(), 80.0 * phi.cos(), 550.0 + 30.0 * (k % 6) as f64];
            (om, [aim[0] - c[0], aim[1] - c[1], aim[2] - c[2]])
        })
        .collect()
}

/// The pose of a left-frame board pose in the right camera: (R R_j, R t_j + T).
fn in_right((om, t): ([f64; 3], [f64; 3])) -> ([f64; 3], [f64; 3]) {
    let (r, rj) = (rodrigues_to_matrix(OM), rodrigues_to_matrix(om));
    let rr: [[f64; 3]; 3] =
        core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| r[i][k] * rj[k][j]).sum()));
    let q = mat_vec(&r, t);
    (matrix_to_rodrigues(&rr), [q[0] + T_MM[0], q[1] + T_MM[1], q[2] + T_MM[2]])
}

/// One camera's view of the board at a pose, corners inside the image only, with noise.
fn view(cam: &CameraModel, noise: &mut dyn FnMut() -> f64) -> PlanarView {
    let mut v = PlanarView::default();
    for j in 0..6 {
        for i in 0..9 {
            let b = [30.0 * i as f64, 30.0 * j as f64];
            let p = cam.project([b[0], b[1], 0.0], 0.0).unwrap();
            if (0.0..SIZE[0] as f64 - 1.0).contains(&p[0]) && (0.0..SIZE[1] as f64 - 1.0).contains(&p[1]) {
                v.board_mm.push(b);
                v.pixels.push([p[0] + noise(), p[1] + noise()]);
            }
        }
    }
    v
}

/// The synchronised pairs of `truth` with `sigma_px` of pixel noise.
fn pairs(truth: &Truth, sigma_px: f64, seed: u64) -> Vec<StereoPair> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, sigma_px.max(1e-300)).unwrap();
    let mut noise = move || if sigma_px > 0.0 { normal.sample(&mut rng) } else { 0.0 };
    board_poses()
        .into_iter()
        .map(|pose| {
            let [pl, pr] = [pose, in_right(pose)];
            let cl = camera(truth.model, truth.k[0], &truth.coefficients[0], pl.0, pl.1);
            let cr = camera(truth.model, truth.k[1], &truth.coefficients[1], pr.0, pr.1);
            StereoPair { left: Some(view(&cl, &mut noise)), right: Some(view(&cr, &mut noise)) }
        })
        .collect()
}

fn calibrate(pairs: &[StereoPair], zhang: ZhangOptions, mode: StereoMode) -> StereoResult {
    stereo_calibrate(pairs, [SIZE, SIZE], &StereoOptions { zhang, mode }).unwrap()
}

/// The largest error of (om, T) against the truth: rad, mm.
fn rt_error(r: &StereoResult) -> (f64, f64) {
    let e = |a: &[f64; 3], b: &[f64; 3]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    (e(&r.rotation_rodrigues, &OM), e(&r.translation_mm, &T_MM))
}

/// Noise-free views: both modes and both families recover R, T to rounding, the joint
/// mode both cameras' intrinsics too; the board poses are the truth's.
#[test]
fn stereo_noise_free_recovers_the_truth() {
    for (zhang, model) in [(OPENCV, DistortionModel::OpenCv), (PAPER, DistortionModel::Paper)] {
        let t = truth(model);
        let p = pairs(&t, 0.0, 1);
        for mode in [StereoMode::FixedIntrinsics, StereoMode::Joint] {
            let r = calibrate(&p, zhang, mode);
            let (dom, dt) = rt_error(&r);
            eprintln!("{model:?} {mode:?}: om off by {dom:.1e} rad, T by {dt:.1e} mm");
            assert!(dom < 1e-10 && dt < 1e-7, "{model:?} {mode:?}: om off by {dom:e} rad, T by {dt:e} mm");
            assert!(r.rms_px < 1e-7, "{model:?} {mode:?}: rms {}", r.rms_px);
            assert_eq!((r.views_used(), r.pairs_used.len()), (12, 12));
            for (cam, k) in [(&r.left, t.k[0]), (&r.right, t.k[1])] {
                let got = [cam.fx, cam.fy, cam.u0, cam.v0];
                assert!(got.iter().zip(k).all(|(a, b)| (a - b).abs() < 1e-6), "{model:?} {mode:?}: {got:?} vs {k:?}");
            }
            let (om0, t0) = board_poses()[3];
            let (om, tj) = r.poses[3];
            assert!((0..3).all(|k| (om[k] - om0[k]).abs() < 1e-10 && (tj[k] - t0[k]).abs() < 1e-7));
            assert!((r.baseline_mm() - (120.0f64.powi(2) + 1.5f64.powi(2) + 16.0).sqrt()).abs() < 1e-7);
        }
    }
}

/// With 0.3 px of noise, R and T lie within 4 standard deviations of the truth in both
/// modes, and over 40 trials the standard deviations describe the errors: the mean squared
/// error in units of its standard deviation lies near 1 for each of the 6 numbers.
#[test]
fn stereo_noisy_errors_match_their_standard_deviations() {
    let t = truth(DistortionModel::OpenCv);
    for mode in [StereoMode::FixedIntrinsics, StereoMode::Joint] {
        let trials = 40;
        let mut z2 = [0.0; 6];
        for seed in 0..trials {
            let r = calibrate(&pairs(&t, 0.3, 100 + seed), OPENCV, mode);
            let (std, truth) = (r.std(), [OM[0], OM[1], OM[2], T_MM[0], T_MM[1], T_MM[2]]);
            let est = [r.rotation_rodrigues, r.translation_mm].concat();
            for k in 0..6 {
                let z = (est[k] - truth[k]) / std[k];
                assert!(z.abs() < 4.5, "{mode:?} seed {seed}: number {k} off by {z:.2} std");
                z2[k] += z * z / trials as f64;
            }
            assert!((r.rms_px - 0.3 * 2f64.sqrt()).abs() < 0.05, "{mode:?}: rms {}", r.rms_px);
        }
        eprintln!("{mode:?}: mean z^2 of (om, T) over {trials} trials {z2:.2?}");
        // Over 40 trials the mean of z^2 has a standard deviation of about sqrt(2/40) = 0.22.
        for (k, m) in z2.iter().enumerate() {
            assert!((0.45..1.8).contains(m), "{mode:?}: number {k}: mean z^2 {m:.2}");
        }
    }
}

/// A view the right camera missed: the left camera's intrinsics still use it, the pairs
/// do not; the result is unchanged in kind and still exact.
#[test]
fn stereo_view_missing_in_one_camera_is_left_out_of_the_pairs() {
    let t = truth(DistortionModel::OpenCv);
    let mut p = pairs(&t, 0.0, 1);
    p[4].right = None;
    p[9].left = None;
    for mode in [StereoMode::FixedIntrinsics, StereoMode::Joint] {
        let r = calibrate(&p, OPENCV, mode);
        assert_eq!(r.pairs_used, [0, 1, 2, 3, 5, 6, 7, 8, 10, 11]);
        let (dom, dt) = rt_error(&r);
        assert!(dom < 1e-10 && dt < 1e-7, "{mode:?}: {dom:e} {dt:e}");
        assert_eq!(r.per_view_rms_px.len(), 10);
        if mode == StereoMode::FixedIntrinsics {
            assert_eq!(r.left.views_used, 11);
            assert_eq!(r.left_pairs, [0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11]);
            assert_eq!(r.right_pairs, [0, 1, 2, 3, 5, 6, 7, 8, 9, 10, 11]);
        } else {
            assert_eq!(r.left.views_used, 10);
            assert_eq!(r.left_pairs, r.pairs_used);
        }
    }
}

/// Too few views in a camera, too few pairs for the joint mode, an OpenCV flag with the
/// paper family: one-line errors naming the input.
#[test]
fn stereo_refuses_too_few_views_and_pairs() {
    let t = truth(DistortionModel::OpenCv);
    let mut p = pairs(&t, 0.0, 1);
    for q in p.iter_mut().skip(2) {
        q.right = None;
    }
    let err = |p: &[StereoPair], zhang, mode| {
        stereo_calibrate(p, [SIZE, SIZE], &StereoOptions { zhang, mode }).unwrap_err().to_string()
    };
    let e = err(&p, OPENCV, StereoMode::FixedIntrinsics);
    assert_eq!(
        e,
        "invalid input: the right camera sees the board in 2 of 12 pairs; each camera needs at least 3 views"
    );
    // Three right views, two of them paired: enough with the intrinsics held, not joint.
    p[2].left = None;
    p[2].right = pairs(&t, 0.0, 1)[2].right.clone();
    let r = calibrate(&p, OPENCV, StereoMode::FixedIntrinsics);
    assert_eq!(r.pairs_used, [0, 1]);
    assert!(rt_error(&r).1 < 1e-7);
    let e = err(&p, OPENCV, StereoMode::Joint);
    assert_eq!(e, "invalid input: both cameras see the board in 2 of 12 pairs; the joint mode needs at least 3");
    let flags =
        ZhangOptions { model: DistortionModel::Paper, flags: OpenCvFlags { fix_k3: true, zero_tangent: false } };
    assert!(err(&pairs(&t, 0.0, 1), flags, StereoMode::Joint).contains("fix_k3"));
    assert!(!e.contains('\n'));
}

/// OpenCV's flags hold the same coefficients in both cameras in the joint mode: k3 stays
/// at 0 and the rest is recovered from views of a camera without k3.
#[test]
fn stereo_joint_honours_opencv_flags() {
    let mut t = truth(DistortionModel::OpenCv);
    t.coefficients[0][4] = 0.0;
    let p = pairs(&t, 0.0, 1);
    let fix_k3 =
        ZhangOptions { model: DistortionModel::OpenCv, flags: OpenCvFlags { fix_k3: true, zero_tangent: false } };
    let r = calibrate(&p, fix_k3, StereoMode::Joint);
    assert_eq!(r.left.coefficients[4], 0.0);
    assert_eq!(r.left.std[8], 0.0);
    assert!((r.left.coefficients[0] - t.coefficients[0][0]).abs() < 1e-9);
    // The right camera has a k3 the model cannot fit: R, T absorb a little of it.
    assert!(rt_error(&r).1 < 2.0, "{:?}", r.translation_mm);
}

/// Partial views (a ChArUco board seen in part): each camera keeps its own corners of a
/// pair, different from the other's, and the result is still exact.
#[test]
fn stereo_partial_views_use_each_cameras_own_corners() {
    let t = truth(DistortionModel::OpenCv);
    let mut p = pairs(&t, 0.0, 1);
    for (j, pair) in p.iter_mut().enumerate() {
        let right = pair.right.as_mut().unwrap();
        let keep: Vec<bool> = (0..right.pixels.len()).map(|i| (i + j) % 3 != 0).collect();
        let mut k = keep.iter();
        right.board_mm.retain(|_| *k.next().unwrap());
        let mut k = keep.iter();
        right.pixels.retain(|_| *k.next().unwrap());
        let left = pair.left.as_mut().unwrap();
        left.board_mm.truncate(40);
        left.pixels.truncate(40);
    }
    for mode in [StereoMode::FixedIntrinsics, StereoMode::Joint] {
        let r = calibrate(&p, OPENCV, mode);
        let (dom, dt) = rt_error(&r);
        assert!(dom < 1e-10 && dt < 1e-7, "{mode:?}: {dom:e} {dt:e}");
    }
}

/// A pair whose right view numbers the board from the opposite corner (a checkerboard
/// symmetric under a half turn, numbered differently in the two images) is refused, naming
/// the pair, instead of biasing R, T.
#[test]
fn stereo_refuses_a_pair_whose_board_is_numbered_differently() {
    let t = truth(DistortionModel::OpenCv);
    let mut p = pairs(&t, 0.0, 1);
    let right = p[5].right.as_mut().unwrap();
    // The board turned half round in its own plane: (x, y) -> (240 - x, 150 - y).
    for b in right.board_mm.iter_mut() {
        *b = [240.0 - b[0], 150.0 - b[1]];
    }
    let e = stereo_calibrate(&p, [SIZE, SIZE], &StereoOptions { zhang: OPENCV, mode: StereoMode::FixedIntrinsics })
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("invalid input: pair 5: the two cameras' board poses disagree by 180 degrees"), "{e}");
}
