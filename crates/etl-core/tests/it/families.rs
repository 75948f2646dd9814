//! Issue 16: the distortion families and the focal degree, against ground truth.
//!
//! The opencv family on the strong-distortion camera (`CameraModel::strong_distortion_rig`:
//! k1 about -0.3, k2 about 0.15 in normalised units, varying with focus): undistortion over
//! the whole image, bundle adjustment of noise-free data to the truth, a few noisy trials
//! against the Cramer-Rao bound, OpenCV's flags, PnP. Focal polynomials of degree 1, 2, 4
//! and 5 recovered from noise-free data of a truth of that degree.

use super::common;

use common::{as_views, paper_rig_of, NO_NOISE};
use etl_core::calib::crlb::crlb_covariance;
use etl_core::calib::jacobian::to_params;
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise_model, BundleAdjustOptions, BundleAdjustReport, Layout, Point,
    View, ViewScratch, A0,
};
use etl_core::model::{CameraModel, DistortionA, DistortionModel, FocalPoly, OpenCvFlags};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The strong rig's image, px.
const IMAGE: [f64; 2] = [1936.0, 1458.0];
/// Currents and stage positions of the strong rig's ETL views: the board moves towards
/// the camera as the lens focuses nearer (depth about 280 mm at 80 mA to 130 mm at 225 mA).
const STRONG_VIEWS: [(f64, f64); 10] = [
    (80.0, 80.0),
    (95.0, 62.0),
    (110.0, 45.0),
    (125.0, 30.0),
    (140.0, 15.0),
    (155.0, 0.0),
    (170.0, -15.0),
    (185.0, -30.0),
    (205.0, -50.0),
    (225.0, -70.0),
];

/// The corners of a large board (12 mm squares, 25 x 20 inner corners around the optical
/// axis) at stage position `z_w` that `model` images inside the image at `e_ma`, with
/// Gaussian pixel noise `sigma_px`.
fn board_view(model: &CameraModel, z_w: f64, e_ma: f64, sigma_px: f64, rng: &mut ChaCha8Rng) -> Vec<Point> {
    let noise = Normal::new(0.0, sigma_px.max(1e-300)).unwrap();
    let mut pts = vec![];
    for j in 0..20 {
        for i in 0..25 {
            let w = [-84.0 + 12.0 * i as f64, -69.0 + 12.0 * j as f64, z_w];
            let Ok(p) = model.project(w, e_ma) else { continue };
            if p[0] < 0.0 || p[1] < 0.0 || p[0] > IMAGE[0] - 1.0 || p[1] > IMAGE[1] - 1.0 {
                continue;
            }
            let n = if sigma_px > 0.0 { [noise.sample(rng), noise.sample(rng)] } else { [0.0; 2] };
            pts.push(Point { world_mm: w, pixel: [p[0] + n[0], p[1] + n[1]] });
        }
    }
    pts
}

/// The strong rig's views of `truth` (its 10 currents and stage positions).
fn strong_views(truth: &CameraModel, sigma_px: f64, seed: u64) -> (Vec<Vec<Point>>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pts = STRONG_VIEWS.iter().map(|&(e, z)| board_view(truth, z, e, sigma_px, &mut rng)).collect();
    (pts, STRONG_VIEWS.iter().map(|v| v.0).collect())
}

/// The exact lens-off intrinsics of `truth` (A0 as a perfect Zhang would give it).
fn exact_a0(truth: &CameraModel) -> A0 {
    let [u0, v0] = truth.principal_point;
    A0 { kf0x: truth.kf_x.coefficients()[0], kf0y: truth.kf_y.coefficients()[0], u0, v0 }
}

/// Initialises `layout` from `a0` and bundle-adjusts (the paper's estimator), holding
/// what OpenCV's `flags` hold. The views have pixel noise only (exact stage positions and
/// currents), so the covariance accounts for that alone.
fn calibrate(views: &[View], a0: &A0, layout: Layout, flags: OpenCvFlags) -> BundleAdjustReport {
    let init = initialise_model(views, a0, layout, flags).unwrap();
    let hold = layout.opencv_mask(flags).unwrap();
    let options = BundleAdjustOptions { hold, input_noise: None, ..BundleAdjustOptions::default() };
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    bundle_adjust(views, &init, &options, &mut scratch).unwrap()
}

