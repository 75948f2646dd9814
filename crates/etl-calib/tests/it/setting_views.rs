//! The setting views in the bundle adjustment (`--setting-views joint`) against ground
//! truth: a paper rig whose projection centre moves (etl_sim with setting views through a
//! moving-centre truth). With the stage views alone fx(E) and dz(E) trade; with the
//! tilted setting views in the joint solve dz1, dz2, u1, v1 and fx(E) come back within
//! their reported standard deviations.

use etl_calib::pipeline::{calibrate, CalibrateOptions, CalibrationResult, SettingViews};
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::Estimator;
use etl_core::model::{CameraModel, MovingCentre};
use etl_formats::ThermalRef;
use etl_sim::simulate::{add_setting_views_of, simulate_rig, NoiseModel, RigDesign, SettingRig, Simulation};

/// The paper rig with a centre that moves 1.6 mm over 80..225 mA and a principal point
/// that drifts 2.9 and -1.5 px.
fn moving_truth() -> CameraModel {
    let mut m = CameraModel::paper_rig();
    m.centre = Some(MovingCentre { dz_mm: [0.015, -1.2e-5], principal_point_slope_px: [0.02, -0.01] });
    m
}

/// The rig's stage views and, at 7 currents, 4 tilted setting views each.
fn simulation(noise: &NoiseModel, seed: u64) -> Simulation {
    let truth = moving_truth();
    let mut sim = simulate_rig(&RigDesign { truth, ..RigDesign::paper() }, noise, seed);
    let rig = SettingRig { views_per_setting: 8, aperture_mm: 1.0, ..SettingRig::default() };
    add_setting_views_of(&mut sim.observations, &truth, &rig, noise, seed);
    sim
}

fn options(setting_views: SettingViews, estimator: Estimator, hold_a0: bool) -> CalibrateOptions {
    CalibrateOptions {
        layout: Layout::PAPER.with_moving_centre(true),
        setting_views,
        estimator,
        hold_a0,
        ..CalibrateOptions::default()
    }
}

fn run(sim: &Simulation, options: &CalibrateOptions) -> CalibrationResult {
    calibrate(&sim.observations, &sim.a0, Some(&ThermalRef::paper()), options).unwrap()
}

/// The centre's move dz(225) - dz(80), mm, and its gradient in the layout's numbers.
fn centre_move(m: &CameraModel) -> (f64, [f64; MAX_PARAMS]) {
    let c = m.centre.unwrap();
    let (lo, hi) = (80.0, 225.0);
    let dz = m.layout().centre_dz();
    let mut g = [0.0; MAX_PARAMS];
    g[dz.at(0)] = hi - lo;
    g[dz.at(1)] = hi * hi - lo * lo;
    (c.dz_mm_at(hi) - c.dz_mm_at(lo), g)
}

fn variance(c: &[[f64; MAX_PARAMS]; MAX_PARAMS], g: &[f64; MAX_PARAMS]) -> f64 {
    (0..MAX_PARAMS).map(|i| (0..MAX_PARAMS).map(|j| g[i] * c[i][j] * g[j]).sum::<f64>()).sum()
}

/// Error / standard deviation of the centre's move, u1, v1, and fx at three currents.
fn z_scores(r: &CalibrationResult, truth: &CameraModel) -> Vec<(&'static str, f64, f64)> {
    let m = &r.report.model;
    let cov = &r.report.covariance;
    let layout = m.layout();
    let (mv, g) = centre_move(m);
    let (mv_true, _) = centre_move(truth);
    let mut out = vec![("move_mm", mv - mv_true, variance(cov, &g).sqrt())];
    let cp = layout.centre_principal_point();
    let (c, ct) = (m.centre.unwrap(), truth.centre.unwrap());
    for k in 0..2 {
        let name = ["u1", "v1"][k];
        let e = c.principal_point_slope_px[k] - ct.principal_point_slope_px[k];
        out.push((name, e, cov[cp.at(k)][cp.at(k)].sqrt()));
    }
    for (name, e) in [("fx(80)", 80.0_f64), ("fx(150)", 150.0), ("fx(225)", 225.0)] {
        let mut g = [0.0; MAX_PARAMS];
        let kf = layout.kf_x();
        for i in 0..kf.len {
            g[kf.at(i)] = e.powi(i as i32);
        }
        out.push((name, m.focal_lengths(e).0 - truth.focal_lengths(e).0, variance(cov, &g).sqrt()));
    }
    out
}

#[test]
fn joint_setting_views_recover_a_moving_centre_where_the_stage_views_cannot() {
    let sim = simulation(&NoiseModel::PAPER, 7);
    let truth = sim.truth;
    for estimator in [Estimator::EIV_PAPER, Estimator::Paper] {
        let joint = z_scores(&run(&sim, &options(SettingViews::Joint, estimator, false)), &truth);
        let stage = z_scores(&run(&sim, &options(SettingViews::Ignored, estimator, false)), &truth);
        for (&(name, err, std), &(_, _, stage_std)) in joint.iter().zip(&stage) {
            assert!(err.abs() < 4.0 * std, "{estimator:?} {name}: error {err} against std {std}");
            assert!(std < stage_std, "{estimator:?} {name}: std {std}, stage views alone {stage_std}");
        }
        // The move and fx: the stage views alone are further off (their fx(E) traded for
        // dz(E)); the joint solve's error is a fraction of theirs.
        for k in [0, 4] {
            let (name, err, _) = joint[k];
            assert!(err.abs() < 0.5 * stage[k].1.abs(), "{estimator:?} {name}: {err} against {}", stage[k].1);
        }
    }
}

