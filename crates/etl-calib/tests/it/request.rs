//! The calibration and Zhang requests (etl_calib::request): each refusal names its option
//! and reads in the caller's words, the defaults are the paper's, and a run is the
//! pipeline's own result for the same options.

use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_calib::request::{
    CalibrationRequest, CentreChoice, DistortionChoice, EivPriors, EstimatorChoice, FocalDegreeChoice, KeySpelling,
    Method, Refusal, RequestOption, Spelling, StageSigma, ZhangRequest,
};
use etl_core::calib::{Estimator, RobustLoss};
use etl_core::model::DistortionModel;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, NoiseModel};

/// A front end's spelling as a test writes it: `<name>`, `<name>=word`, `<name>!`.
struct Brackets;

impl Spelling for Brackets {
    fn name(&self, option: RequestOption) -> String {
        format!("<{}>", option.key())
    }
    fn word(&self, word: &str) -> String {
        format!("'{word}'")
    }
    fn with_word(&self, option: RequestOption, word: &str) -> String {
        format!("<{}>='{word}'", option.key())
    }
    fn switched_on(&self, option: RequestOption) -> String {
        format!("<{}>!", option.key())
    }
}

#[test]
fn the_defaults_are_the_papers_model_and_errors_in_variables() {
    let r = CalibrationRequest::default();
    assert_eq!(r.method, Method::Proposed);
    assert_eq!(r.estimator(), Estimator::EIV_PAPER);
    assert_eq!((r.family(), r.degree()), (Some(DistortionModel::Paper), Some(3)));
    assert_eq!(r.options(), CalibrateOptions::default());
    // Priors given in either unit give the same estimator: 10 um is the paper's 0.010 mm.
    for sigma_z in [StageSigma::Um(10.0), StageSigma::Mm(0.010)] {
        let given = CalibrationRequest {
            priors: EivPriors { sigma_z: Some(sigma_z), sigma_e_ma: Some(0.4), sigma_p_dpt: None, sigma_px: None },
            ..CalibrationRequest::default()
        };
        assert_eq!(given.estimator(), Estimator::EIV_PAPER);
    }
    let px = CalibrationRequest {
        priors: EivPriors { sigma_px: Some(0.3), ..EivPriors::default() },
        ..CalibrationRequest::default()
    };
    assert_eq!(px.estimator(), Estimator::Eiv { sigma_z_mm: 0.010, sigma_e_ma: 0.4, sigma_px: Some(0.3) });
    let paper = CalibrationRequest { estimator: Some(EstimatorChoice::Paper), ..px };
    assert_eq!(paper.estimator(), Estimator::Paper);
    assert_eq!(ZhangRequest::default().options(), etl_calib::zhang::ZhangOptions::default());
}

