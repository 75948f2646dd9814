//! `calibrate`: the calibration pipeline from observations (E_com -> RAC -> focal
//! polynomial -> distortion -> bundle adjustment), run without the GIL.

use etl_calib::pipeline::select::{refuse_opencv_flags, select, A0Source, Candidates};
use etl_calib::pipeline::{calibrate as run_pipeline, CalibrateOptions};
use etl_core::calib::{Estimator, Layout, RobustLoss};
use etl_core::model::{DistortionModel, OpenCvFlags};
use pyo3::prelude::*;

use crate::calibration::Calibration;
use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};
use crate::observations::{Observations, A0};

/// Calibrates an ETL camera from observations (paper section 4): E_com of each view
/// through the thermal surface (unless recorded), RAC (Eq. 19-20), the focal polynomial
/// and tz (Eq. 21-22), the distortion (Eq. 23), then bundle adjustment (Eq. 24).
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
///     robust_k_px: threshold / scale of the robust loss, px.
///     sigma_z_mm: "eiv" prior on the stage position, mm (paper: 0.010).
///     sigma_e_ma: "eiv" prior on the current, mA (paper: 0.4).
///     sigma_px: "eiv" pixel noise, px (default: estimated from a plain solution).
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
///
/// Returns: a `Calibration` with the standard deviations (`std`), the RMS reprojection
/// error (`rms_px`), per-view summaries (`views`), the corners left out as gross outliers
/// (`outliers`) and why the result may be implausible (`warnings`).
///
/// Warns: UserWarning for each of `warnings` (and when there is no focus law).
///
/// Raises: InputError naming the unmet precondition (e.g. fewer than 3 distinct
/// currents, no lens-off views when a0 is None); NotConvergedError when the bundle
/// adjustment fails.
#[pyfunction]
#[pyo3(signature = (observations, a0=None, thermal=None, estimator=None, hold_a0=false, robust=None,
    robust_k_px=1.0, sigma_z_mm=0.010, sigma_e_ma=0.4, sigma_px=None, method="proposed", distortion=None,
    focal_degree=None, fix_k3=false, zero_tangent=false))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    observations: &Observations,
    a0: Option<&A0>,
    thermal: Option<&Bound<'_, PyAny>>,
    estimator: Option<&str>,
    hold_a0: bool,
    robust: Option<&str>,
    robust_k_px: f64,
    sigma_z_mm: f64,
    sigma_e_ma: f64,
    sigma_px: Option<f64>,
    method: &str,
    distortion: Option<&str>,
    focal_degree: Option<&Bound<'_, PyAny>>,
    fix_k3: bool,
    zero_tangent: bool,
) -> PyResult<Calibration> {
    let thermal = thermal.map(crate::calibration::thermal_ref).transpose()?;
    let model_given = [
        ("distortion", distortion.is_some()),
        ("focal_degree", focal_degree.is_some()),
        ("fix_k3", fix_k3),
        ("zero_tangent", zero_tangent),
    ];
    let choice = ModelChoice::parse(distortion, focal_degree, OpenCvFlags { fix_k3, zero_tangent })?;
    match method {
        "proposed" => {}
        "per-setting" => {
            // An estimator given at all is refused, "eiv" and "paper" alike: the baseline
            // has no bundle adjustment.
            etl_calib::baseline::refuse_bundle_adjust_options(
                "method=\"per-setting\"",
                [
                    ("a0", a0.is_some()),
                    ("estimator", estimator.is_some()),
                    ("hold_a0", hold_a0),
                    ("robust", robust.is_some()),
                ],
            )
            .py()?;
            if let Some((name, _)) = model_given.iter().find(|(_, given)| *given) {
                return Err(invalid(
                    name,
                    format!(
                        "method=\"per-setting\" takes no {name}: the baseline fits the paper's model (cubic, paper distortion)"
                    ),
                ));
            }
            let obs = observations.file.clone();
            let result = py.detach(|| etl_calib::baseline::per_setting(&obs, thermal.as_ref())).py()?;
            return Calibration::from_file(result.calibration);
        }
        other => {
            return Err(invalid_value(
                "method",
                other,
                format!("method must be \"proposed\" or \"per-setting\", got {other:?}"),
            ))
        }
    }
    let estimator = match estimator.unwrap_or("eiv") {
        "paper" => Estimator::Paper,
        "eiv" => Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px },
        other => {
            return Err(invalid_value(
                "estimator",
                other,
                format!("estimator must be \"paper\" or \"eiv\", got {other:?}"),
            ))
        }
    };
    let robust = match robust {
        None => None,
        Some("huber") => Some(RobustLoss::Huber { k_px: robust_k_px }),
        Some("cauchy") => Some(RobustLoss::Cauchy { k_px: robust_k_px }),
        Some(other) => {
            return Err(invalid_value(
                "robust",
                other,
                format!("robust must be None, \"huber\" or \"cauchy\", got {other:?}"),
            ))
        }
    };
    let options = CalibrateOptions { estimator, hold_a0, robust, layout: Layout::PAPER, flags: choice.flags };
    let obs = observations.file.clone();
    let a0 = a0.map(|a| a.inner);
    let result = py.detach(|| choice.run(&obs, a0, thermal.as_ref(), &options)).py()?;
    // Said, not silent: a calibration without a focus law, and implausible data (also in
    // Calibration.warnings).
    for why in result.focus_law_warning.iter().chain(&result.calibration.warnings) {
        let message = std::ffi::CString::new(why.as_str()).map_err(|e| input_error(e.to_string()))?;
        PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &message, 1)?;
    }
    Calibration::from_file(result.calibration)
}

