//! `calibrate`: the calibration pipeline from observations (E_com -> RAC -> focal
//! polynomial -> distortion -> bundle adjustment), run without the GIL. The keywords only
//! parse into etl-calib's `CalibrationRequest` (its defaults, refusals and run), which
//! `etlcal calibrate` parses its flags into too: the same names, the same file.

use etl_calib::pipeline::SettingViews;
use etl_calib::request::{
    CalibrationRequest, CentreChoice, DistortionChoice, EivPriors, EstimatorChoice, FocalDegreeChoice, Method,
    RequestOption, Spelling, StageSigma, DEFAULT_ROBUST_K_PX,
};
use etl_core::calib::RobustLoss;
use etl_core::model::DistortionModel;
use pyo3::prelude::*;

use crate::calibration::Calibration;
use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};
use crate::observations::{Observations, A0};

/// Python's words for the options of a request: the keyword (`hold_a0`), a word as a
/// string literal (`"auto"`), `distortion="opencv"`, `fix_k3=True`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Keywords;

impl Spelling for Keywords {
    fn name(&self, option: RequestOption) -> String {
        option.key().to_owned()
    }
    fn word(&self, word: &str) -> String {
        format!("{word:?}")
    }
    fn with_word(&self, option: RequestOption, word: &str) -> String {
        format!("{}={word:?}", option.key())
    }
    fn switched_on(&self, option: RequestOption) -> String {
        format!("{}=True", option.key())
    }
}