#[test]
fn every_refusal_names_its_option_in_the_callers_words() {
    let base = CalibrationRequest::default();
    let per_setting = CalibrationRequest { method: Method::PerSetting, ..base.clone() };
    let priors = |p: EivPriors| CalibrationRequest { priors: p, ..base.clone() };
    let cases: Vec<(CalibrationRequest, RequestOption, &str)> = vec![
        (
            CalibrationRequest { hold_a0: true, ..per_setting.clone() },
            RequestOption::HoldA0,
            "<method>='per-setting' takes no <a0>, <estimator>, <hold_a0> or <robust>: the baseline",
        ),
        (
            CalibrationRequest { estimator: Some(EstimatorChoice::Eiv), ..per_setting.clone() },
            RequestOption::Estimator,
            "takes no <a0>, <estimator>",
        ),
        (
            CalibrationRequest { focal_degree: Some(FocalDegreeChoice::Degree(3)), ..per_setting.clone() },
            RequestOption::FocalDegree,
            "<method>='per-setting' takes no <focal_degree>: the baseline fits the paper's model",
        ),
        (
            CalibrationRequest { zero_tangent: true, ..per_setting },
            RequestOption::ZeroTangent,
            "takes no <zero_tangent>",
        ),
        (
            CalibrationRequest { fix_k3: true, ..base.clone() },
            RequestOption::FixK3,
            "<fix_k3>! is an OpenCV flag: it needs <distortion>='opencv' or 'auto' (the paper's distortion",
        ),
        (
            CalibrationRequest {
                zero_tangent: true,
                distortion: Some(DistortionChoice::Family(DistortionModel::Paper)),
                ..base.clone()
            },
            RequestOption::ZeroTangent,
            "<zero_tangent>! is an OpenCV flag",
        ),
        (
            CalibrationRequest { focal_degree: Some(FocalDegreeChoice::Degree(6)), ..base.clone() },
            RequestOption::FocalDegree,
            "<focal_degree> must be 1..5 or 'auto', got 6",
        ),
        (
            priors(EivPriors { sigma_z: Some(StageSigma::Um(-1.0)), ..EivPriors::default() }),
            RequestOption::SigmaZUm,
            "<sigma_z_um> must be positive and finite",
        ),
        (
            priors(EivPriors { sigma_z: Some(StageSigma::Mm(f64::INFINITY)), ..EivPriors::default() }),
            RequestOption::SigmaZMm,
            "<sigma_z_mm> must be positive and finite",
        ),
        (priors(EivPriors { sigma_e_ma: Some(0.0), ..EivPriors::default() }), RequestOption::SigmaEMa, "<sigma_e_ma>"),
        (priors(EivPriors { sigma_px: Some(f64::NAN), ..EivPriors::default() }), RequestOption::SigmaPx, "<sigma_px>"),
        // Beyond any rig's noise: its square would overflow (the bound was 0 at 1e155 px).
        (
            priors(EivPriors { sigma_px: Some(1e155), ..EivPriors::default() }),
            RequestOption::SigmaPx,
            "<sigma_px> must be positive and finite, at most 100 px",
        ),
        (
            priors(EivPriors { sigma_z: Some(StageSigma::Um(10_001.0)), ..EivPriors::default() }),
            RequestOption::SigmaZUm,
            "<sigma_z_um> must be positive and finite, at most 10000 um",
        ),
        (
            priors(EivPriors { sigma_e_ma: Some(51.0), ..EivPriors::default() }),
            RequestOption::SigmaEMa,
            "at most 50 mA",
        ),
        (
            CalibrationRequest { robust: Some(RobustLoss::Cauchy { k_px: -2.0 }), ..base.clone() },
            RequestOption::RobustKPx,
            "<robust_k_px> must be positive and finite",
        ),
        (
            CalibrationRequest { model_auto: true, centre: Some(CentreChoice::Fixed), ..base.clone() },
            RequestOption::Centre,
            "<model>='auto' chooses the distortion family, the focal degree and the centre itself: drop <centre>",
        ),
        (
            CalibrationRequest {
                model_auto: true,
                ..CalibrationRequest { method: Method::PerSetting, ..base.clone() }
            },
            RequestOption::Model,
            "<method>='per-setting' takes no <model>",
        ),
    ];
    for (request, option, words) in cases {
        let refusal = request.check().unwrap_err();
        assert_eq!(refusal.option(), option, "{refusal:?}");
        let e = request.validate(&Brackets).unwrap_err();
        let message = e.to_string();
        assert!(message.contains(words) && !message.contains('\n'), "{words:?} not in {message}");
        assert_eq!(e.input_what(), Some(format!("<{}>", option.key()).as_str()), "{message}");
    }
    let e = CalibrationRequest { robust: Some(RobustLoss::Huber { k_px: -2.0 }), ..base }.validate(&KeySpelling);
    let e = e.unwrap_err();
    assert_eq!((e.input_what(), e.input_value().as_deref()), (Some("robust_k_px"), Some("-2")));
    // The paper family's flag is allowed where the data may choose opencv.
    let auto = CalibrationRequest { fix_k3: true, distortion: Some(DistortionChoice::Auto), ..Default::default() };
    assert!(auto.check().is_ok());
    // model = auto leaves every choice to the data.
    let model = CalibrationRequest { model_auto: true, ..Default::default() };
    assert!(model.check().is_ok());
    assert_eq!((model.family(), model.degree(), model.moving_centre()), (None, None, None));
    let zhang = ZhangRequest { zero_tangent: true, ..ZhangRequest::default() };
    assert_eq!(
        zhang.check().unwrap_err(),
        Refusal::OpenCvFlagNeedsOpenCv {
            flag: RequestOption::ZeroTangent,
            family: RequestOption::Model,
            auto_allowed: false
        }
    );
    let message = zhang.validate(&Brackets).unwrap_err().to_string();
    assert!(message.contains("<zero_tangent>! is an OpenCV flag: it needs <model>='opencv' (the"), "{message}");
}