/// The largest relative difference of the curves a user feels: fx(E), fy(E) and every
/// distortion coefficient (relative to the largest |coefficient| of the family, so that
/// the small tangential terms are judged on the scale of the distortion) over 80..225
/// mA, and the principal point relative to the focal length.
fn curve_error(est: &CameraModel, truth: &CameraModel) -> f64 {
    let mut worst = 0.0f64;
    for k in 0..=29 {
        let e = 80.0 + 5.0 * k as f64;
        let (a, b) = (est.focal_lengths(e), truth.focal_lengths(e));
        worst = worst.max(((a.0 - b.0) / b.0).abs()).max(((a.1 - b.1) / b.1).abs());
        let (da, db) = (est.distortion(e).unwrap(), truth.distortion(e).unwrap());
        let scale = db.coefficients().iter().fold(0.0f64, |m, c| m.max(c.abs()));
        for (x, y) in da.coefficients().iter().zip(db.coefficients()) {
            worst = worst.max((x - y).abs() / scale);
        }
    }
    let f = truth.focal_lengths(150.0).0;
    for k in 0..2 {
        worst = worst.max((est.principal_point[k] - truth.principal_point[k]).abs() / f);
    }
    worst
}

#[test]
fn undistort_round_trips_over_the_whole_image_of_the_strong_lens() {
    let cam = CameraModel::strong_distortion_rig();
    for e in [80.0, 150.0, 225.0] {
        let k = cam.intrinsics(e).unwrap();
        let d = cam.distortion(e).unwrap();
        assert_eq!(d.model(), DistortionModel::OpenCv);
        let (mut worst, mut largest) = (0.0f64, 0.0f64);
        // Every 16 px over the whole image, the corners included: observed -> ideal ->
        // observed again.
        for iy in 0..=91 {
            for ix in 0..=121 {
                let px = [(ix as f64 * 16.0).min(IMAGE[0] - 1.0), (iy as f64 * 16.0).min(IMAGE[1] - 1.0)];
                let ideal = cam.undistort(px, e).unwrap();
                let [ud, vd] = d.distort(ideal[0] - k.u0, ideal[1] - k.v0);
                worst = worst.max((ud + k.u0 - px[0]).abs()).max((vd + k.v0 - px[1]).abs());
                largest = largest.max((ideal[0] - px[0]).hypot(ideal[1] - px[1]));
            }
        }
        eprintln!("E = {e}: round trip {worst:e} px, largest distortion {largest:.1} px");
        assert!(worst < 1e-8, "E = {e}: worst round trip {worst} px");
        // The lens is strong: the image corners move by hundreds of pixels.
        assert!(largest > 200.0, "E = {e}: largest distortion {largest} px");
    }
}

#[test]
fn noise_free_opencv_family_is_recovered_to_the_truth() {
    let truth = CameraModel::strong_distortion_rig();
    let (pts, e) = strong_views(&truth, 0.0, 1);
    let views = as_views(&pts, &e);
    assert!(pts.iter().all(|p| p.len() >= 100), "{:?}", pts.iter().map(Vec::len).collect::<Vec<_>>());
    let r = calibrate(&views, &exact_a0(&truth), truth.layout(), OpenCvFlags::NONE);
    assert_eq!(r.model.layout(), truth.layout());
    assert!(r.rms_px < 1e-7, "rms {}", r.rms_px);
    let err = curve_error(&r.model, &truth);
    eprintln!("noise-free opencv: {} iterations, rms {:e} px, curves {err:e}", r.iterations, r.rms_px);
    assert!(err < 1e-9, "largest relative error of the curves {err:e}");
    // Every number that is not 0 in the truth, to 1e-6 relative (the a_i of one
    // coefficient are strongly correlated across the narrow w range).
    let (x, t) = (to_params(&r.model), to_params(&truth));
    for i in 0..truth.layout().len() {
        if t[i] != 0.0 {
            assert!(((x[i] - t[i]) / t[i]).abs() < 1e-6, "{}: {} vs {}", truth.layout().name(i), x[i], t[i]);
        }
    }
}