/// The reported covariance against a small Monte Carlo: the spread of the move and of
/// fx(150) over seeds against the mean reported standard deviation (errors-in-variables,
/// whose priors are those of the simulation's noise).
#[test]
fn the_joint_covariance_matches_a_small_monte_carlo() {
    let seeds = 0..12;
    let mut rows = vec![];
    for seed in seeds {
        let sim = simulation(&NoiseModel::PAPER, 100 + seed);
        rows.push(z_scores(&run(&sim, &options(SettingViews::Joint, Estimator::EIV_PAPER, false)), &sim.truth));
    }
    for k in [0, 1, 2, 4] {
        let n = rows.len() as f64;
        let errors: Vec<f64> = rows.iter().map(|r| r[k].1).collect();
        let mean = errors.iter().sum::<f64>() / n;
        let spread = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let reported = (rows.iter().map(|r| r[k].2.powi(2)).sum::<f64>() / n).sqrt();
        // 12 seeds: the spread's own relative standard error is about 1 / sqrt(22) = 21 %.
        let ratio = spread / reported;
        assert!((0.5..1.7).contains(&ratio), "{}: spread {spread}, reported {reported}", rows[0][k].0);
        assert!(mean.abs() < 4.0 * reported / n.sqrt(), "{}: bias {mean} against {reported}", rows[0][k].0);
    }
}

/// Every other choice goes with the joint solve: a fixed centre, A0 held, the opencv
/// family, both estimators; fx(E) comes back within its reported standard deviations.
#[test]
fn the_joint_solve_takes_a_fixed_centre_a0_held_and_the_opencv_family() {
    use etl_core::model::DistortionModel;
    let sim = simulation(&NoiseModel::PAPER, 3);
    let opencv = Layout::new(DistortionModel::OpenCv, 3).unwrap();
    for (layout, estimator, hold_a0) in [
        (Layout::PAPER, Estimator::EIV_PAPER, true),
        (opencv.with_moving_centre(true), Estimator::Paper, true),
        (opencv, Estimator::EIV_PAPER, false),
    ] {
        let o = CalibrateOptions { layout, ..options(SettingViews::Joint, estimator, hold_a0) };
        let r = run(&sim, &o);
        assert_eq!(r.report.model.layout(), layout);
        let held = r.report.std[layout.u0()];
        assert!(!hold_a0 || held < 1e-3, "{layout:?}: u0 held, std {held}");
        let fx = r.report.model.focal_lengths(150.0).0;
        // A fixed centre fitted to a moving one: fx(E) absorbs the move (0.2 % of
        // fx at most here); the moving centre's within its standard deviation.
        let tol = if layout.moving_centre() { 4.0 * r.report.std[layout.kf_x().at(0)].max(2.0) } else { 0.01 * fx };
        assert!((fx - sim.truth.focal_lengths(150.0).0).abs() < tol, "{layout:?} {estimator:?}: fx {fx}");
    }
}

/// Refused: the joint solve without setting views; a setting view with fewer than 4
/// points, named.
#[test]
fn the_joint_solve_refuses_missing_and_too_small_setting_views() {
    let mut sim = simulation(&NoiseModel::PAPER, 5);
    let o = options(SettingViews::Joint, Estimator::EIV_PAPER, false);
    sim.observations.setting_views[3].points.truncate(3);
    let err = calibrate(&sim.observations, &sim.a0, Some(&ThermalRef::paper()), &o).unwrap_err().to_string();
    assert!(err.contains("setting view 3 has 3 points"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    sim.observations.setting_views.clear();
    let err = calibrate(&sim.observations, &sim.a0, Some(&ThermalRef::paper()), &o).unwrap_err().to_string();
    assert!(err.contains("needs setting_views"), "{err}");
}

/// The calibration records each setting view the joint solve took: noise-free, every
/// board pose it recorded reprojects its view's points to 1e-6 px through the calibrated
/// model, its current correction is zero, and the JSON round trip keeps them; a
/// calibration without the option records none.
#[test]
fn the_calibration_records_the_setting_views_poses() {
    let sim = simulation(&NoiseModel::NONE, 2);
    let joint = run(&sim, &options(SettingViews::Joint, Estimator::EIV_PAPER, false));
    let c = &joint.calibration;
    assert_eq!(c.setting_views.len(), sim.observations.setting_views.len());
    let model = joint.report.model;
    for (s, v) in c.setting_views.iter().zip(&sim.observations.setting_views) {
        assert_eq!((s.points, s.e_com_ma), (v.points.len(), v.e_com_ma.unwrap()));
        assert!(s.rms_px < 1e-6 && s.de_ma.abs() < 1e-6, "{s:?}");
        let posed = CameraModel { rotation_rodrigues: s.rotation_rodrigues, translation_mm: s.translation_mm, ..model };
        for p in &v.points {
            let q = posed.project(p.world_mm, s.e_com_ma + s.de_ma).unwrap();
            assert!((q[0] - p.pixel[0]).hypot(q[1] - p.pixel[1]) < 1e-6, "{q:?} against {:?}", p.pixel);
        }
    }
    let text = serde_json::to_string(c).unwrap();
    let back: etl_formats::calibration::Calibration = serde_json::from_str(&text).unwrap();
    assert_eq!(back.setting_views, c.setting_views);
    let ignored = run(&sim, &options(SettingViews::Ignored, Estimator::EIV_PAPER, false));
    assert!(ignored.calibration.setting_views.is_empty());
    assert!(!serde_json::to_string(&ignored.calibration).unwrap().contains("\"setting_views\""));
}
