//! A setting whose zero is not the lens off (a focal power: the lens off is near 8 dpt,
//! not at 0 dpt): the linear start solves kf0 with the focal polynomial ([`Kf0::Solved`])
//! instead of taking it from A0, and the bundle adjustment recovers the truth exactly on
//! noise-free data.

use super::common;

use common::{as_views, paper_rig, NO_NOISE};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise_model_with, BundleAdjustOptions, Kf0, Layout, View, ViewScratch,
    A0,
};
use etl_core::model::{CameraModel, FocalPoly, OpenCvFlags};

/// The setting s = E / 10 + 8 (dpt-like: 16 at 80 mA, 30.5 at 225 mA), so E = 10 (s - 8).
fn setting_of(e_ma: f64) -> f64 {
    e_ma / 10.0 + 8.0
}

/// `poly` in E as a polynomial in s: sum_i k_i (10 (s - 8))^i expanded by the binomial
/// theorem.
fn in_setting(poly: &FocalPoly) -> FocalPoly {
    let k = poly.coefficients();
    let mut out = vec![0.0; k.len()];
    for (i, &ki) in k.iter().enumerate() {
        // (10 s - 80)^i = sum_j C(i, j) (10 s)^j (-80)^(i - j)
        for j in 0..=i {
            let c = (1..=j).fold(1.0, |c, m| c * (i + 1 - m) as f64 / m as f64);
            out[j] += ki * c * 10f64.powi(j as i32) * (-80f64).powi((i - j) as i32);
        }
    }
    FocalPoly::new(&out).unwrap()
}

#[test]
fn kf0_solved_with_the_polynomial_recovers_a_setting_with_an_offset_zero() {
    let truth_e = CameraModel::paper_rig();
    let truth = CameraModel { kf_x: in_setting(&truth_e.kf_x), kf_y: in_setting(&truth_e.kf_y), ..truth_e };
    for e in [80.0, 150.0, 225.0] {
        let (a, b) = (truth.focal_lengths(setting_of(e)).0, truth_e.focal_lengths(e).0);
        assert!((a / b - 1.0).abs() < 1e-12, "the truth in s: {a} against {b}");
    }
    let (pts, e, a0) = paper_rig(&NO_NOISE, 0);
    let s: Vec<f64> = e.iter().map(|&e| setting_of(e)).collect();
    let views: Vec<View> = as_views(&pts, &s);
    // A0's kf0 is fx at E = 0, that is at s = 8, not at s = 0: it must not be used.
    let a0 = A0 { kf0x: f64::NAN, kf0y: f64::NAN, ..a0 };
    let init = initialise_model_with(&views, &a0, Kf0::Solved, Layout::PAPER, OpenCvFlags::NONE).unwrap();
    let start = (init.focal_lengths(setting_of(150.0)).0 / truth.focal_lengths(setting_of(150.0)).0 - 1.0).abs();
    // The start with kf0 known (the paper's, on the same views in E) is as far off: the
    // linear steps ignore the distortion. Solving kf0 costs the start little.
    let kf0 = Kf0::Known([truth_e.kf_x.coefficients()[0], truth_e.kf_y.coefficients()[0]]);
    let (pts_e, a0_e) = (as_views(&pts, &e), paper_rig(&NO_NOISE, 0).2);
    let known = initialise_model_with(&pts_e, &a0_e, kf0, Layout::PAPER, OpenCvFlags::NONE).unwrap();
    let known_start = (known.focal_lengths(150.0).0 / truth_e.focal_lengths(150.0).0 - 1.0).abs();
    assert!(start < 1.2 * known_start && start < 0.1, "start {start:e} against {known_start:e} with kf0 known");
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let r = bundle_adjust(&views, &init, &BundleAdjustOptions::default(), &mut scratch).unwrap();
    for e in [80.0, 115.0, 150.0, 190.0, 225.0] {
        let err = (r.model.focal_lengths(setting_of(e)).0 / truth.focal_lengths(setting_of(e)).0 - 1.0).abs();
        assert!(err < 1e-9, "fx at {e} mA off by {err:e}");
    }
    assert!(r.rms_px < 1e-6, "rms {} px", r.rms_px);
}

/// Solving kf0 needs one more distinct setting than the cubic with A0, and a setting that
/// is not zero everywhere.
#[test]
fn kf0_solved_needs_four_settings_for_the_cubic() {
    let (pts, e, a0) = paper_rig(&NO_NOISE, 0);
    let few: Vec<f64> = (0..e.len()).map(|i| [16.0, 20.0, 24.0][i % 3]).collect();
    let views = as_views(&pts, &few);
    let err = initialise_model_with(&views, &a0, Kf0::Solved, Layout::PAPER, OpenCvFlags::NONE).unwrap_err();
    assert!(err.to_string().contains("distinct currents"), "{err}");
}