/// The model `calibrate` is asked for: a family and a degree, each given or chosen by the
/// data (None), and OpenCV's flags.
struct ModelChoice {
    family: Option<DistortionModel>,
    degree: Option<usize>,
    flags: OpenCvFlags,
}

impl ModelChoice {
    /// From `distortion=` ("paper" | "opencv" | "auto"; None: "paper"), `focal_degree=`
    /// (1..5 | "auto"; None: 3) and the flags, refused with the paper family.
    fn parse(distortion: Option<&str>, focal_degree: Option<&Bound<'_, PyAny>>, flags: OpenCvFlags) -> PyResult<Self> {
        let family = match distortion.unwrap_or("paper") {
            "auto" => None,
            name => Some(DistortionModel::from_name(name).ok_or_else(|| {
                invalid_value(
                    "distortion",
                    name,
                    format!("distortion must be \"paper\", \"opencv\" or \"auto\", got {name:?}"),
                )
            })?),
        };
        let degree = match focal_degree {
            None => Some(etl_core::model::PAPER_FOCAL_DEGREE),
            Some(d) if d.extract::<String>().is_ok_and(|s| s == "auto") => None,
            Some(d) => match d.extract::<usize>() {
                Ok(n) if (1..=etl_core::model::MAX_FOCAL_DEGREE).contains(&n) => Some(n),
                _ => {
                    return Err(invalid_value(
                        "focal_degree",
                        d.to_string(),
                        format!("focal_degree must be 1..5 or \"auto\", got {d}"),
                    ))
                }
            },
        };
        refuse_opencv_flags(family, flags, ["fix_k3=True", "zero_tangent=True"], "distortion=\"opencv\" or \"auto\"")
            .map_err(crate::errors::calib_err)?;
        Ok(ModelChoice { family, degree, flags })
    }

    /// Calibrates: the given model, or [`select`] among the candidates. A0 given, or from
    /// Zhang's method on the lens-off views with the (candidate's) family.
    fn run(
        &self,
        obs: &etl_formats::Observations,
        a0: Option<etl_core::calib::A0>,
        thermal: Option<&etl_formats::ThermalRef>,
        options: &CalibrateOptions,
    ) -> etl_formats::Result<etl_calib::pipeline::CalibrationResult> {
        match (self.family, self.degree) {
            (Some(model), Some(degree)) => {
                let layout = Layout::new(model, degree).map_err(etl_formats::Error::Core)?;
                let a0 = match a0 {
                    Some(a0) => a0,
                    None => {
                        let zhang = etl_calib::zhang::ZhangOptions { model, flags: self.flags };
                        etl_calib::pipeline::a0_from_offstate_with(obs, &zhang)?.a0()
                    }
                };
                run_pipeline(obs, &a0, thermal, &CalibrateOptions { layout, ..*options })
            }
            _ => {
                let candidates = Candidates {
                    families: self.family.map_or(DistortionModel::ALL.to_vec(), |f| vec![f]),
                    focal_degrees: self.degree.map_or((1..=etl_core::model::MAX_FOCAL_DEGREE).collect(), |d| vec![d]),
                };
                select(obs, &a0.map_or(A0Source::Offstate, A0Source::Given), thermal, options, &candidates)
            }
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
    observations: &Observations,
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
    if !(sigma_px > 0.0 && sigma_px.is_finite()) {
        return Err(invalid_value("sigma_px", sigma_px, format!("sigma_px = {sigma_px} must be a finite number > 0")));
    }
    let thermal = thermal.map(crate::calibration::thermal_ref).transpose()?;
    let obs = &observations.file;
    obs.validate().py()?;
    let e_com = obs.e_com_ma(thermal.as_ref()).map_err(crate::errors::calib_err)?;
    let pts = obs.core_points();
    let model = truth.model;
    let cov = py
        .detach(|| {
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