/// Calibrates an ETL camera from observations (paper section 4): E_com of each view
/// through the thermal surface (unless recorded), RAC (Eq. 19-20), the focal polynomial
/// and tz (Eq. 21-22), the distortion (Eq. 23), then bundle adjustment (Eq. 24). Every
/// keyword has a flag of `etlcal calibrate` of the same name (`hold_a0`: `--hold-a0`), and
/// the same request gives the same calibration through both.
///
/// Args:
///     observations: the corners of the ETL views (an `Observations`; >= 3 distinct
///         currents, non-coplanar points: the board at several stage positions).
///     a0: the lens-off intrinsics (an `A0`: kf0x, kf0y, u0, v0 in px), e.g. from
///         `zhang(...)` on lens-off views. None: Zhang's method on the observations'
///         lens-off views (section 4.2), as `etlcal calibrate` does without `--a0`.
///     thermal: the temperature compensation used for views without a recorded E_com:
///         a `ThermalCalibration`, or "paper" for the paper's surface. Required when a
///         view has no E_com (none is assumed); kept whole in the calibration, which
///         uses it at run time (`Calibration.at`).
///     estimator: "eiv" (errors-in-variables: a stage and a current correction per view
///         with Gaussian priors sigma_z_mm and sigma_e_ma; under the paper's noise model
///         it reaches the Cramer-Rao bound) or "paper" (Eq. 24: recorded stage positions
///         and currents exact). None (the default): "eiv".
///     hold_a0: hold kf0x, kf0y, u0, v0 at A0 in the bundle adjustment.
///     robust: None, "huber" or "cauchy" (a robust loss on each point's error).
///     robust_k_px: threshold / scale of the robust loss, px (> 0; used with robust;
///         None: 1 px).
///     sigma_z_mm: spread of a view's recorded stage position, mm (None: the paper's
///         0.010): the "eiv" prior, and the error the "paper" covariance accounts for.
///     sigma_e_ma: the same for the recorded current, mA (None: the paper's 0.4).
///     sigma_p_dpt: the same for a focal-power view's commanded power, dpt (views at focal
///         powers only; None: 0.05, half the driver's stated 0.1 dpt reproducibility).
///     model: "auto" chooses the distortion family, the focal degree and the centre
///         together by held-out views (all 20 candidates, in `model_selection`); not with
///         distortion, focal_degree or centre.
///     sigma_px: pixel noise, px (None: estimated from the residuals).
///     method: "proposed" (the paper's method, above) or "per-setting" (the paper's
///         baseline of section 5.2.3: Zhang at each current of the observations'
///         setting views, >= 3 views at each of >= 3 currents, then a cubic through
///         fx(E), fy(E); R and T are not defined and are zero; a0, estimator, hold_a0,
///         robust and the model's options below do not apply and must be left at their
///         defaults).
///     distortion: the distortion family: "paper" (the default: Eq. 17, k1, p1, p2 in
///         centred pixels), "opencv" (OpenCV's k1, k2, p1, p2, k3 in normalised
///         coordinates; `to_opencv` is then exact) or "auto" (chosen by how well each
///         predicts the views held out one at a time; the comparison is the result's
///         `model_selection`). With a0=None, A0 comes from Zhang's method with the same
///         family.
///     focal_degree: the degree of fx(E), fy(E): 1..5 (default 3, the paper's cubic) or
///         "auto" (as distortion="auto").
///     fix_k3: hold k3 = 0 (cv2.CALIB_FIX_K3); distortion "opencv" or "auto" only.
///     zero_tangent: hold p1 = p2 = 0 (cv2.CALIB_ZERO_TANGENT_DIST); likewise.
///     sigma_z_um: the stage prior in um instead (as `--sigma-z-um`); not with sigma_z_mm.
///     centre: the projection centre: "fixed" (the default, the paper's), "moving" (the
///         centre moves along the axis by dz(E) = dz1 E + dz2 E^2 and the principal
///         point by (u1 E, v1 E): the entrance pupil behind an ETL moves with its power;
///         the result's `centre`) or "auto" (as distortion="auto").
///     setting_views: what the bundle adjustment does with the observations'
///         setting views (tilted boards, each in its own pose): None or "ignored" (the
///         default, the paper's method: the stage views alone) or "joint" (solved with
///         the stage views, each board's pose a free unknown started by PnP, so that
///         tilted views tell fx(E) from a moving centre's dz(E)); "joint" needs setting
///         views of >= 4 points each and is refused with method="per-setting", a robust
///         loss or an "auto" model choice.
///     accept_ill_conditioned: keep a calibration the data do not determine (a focal
///         length not positive over the range, a principal point std above 5 % of the
///         image), its symptom the first of its `warnings`; False (the default): refused
///         with InputError naming the cause.
///
/// Returns: a `Calibration` with the standard deviations (`std`), the RMS reprojection
/// error (`rms_px`), per-view summaries (`views`), the corners left out as gross outliers
/// (`outliers`) and why the result may be implausible (`warnings`).
///
/// Warns: UserWarning for each of `warnings` (and when there is no focus law).
///
/// Raises: InputError naming the argument or the unmet precondition (e.g. fewer than 3
/// distinct currents, no lens-off views when a0 is None); NotConvergedError when the
/// bundle adjustment fails.
#[pyfunction]
#[pyo3(signature = (observations, a0=None, thermal=None, estimator=None, hold_a0=false, robust=None,
    robust_k_px=None, sigma_z_mm=None, sigma_e_ma=None, sigma_px=None, method="proposed",
    distortion=None, focal_degree=None, fix_k3=false, zero_tangent=false, sigma_z_um=None,
    accept_ill_conditioned=false, centre=None, sigma_p_dpt=None, model=None, setting_views=None))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    // By value (a copy taken under the GIL): a borrow held through the solve would make
    // another thread's `add_view` fail with "Already borrowed".
    observations: Observations,
    a0: Option<&A0>,
    thermal: Option<&Bound<'_, PyAny>>,
    estimator: Option<&str>,
    hold_a0: bool,
    robust: Option<&str>,
    robust_k_px: Option<f64>,
    sigma_z_mm: Option<f64>,
    sigma_e_ma: Option<f64>,
    sigma_px: Option<f64>,
    method: &str,
    distortion: Option<&str>,
    focal_degree: Option<&Bound<'_, PyAny>>,
    fix_k3: bool,
    zero_tangent: bool,
    sigma_z_um: Option<f64>,
    accept_ill_conditioned: bool,
    centre: Option<&str>,
    sigma_p_dpt: Option<f64>,
    model: Option<&str>,
    setting_views: Option<&str>,
) -> PyResult<Calibration> {
    let mut request = request_of(
        (method, a0, thermal, estimator, hold_a0, robust, robust_k_px),
        (sigma_z_mm, sigma_e_ma, sigma_px, sigma_z_um, sigma_p_dpt),
        (distortion, focal_degree, fix_k3, zero_tangent, accept_ill_conditioned, centre, model),
    )?;
    request.setting_views = setting_views.map(parse_setting_views).transpose()?;
    request.validate(&Keywords).py()?;
    let obs = observations.file;
    let calibrated = crate::pool::detach(py, || request.run(&obs, &Keywords)).py()?;
    // Said, not silent: a calibration without a focus law, and implausible data (also in
    // Calibration.warnings).
    // Also said once: no temperature compensation (views with E_com, no thermal=).
    let uncompensated = calibrated
        .calibration()
        .temperature_compensation_warning()
        .map(|why| format!("{why}: use it with at_e_com(e_com_ma)"));
    for why in calibrated.warnings().into_iter().chain(uncompensated.as_deref()) {
        let message = std::ffi::CString::new(why).map_err(|e| input_error(e.to_string()))?;
        // Level 2: the caller's line, above `etlcal._guard`'s wrapper (the user calls that).
        PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &message, 2)?;
    }
    Calibration::from_file(calibrated.into_calibration())
}