#[test]
fn a_run_is_the_pipelines_result_and_refuses_missing_data_by_name() {
    let sim = paper_rig(&NoiseModel::PAPER, 1);
    let thermal = ThermalRef::paper();
    let request = CalibrationRequest {
        a0: Some(sim.a0),
        thermal: Some(thermal.clone()),
        hold_a0: true,
        robust: Some(RobustLoss::Huber { k_px: 1.5 }),
        ..CalibrationRequest::default()
    };
    let got = request.run(&sim.observations, &KeySpelling).unwrap().into_calibration();
    let options =
        CalibrateOptions { hold_a0: true, robust: Some(RobustLoss::Huber { k_px: 1.5 }), ..Default::default() };
    let want = calibrate(&sim.observations, &sim.a0, Some(&thermal), &options).unwrap().calibration;
    assert_eq!(serde_json::to_value(&got).unwrap(), serde_json::to_value(&want).unwrap());
    assert!((got.kf_x[0] - sim.a0.kf0x).abs() < 1e-3, "A0 held: {}", got.kf_x[0]);
    // No lens-off views and no A0; no setting views for the baseline.
    let mut no_offstate = sim.observations.clone();
    no_offstate.offstate_views.clear();
    let e = CalibrationRequest::default().run(&no_offstate, &Brackets).unwrap_err();
    assert_eq!(e.input_what(), Some("offstate_views"));
    assert!(e.to_string().contains("no lens-off views (offstate_views) in the observations: pass <a0>"), "{e}");
    let baseline = CalibrationRequest { method: Method::PerSetting, ..CalibrationRequest::default() };
    let e = baseline.run(&sim.observations, &Brackets).unwrap_err();
    assert_eq!(e.input_what(), Some("setting_views"));
    assert!(e.to_string().contains("<method>='per-setting' needs setting_views"), "{e}");
}

/// A per-camera request on top of a shared one takes exactly the options given from the
/// camera's (both units of the stage prior and both words of the robust loss included),
/// and every key names its option.
#[test]
fn overridden_takes_the_given_options_only() {
    use etl_calib::request::{CentreChoice, DistortionChoice, EivPriors, RequestOption, StageSigma};
    for option in RequestOption::ALL {
        assert_eq!(RequestOption::from_key(option.key()), Some(option));
    }
    assert_eq!(RequestOption::from_key("out"), None);
    let shared = CalibrationRequest {
        thermal: Some(ThermalRef::paper()),
        hold_a0: true,
        priors: EivPriors { sigma_px: Some(0.3), ..EivPriors::default() },
        ..CalibrationRequest::default()
    };
    let camera = CalibrationRequest {
        distortion: Some(DistortionChoice::Family(DistortionModel::OpenCv)),
        centre: Some(CentreChoice::Moving),
        priors: EivPriors { sigma_z: Some(StageSigma::Um(20.0)), ..EivPriors::default() },
        ..CalibrationRequest::default()
    };
    let merged = shared.overridden(&camera, &[RequestOption::Distortion, RequestOption::HoldA0]);
    assert_eq!(merged.distortion, camera.distortion);
    assert!(!merged.hold_a0, "hold_a0 given (off) by the camera");
    assert_eq!((merged.centre, merged.thermal.clone(), merged.priors), (None, shared.thermal.clone(), shared.priors));
    let stage = shared.overridden(&camera, &[RequestOption::SigmaZUm, RequestOption::Thermal]);
    assert_eq!((stage.priors.sigma_z, stage.priors.sigma_px, stage.thermal), (camera.priors.sigma_z, Some(0.3), None));
    assert_eq!(shared.overridden(&camera, &[]), shared);
}