/// Pixel noise only: the spread of a few trials' errors, each in units of its Cramer-Rao
/// standard deviation, has mean square about 1 (an efficient, unbiased estimator). The
/// 300-trial efficiency study per number is `etlcal study crlb`'s.
#[test]
fn noisy_opencv_family_errors_match_the_cramer_rao_bound() {
    let truth = CameraModel::strong_distortion_rig();
    let layout = truth.layout();
    let sigma = 0.2;
    let (pts0, e) = strong_views(&truth, 0.0, 0);
    let bound = crlb_covariance(&as_views(&pts0, &e), &truth, sigma).unwrap();
    let t = to_params(&truth);
    let trials = 12;
    let (mut sum_z2, mut n) = (0.0, 0usize);
    for seed in 0..trials {
        // A0 as a perfect Zhang would give it: the bound is of all numbers free, so the
        // errors of kf0 and (u0, v0) only come from this data.
        let (pts, e) = strong_views(&truth, sigma, 100 + seed);
        let r = calibrate(&as_views(&pts, &e), &exact_a0(&truth), layout, OpenCvFlags::NONE);
        let x = to_params(&r.model);
        for i in 0..layout.len() {
            let z = (x[i] - t[i]) / bound[i][i].sqrt();
            sum_z2 += z * z;
            n += 1;
        }
        // The solver's own standard deviations agree with the bound at the truth.
        for i in 0..layout.len() {
            let ratio = r.std[i] / bound[i][i].sqrt();
            assert!((ratio - 1.0).abs() < 0.1, "seed {seed} {}: std / bound = {ratio}", layout.name(i));
        }
    }
    let mean_z2 = sum_z2 / n as f64;
    eprintln!("{trials} trials, {n} errors: mean squared error in CRLB units {mean_z2:.3}");
    // 12 trials x 31 numbers (correlated within a trial): mean z^2 within [0.6, 1.6].
    assert!((0.6..=1.6).contains(&mean_z2), "mean squared error in CRLB units {mean_z2}");
}

#[test]
fn opencv_flags_hold_k3_and_the_tangential_terms_at_zero() {
    let mut truth = CameraModel::strong_distortion_rig();
    // A lens without k3 and decentering: what the flags assume.
    let a = truth.distortion_a.as_slice();
    let mut held = [0.0; 15];
    held[..6].copy_from_slice(&a[..6]);
    truth.distortion_a = DistortionA::opencv(held);
    let (pts, e) = strong_views(&truth, 0.1, 7);
    let views = as_views(&pts, &e);
    let layout = truth.layout();
    let flags = OpenCvFlags { fix_k3: true, zero_tangent: true };
    let r = calibrate(&views, &exact_a0(&truth), layout, flags);
    let mask = layout.opencv_mask(flags).unwrap();
    assert_eq!(mask.count(), 9);
    let x = to_params(&r.model);
    for i in mask.indices() {
        assert!(x[i].abs() < 1e-12 * layout.len() as f64, "{} = {} is held at 0", layout.name(i), x[i]);
        assert!(r.std[i] < 1e-6 * r.std[layout.distortion_triple(0).at(2)], "{}: std {}", layout.name(i), r.std[i]);
    }
    // k3, p1, p2 of the result are 0 at every current; k1, k2 are the truth's within noise.
    for e in [80.0, 150.0, 225.0] {
        let c = r.model.distortion(e).unwrap();
        let c = c.coefficients();
        assert!(c[2].abs() < 1e-12 && c[3].abs() < 1e-12 && c[4].abs() < 1e-12, "{c:?}");
        let t = truth.distortion(e).unwrap();
        assert!((c[0] - t.coefficients()[0]).abs() < 1e-3, "k1 {} vs {}", c[0], t.coefficients()[0]);
    }
    // The flags belong to the opencv family.
    let paper = Layout::PAPER;
    assert!(initialise_model(&views, &exact_a0(&truth), paper, flags).is_err());
    assert!(paper.opencv_mask(OpenCvFlags { fix_k3: true, zero_tangent: false }).is_err());
}