/// The request's run options: method, A0, thermal, estimator, hold_a0, robust loss and
/// its threshold.
pub(crate) type RunKeywords<'a, 'py> =
    (&'a str, Option<&'a A0>, Option<&'a Bound<'py, PyAny>>, Option<&'a str>, bool, Option<&'a str>, Option<f64>);
/// The request's priors: sigma_z_mm, sigma_e_ma, sigma_px, sigma_z_um, sigma_p_dpt.
pub(crate) type PriorKeywords = (Option<f64>, Option<f64>, Option<f64>, Option<f64>, Option<f64>);
/// The request's model: distortion, focal degree, fix_k3, zero_tangent,
/// accept_ill_conditioned, centre, model.
pub(crate) type ModelKeywords<'a, 'py> =
    (Option<&'a str>, Option<&'a Bound<'py, PyAny>>, bool, bool, bool, Option<&'a str>, Option<&'a str>);

/// The keywords of `calibrate` (and `calibrate_rig`) as etl-calib's request, each word
/// parsed (refused naming the keyword), not yet validated.
pub(crate) fn request_of(
    (method, a0, thermal, estimator, hold_a0, robust, robust_k_px): RunKeywords<'_, '_>,
    (sigma_z_mm, sigma_e_ma, sigma_px, sigma_z_um, sigma_p_dpt): PriorKeywords,
    (distortion, focal_degree, fix_k3, zero_tangent, accept_ill_conditioned, centre, model): ModelKeywords<'_, '_>,
) -> PyResult<CalibrationRequest> {
    let model_auto = match model {
        None => false,
        Some("auto") => true,
        Some(other) => {
            return Err(invalid_value("model", other, format!("model must be \"auto\" or None, got {other:?}")))
        }
    };
    let sigma_z = match (sigma_z_mm, sigma_z_um) {
        (Some(_), Some(_)) => return Err(invalid("sigma_z_um", "give sigma_z_mm or sigma_z_um, not both")),
        (mm, um) => mm.map(StageSigma::Mm).or(um.map(StageSigma::Um)),
    };
    Ok(CalibrationRequest {
        method: parse_method(method)?,
        a0: a0.map(|a| a.inner),
        thermal: thermal.map(crate::calibration::thermal_ref).transpose()?,
        estimator: estimator.map(parse_estimator).transpose()?,
        priors: EivPriors { sigma_z, sigma_e_ma, sigma_p_dpt, sigma_px },
        hold_a0,
        robust: robust.map(|r| parse_robust(r, robust_k_px.unwrap_or(DEFAULT_ROBUST_K_PX))).transpose()?,
        distortion: distortion.map(parse_distortion).transpose()?,
        focal_degree: focal_degree.map(parse_focal_degree).transpose()?,
        fix_k3,
        zero_tangent,
        accept_ill_conditioned,
        centre: centre.map(parse_centre).transpose()?,
        model_auto,
        // Set by the callers that take it: `calibrate`'s keyword, a `per_camera` entry's.
        setting_views: None,
    })
}

/// `setting_views=`: "ignored" or "joint".
pub(crate) fn parse_setting_views(word: &str) -> PyResult<SettingViews> {
    SettingViews::from_word(word).ok_or_else(|| {
        invalid_value(
            "setting_views",
            word,
            format!("setting_views must be \"ignored\", \"joint\" or None, got {word:?}"),
        )
    })
}

/// `centre=`: "fixed", "moving" or "auto".
fn parse_centre(centre: &str) -> PyResult<CentreChoice> {
    CentreChoice::from_word(centre).ok_or_else(|| {
        invalid_value("centre", centre, format!("centre must be \"fixed\", \"moving\" or \"auto\", got {centre:?}"))
    })
}

/// `method=`: "proposed" or "per-setting".
fn parse_method(method: &str) -> PyResult<Method> {
    match method {
        "proposed" => Ok(Method::Proposed),
        "per-setting" => Ok(Method::PerSetting),
        other => Err(invalid_value(
            "method",
            other,
            format!("method must be \"proposed\" or \"per-setting\", got {other:?}"),
        )),
    }
}

/// `estimator=`: "paper" or "eiv".
fn parse_estimator(estimator: &str) -> PyResult<EstimatorChoice> {
    match estimator {
        "paper" => Ok(EstimatorChoice::Paper),
        "eiv" => Ok(EstimatorChoice::Eiv),
        other => {
            Err(invalid_value("estimator", other, format!("estimator must be \"paper\" or \"eiv\", got {other:?}")))
        }
    }
}

/// `robust=` ("huber" or "cauchy") with `robust_k_px=`.
fn parse_robust(robust: &str, k_px: f64) -> PyResult<RobustLoss> {
    match robust {
        "huber" => Ok(RobustLoss::Huber { k_px }),
        "cauchy" => Ok(RobustLoss::Cauchy { k_px }),
        other => {
            Err(invalid_value("robust", other, format!("robust must be None, \"huber\" or \"cauchy\", got {other:?}")))
        }
    }
}

/// `distortion=`: "paper", "opencv" or "auto".
fn parse_distortion(name: &str) -> PyResult<DistortionChoice> {
    if name == "auto" {
        return Ok(DistortionChoice::Auto);
    }
    DistortionModel::from_name(name).map(DistortionChoice::Family).ok_or_else(|| {
        invalid_value("distortion", name, format!("distortion must be \"paper\", \"opencv\" or \"auto\", got {name:?}"))
    })
}

/// `focal_degree=`: 1..5 or "auto".
fn parse_focal_degree(d: &Bound<'_, PyAny>) -> PyResult<FocalDegreeChoice> {
    if d.extract::<String>().is_ok_and(|s| s == "auto") {
        return Ok(FocalDegreeChoice::Auto);
    }
    match d.extract::<usize>() {
        Ok(n) if (1..=etl_core::model::MAX_FOCAL_DEGREE).contains(&n) => Ok(FocalDegreeChoice::Degree(n)),
        _ => {
            Err(invalid_value("focal_degree", d.to_string(), format!("focal_degree must be 1..5 or \"auto\", got {d}")))
        }
    }
}

/// The Cramer-Rao lower bound of the calibration: the smallest standard deviation any
/// unbiased estimator can reach for each of the 25 numbers, at the true camera, for the
/// views' geometry (the benchmark of docs/METHOD.md, "statistical efficiency").
///
/// Args:
///     observations: the views (their world points and currents are used; the pixels
///         are not).
///     truth: the true camera (a `Calibration`).
///     sigma_px: pixel noise standard deviation, px (> 0).
///     sigma_z_mm: prior standard deviation of each view's stage position, mm (None:
///         stage positions exact, the paper's model).
///     sigma_e_ma: prior standard deviation of each view's current, mA (given together
///         with sigma_z_mm).
///     thermal: temperature compensation for views without a recorded E_com (a
///         `ThermalCalibration` or "paper"; required when a view has none).
///
/// Returns: a ModelStd like `Calibration.std` (one standard deviation per number; NaN for
/// directions the data do not identify).
#[pyfunction]
#[pyo3(signature = (observations, truth, sigma_px, sigma_z_mm=None, sigma_e_ma=None, thermal=None))]
pub fn cramer_rao_std<'py>(
    py: Python<'py>,
    observations: Observations,
    truth: &Calibration,
    sigma_px: f64,
    sigma_z_mm: Option<f64>,
    sigma_e_ma: Option<f64>,
    thermal: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let priors = match (sigma_z_mm, sigma_e_ma) {
        (None, None) => None,
        (Some(z), Some(e)) => Some((z, e)),
        (None, _) => return Err(invalid("sigma_z_mm", "give both sigma_z_mm and sigma_e_ma, or neither")),
        (_, None) => return Err(invalid("sigma_e_ma", "give both sigma_z_mm and sigma_e_ma, or neither")),
    };
    // The calibration request's ranges: a sigma whose square overflows gave a bound of 0.
    let sigmas = [
        (RequestOption::SigmaPx, Some(sigma_px)),
        (RequestOption::SigmaZMm, sigma_z_mm),
        (RequestOption::SigmaEMa, sigma_e_ma),
    ];
    for (option, value) in sigmas {
        if let Some(v) = value {
            etl_calib::request::positive(option, v).map_err(|r| crate::errors::calib_err(r.to_error(&Keywords)))?;
        }
    }
    let thermal = thermal.map(crate::calibration::thermal_ref).transpose()?;
    let obs = &observations.file;
    obs.validate().py()?;
    let e_com = obs.e_com_ma(thermal.as_ref()).map_err(crate::errors::calib_err)?;
    let pts = obs.core_points();
    let model = truth.model;
    let cov = crate::pool::detach(py, || {
        let views: Vec<etl_core::calib::View<'_>> =
            pts.iter().zip(&e_com).map(|(p, &e)| etl_core::calib::View { e_com_ma: e, points: p }).collect();
        etl_core::calib::crlb::crlb_covariance_eiv(&views, &model, sigma_px, priors)
    })
    .py()?;
    let sd: [f64; etl_core::calib::params::MAX_PARAMS] =
        core::array::from_fn(|i| if cov[i][i] >= 0.0 { cov[i][i].sqrt() } else { f64::NAN });
    let std = etl_formats::calibration::ModelStd::from_params(&model.layout(), &sd);
    crate::calibration::std_dict(py, &std)
}
