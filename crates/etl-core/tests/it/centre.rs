//! The moving centre (Eq. C1-C3, `etl_core::model::centre`) in the bundle adjustment,
//! against ground truth: data from a model whose centre and principal point move with E,
//! solved with the moving-centre layout (the truth recovered) and with the fixed one (the
//! bias the paper's model takes on); data from a fixed centre solved with the moving
//! layout (no move found).

use super::common;

use common::{as_views, paper_rig_of, NO_NOISE};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise_model, BundleAdjustOptions, BundleAdjustReport, Layout, View,
    ViewScratch, A0,
};
use etl_core::model::{CameraModel, MovingCentre, OpenCvFlags};

/// A centre that moves by -1.0 mm between 80 and 225 mA, with a bend, and a principal
/// point that moves by 2.9 and -1.45 px over the range: an EL-10-30 behind a 16 mm lens
/// decentred by a few hundredths of a mm (docs/RESULTS.md, the traced rigs).
const CENTRE: MovingCentre = MovingCentre { dz_mm: [-0.012, 1.8e-5], principal_point_slope_px: [0.02, -0.01] };

/// The paper's A0 of `truth` (lens-off focal lengths and principal point), exact.
fn exact_a0(truth: &CameraModel) -> A0 {
    let [u0, v0] = truth.principal_point;
    A0 { kf0x: truth.kf_x.coefficients()[0], kf0y: truth.kf_y.coefficients()[0], u0, v0 }
}

fn calibrate(views: &[View], a0: &A0, layout: Layout) -> BundleAdjustReport {
    let init = initialise_model(views, a0, layout, OpenCvFlags::NONE).unwrap();
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    bundle_adjust(views, &init, &BundleAdjustOptions::default(), &mut scratch).unwrap()
}

/// The largest |fx_est(E) / fx(E) - 1| over 80..225 mA.
fn fx_error(est: &CameraModel, truth: &CameraModel) -> f64 {
    (0..=29)
        .map(|k| 80.0 + 5.0 * k as f64)
        .fold(0.0f64, |m, e| m.max((est.focal_lengths(e).0 / truth.focal_lengths(e).0 - 1.0).abs()))
}

#[test]
fn a_moving_centre_is_recovered_and_the_fixed_model_is_biased_by_it() {
    let truth = CameraModel { centre: Some(CENTRE), ..CameraModel::paper_rig() };
    let (pts, e, _) = paper_rig_of(&truth, &NO_NOISE, 0);
    let views = as_views(&pts, &e);
    let moving = calibrate(&views, &exact_a0(&truth), Layout::PAPER.with_moving_centre(true));
    let c = moving.model.centre.expect("a moving centre");
    for e_ma in [80.0, 150.0, 225.0] {
        let dz = c.dz_mm_at(e_ma) - CENTRE.dz_mm_at(e_ma);
        assert!(dz.abs() < 1e-6, "dz at {e_ma} mA off by {dz} mm");
        let [du, dv] = [0, 1].map(|k| moving.model.principal_point_at(e_ma)[k] - truth.principal_point_at(e_ma)[k]);
        assert!(du.abs() < 1e-6 && dv.abs() < 1e-6, "principal point at {e_ma} mA off by ({du}, {dv}) px");
    }
    assert!(fx_error(&moving.model, &truth) < 1e-9 && moving.rms_px < 1e-6, "rms {}", moving.rms_px);
    // The paper's fixed centre cannot follow: fx(E) takes on the move.
    let fixed = calibrate(&views, &exact_a0(&truth), Layout::PAPER);
    let bias = fx_error(&fixed.model, &truth);
    eprintln!("fixed centre on moving-centre data: fx bias {bias:e}, rms {} px", fixed.rms_px);
    assert!(bias > 1e-4 && fixed.rms_px > 1e-3, "bias {bias:e}, rms {}", fixed.rms_px);
}

#[test]
fn a_fixed_centre_is_found_not_to_move() {
    let truth = CameraModel::paper_rig();
    let (pts, e, a0) = paper_rig_of(&truth, &NO_NOISE, 0);
    let views = as_views(&pts, &e);
    let r = calibrate(&views, &a0, Layout::PAPER.with_moving_centre(true));
    let c = r.model.centre.expect("the moving layout");
    assert!(
        c.dz_mm_at(225.0).abs() < 1e-7 && c.principal_point_shift_px(225.0).iter().all(|d| d.abs() < 1e-7),
        "{c:?}"
    );
    assert!(fx_error(&r.model, &truth) < 1e-9);
    // The standard deviations of the move are those of an observable parameter.
    let l = r.model.layout();
    assert!((0..l.len()).all(|i| r.std[i].is_finite()));
}

#[test]
fn the_opencv_family_with_a_moving_centre() {
    let truth = CameraModel { centre: Some(CENTRE), ..CameraModel::paper_rig() };
    let mut t = truth;
    t.distortion_a = etl_core::model::DistortionA::zero(etl_core::model::DistortionModel::OpenCv);
    let (pts, e, _) = paper_rig_of(&t, &NO_NOISE, 0);
    let views = as_views(&pts, &e);
    let layout = Layout::new(etl_core::model::DistortionModel::OpenCv, 3).unwrap().with_moving_centre(true);
    let r = calibrate(&views, &exact_a0(&t), layout);
    let c = r.model.centre.unwrap();
    assert!((c.dz_mm_at(225.0) - CENTRE.dz_mm_at(225.0)).abs() < 1e-6, "{c:?}");
    assert!(fx_error(&r.model, &t) < 1e-8);
}

#[test]
fn a_moving_centre_serialises_as_the_files_centre() {
    let m = CameraModel { centre: Some(CENTRE), ..CameraModel::paper_rig() };
    let v = serde_json::to_value(m).unwrap();
    assert_eq!(v["centre"]["dz_mm"], serde_json::json!([0.0, -0.012, 1.8e-5]));
    assert_eq!(v["centre"]["principal_point_px"], serde_json::json!([[900.0, 0.02], [550.0, -0.01]]));
    assert!(serde_json::to_value(CameraModel::paper_rig()).unwrap().get("centre").is_none());
}