/// The paper rig with focal polynomials of another degree: noise-free views recover them.
#[test]
fn focal_degrees_1_2_4_5_recover_a_truth_of_that_degree() {
    let kf: [(usize, [f64; 6]); 4] = [
        (1, [5200.0, -3.2, 0.0, 0.0, 0.0, 0.0]),
        (2, [5380.0, -6.0, 0.008, 0.0, 0.0, 0.0]),
        (4, [5380.0, -7.0, 0.02, -3e-5, 2e-8, 0.0]),
        (5, [5380.0, -7.0, 0.02, -3e-5, 4e-8, -5e-11]),
    ];
    for family in DistortionModel::ALL {
        for (d, c) in kf {
            let mut truth = if family == DistortionModel::Paper {
                CameraModel::paper_rig()
            } else {
                CameraModel::strong_distortion_rig()
            };
            // The strong rig's lens is four times shorter: its polynomial scaled so.
            let scale = truth.kf_x.coefficients()[0] / 5380.0;
            let cx: Vec<f64> = c[..=d].iter().map(|v| v * scale).collect();
            let mut cy = cx.clone();
            cy[0] += 10.0 * scale;
            truth.kf_x = FocalPoly::new(&cx).unwrap();
            truth.kf_y = FocalPoly::new(&cy).unwrap();
            let (pts, e) = if family == DistortionModel::Paper {
                let (pts, e, _) = paper_rig_of(&truth, &NO_NOISE, 0);
                (pts, e)
            } else {
                strong_views(&truth, 0.0, 3)
            };
            let views = as_views(&pts, &e);
            let layout = Layout::new(family, d).unwrap();
            let r = calibrate(&views, &exact_a0(&truth), layout, OpenCvFlags::NONE);
            assert_eq!(r.model.focal_degree(), d);
            let err = curve_error(&r.model, &truth);
            eprintln!("{family:?} degree {d}: curves {err:e}, {} iterations", r.iterations);
            assert!(err < 1e-8, "{family:?} degree {d}: largest relative error of the curves {err:e}");
            for (got, want) in r.model.kf_x.coefficients().iter().zip(&cx) {
                assert!(((got - want) / want).abs() < 1e-6, "{family:?} degree {d}: kf_x {got} vs {want}");
            }
        }
    }
}

/// PnP through the opencv family: a board's pose from its noise-free pixels, exactly.
#[test]
fn pnp_through_the_opencv_family_is_exact() {
    let cam = CameraModel::strong_distortion_rig();
    let board: Vec<[f64; 3]> = (0..99).map(|i| [15.0 * (i % 11) as f64, 15.0 * (i / 11) as f64, 0.0]).collect();
    for (e, z) in [(90.0, 60.0), (180.0, -30.0)] {
        let px: Vec<[f64; 2]> = board.iter().map(|b| cam.project([b[0] - 60.0, b[1] - 50.0, z], e).unwrap()).collect();
        let pose = etl_core::pnp::solve_pnp(&cam, e, &board, &px).unwrap();
        let t = cam.world_to_camera([-60.0, -50.0, z]);
        for k in 0..3 {
            assert!((pose.translation_mm[k] - t[k]).abs() < 1e-7, "E = {e}: {:?} vs {t:?}", pose.translation_mm);
        }
        assert!(pose.rms_px < 1e-8);
    }
}

/// The model serialises as the calibration file's fields: the paper's exactly as before
/// the families (what `etlcal simulate` writes as truth.json), the opencv family naming
/// itself.
#[test]
fn models_serialise_as_the_files_fields() {
    let paper = serde_json::to_string(&CameraModel::paper_rig()).unwrap();
    let before = serde_json::json!({
        "rotation_rodrigues": [0.2, 0.2, 0.2], "translation_mm": [-11.0, -4.0, 48.0],
        "kf_x": [5380.0, -7.0, 0.02, -3e-5], "kf_y": [5430.0, -7.0, 0.02, -3e-5], "principal_point": [900.0, 550.0],
        "distortion_a": [-0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6]
    });
    // The same text, keys in the same order (serde_json's map keeps insertion order only
    // with a feature: compare the text of the expected value re-serialised in field order).
    assert_eq!(serde_json::from_str::<serde_json::Value>(&paper).unwrap(), before);
    let keys: Vec<&str> = paper.split('"').skip(1).step_by(2).collect();
    assert_eq!(keys, ["rotation_rodrigues", "translation_mm", "kf_x", "kf_y", "principal_point", "distortion_a"]);
    let strong: serde_json::Value = serde_json::to_value(CameraModel::strong_distortion_rig()).unwrap();
    assert_eq!(strong["distortion_model"], "opencv");
    assert_eq!(strong["distortion_a"].as_array().unwrap().len(), 15);
    assert_eq!(strong["kf_x"].as_array().unwrap().len(), 4);
}
