//! [`CalibrationRequest`]: every option of a calibration, its defaults, its validation and
//! its run.

use etl_core::calib::{Estimator, InputNoise, Layout, RobustLoss, A0};
use etl_core::model::{DistortionModel, OpenCvFlags, MAX_FOCAL_DEGREE, PAPER_FOCAL_DEGREE};
use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::observations::Observations;
use etl_formats::{Error, Result};

use super::option::{RequestOption, Spelling};
use super::refusal::{positive, Refusal};
use crate::baseline::{per_setting, BaselineResult};
use crate::pipeline::select::{select, A0Source, Candidates};
use crate::pipeline::{a0_from_offstate_with, calibrate, CalibrateOptions, CalibrationResult, SettingViews};
use crate::zhang::ZhangOptions;

/// The threshold / scale of the robust loss when the front end is given the loss without
/// one, px: one pixel, about five times the paper rig's corner noise (0.2 px), so that
/// clean corners stay in the quadratic part.
pub const DEFAULT_ROBUST_K_PX: f64 = 1.0;

/// The calibration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// The paper's method (section 4): RAC, focal polynomial, distortion, bundle adjustment.
    #[default]
    Proposed,
    /// The paper's baseline (section 5.2.3): Zhang at each current of the observations'
    /// setting views, then a cubic through fx(E), fy(E).
    PerSetting,
}

/// The bundle adjustment's estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EstimatorChoice {
    /// The paper's Eq. 24: recorded stage positions and currents exact.
    Paper,
    /// Errors-in-variables: a stage and a current correction per view with Gaussian priors
    /// ([`EivPriors`]); under the paper's noise model it reaches the Cramer-Rao bound.
    Eiv,
}

/// The stage-position prior of errors-in-variables in the unit it was given in (the CLI
/// took um, Python mm; both now take both), so that a refusal names what was given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StageSigma {
    /// In mm.
    Mm(f64),
    /// In um.
    Um(f64),
}

impl StageSigma {
    /// The standard deviation, mm (um / 1000).
    pub fn mm(self) -> f64 {
        match self {
            StageSigma::Mm(mm) => mm,
            StageSigma::Um(um) => um / 1000.0,
        }
    }

    /// The option it was given as, and its value there.
    fn given(self) -> (RequestOption, f64) {
        match self {
            StageSigma::Mm(mm) => (RequestOption::SigmaZMm, mm),
            StageSigma::Um(um) => (RequestOption::SigmaZUm, um),
        }
    }
}

/// The noise levels of errors-in-variables; each `None` takes the paper's
/// ([`Estimator::EIV_PAPER`]: 10 um, 0.4 mA, sigma_px estimated from a plain solution).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EivPriors {
    /// The stage position's prior standard deviation.
    pub sigma_z: Option<StageSigma>,
    /// The current's prior standard deviation, mA.
    pub sigma_e_ma: Option<f64>,
    /// A focal-power view's prior standard deviation, dpt (focal-power views only;
    /// `None`: [`crate::pipeline::FOCAL_POWER_SIGMA_DPT`]).
    pub sigma_p_dpt: Option<f64>,
    /// The pixel noise, px; `None`: estimated (the default).
    pub sigma_px: Option<f64>,
}

/// A distortion family, or the choice left to the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DistortionChoice {
    /// This family.
    Family(DistortionModel),
    /// Chosen by how well each family predicts the views held out one at a time
    /// ([`crate::pipeline::select`]).
    Auto,
}

/// A degree of fx(E), fy(E), or the choice left to the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FocalDegreeChoice {
    /// This degree, 1..=[`MAX_FOCAL_DEGREE`].
    Degree(usize),
    /// Chosen by held-out views, as [`DistortionChoice::Auto`].
    Auto,
}

/// The projection centre of the model (docs/METHOD.md, "The moving centre").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CentreChoice {
    /// The paper's: one centre and one principal point for every setting.
    Fixed,
    /// A centre that moves along the axis by dz(E) and a principal point (u0(E), v0(E))
    /// (Eq. C1-C3 of `etl_core::model::centre`).
    Moving,
    /// Chosen by held-out views, as [`DistortionChoice::Auto`] (fixed unless the moving
    /// centre predicts better by more than one standard error).
    Auto,
}

impl CentreChoice {
    /// The word of the choice (`fixed`, `moving`, `auto`): the CLI's value and Python's.
    pub const fn word(self) -> &'static str {
        match self {
            CentreChoice::Fixed => "fixed",
            CentreChoice::Moving => "moving",
            CentreChoice::Auto => "auto",
        }
    }

    /// The choice a word names, or `None`.
    pub fn from_word(word: &str) -> Option<Self> {
        [CentreChoice::Fixed, CentreChoice::Moving, CentreChoice::Auto].into_iter().find(|c| c.word() == word)
    }
}

/// Every option of a calibration: what `etlcal calibrate` and Python's
/// `etlcal.calibrate(...)` parse their arguments into, so that the two give the same file
/// for the same request. An option left `None` (or `false`) was not given and takes its
/// default, defined here once: the proposed method, A0 by Zhang's method on the lens-off
/// views, errors-in-variables with the paper's noise levels, no robust loss, A0 free, the
/// paper's distortion family and cubic fx(E), fy(E), no OpenCV flag. "Not given" is kept
/// apart from "given the default" because the per-setting baseline refuses an option given
/// at all (an explicit `eiv` too): it would be silently ignored.
///
/// [`CalibrationRequest::check`] refuses what no run can honour (cheap, before any input is
/// read); [`CalibrationRequest::run`] checks again and calibrates. Refusals name the option
/// in the caller's words ([`Spelling`]).
///
/// ```
/// use etl_calib::request::{CalibrationRequest, EstimatorChoice, KeySpelling, Refusal, RequestOption};
/// use etl_formats::ThermalRef;
/// use etl_sim::simulate::{paper_rig, NoiseModel};
///
/// let sim = paper_rig(&NoiseModel::PAPER, 1);
/// let request = CalibrationRequest {
///     a0: Some(sim.a0),
///     thermal: Some(ThermalRef::paper()),
///     estimator: Some(EstimatorChoice::Paper),
///     ..CalibrationRequest::default()
/// };
/// let calibrated = request.run(&sim.observations, &KeySpelling)?;
/// let cal = calibrated.calibration();
/// assert_eq!((cal.estimator.as_str(), cal.views.len()), ("paper", 15));
/// let fx = cal.kf_x.iter().rev().fold(0.0, |acc, k| acc * 150.0 + k);
/// assert!((fx / sim.truth.focal_lengths(150.0).0 - 1.0).abs() < 0.02);
///
/// // An OpenCV flag with the paper's distortion is refused, naming the flag.
/// let bad = CalibrationRequest { fix_k3: true, ..CalibrationRequest::default() };
/// let refusal = bad.check().unwrap_err();
/// assert_eq!(refusal.option(), RequestOption::FixK3);
/// assert!(matches!(refusal, Refusal::OpenCvFlagNeedsOpenCv { .. }));
/// assert!(refusal.message(&KeySpelling).starts_with("fix_k3 = true is an OpenCV flag"));
/// # Ok::<(), etl_calib::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CalibrationRequest {
    /// The method (default: proposed).
    pub method: Method,
    /// The lens-off intrinsics; `None`: Zhang's method on the lens-off views with the
    /// calibration's distortion family (a strongly distorting lens would otherwise bias A0).
    pub a0: Option<A0>,
    /// The temperature compensation of views without a recorded E_com; none is assumed.
    pub thermal: Option<ThermalRef>,
    /// The estimator; `None`: errors-in-variables.
    pub estimator: Option<EstimatorChoice>,
    /// The noise levels of errors-in-variables (checked whatever the estimator).
    pub priors: EivPriors,
    /// Hold kf0x, kf0y, u0, v0 at A0 in the bundle adjustment.
    pub hold_a0: bool,
    /// A robust loss on each point's error (threshold / scale in px).
    pub robust: Option<RobustLoss>,
    /// The distortion family; `None`: the paper's.
    pub distortion: Option<DistortionChoice>,
    /// The degree of fx(E), fy(E); `None`: 3, the paper's cubic.
    pub focal_degree: Option<FocalDegreeChoice>,
    /// Hold k3 = 0 (OpenCV's `CALIB_FIX_K3`; the opencv family, or `auto`).
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's `CALIB_ZERO_TANGENT_DIST`; likewise).
    pub zero_tangent: bool,
    /// Keep a calibration the data do not determine (a focal length not positive over
    /// the range, a loose principal point: [`super::ill_condition`]) instead of refusing
    /// it; its symptom is then the first of its `warnings`.
    pub accept_ill_conditioned: bool,
    /// The projection centre; `None`: fixed, the paper's.
    pub centre: Option<CentreChoice>,
    /// Every model choice to the data (`--model auto`, Python `model="auto"`): the
    /// distortion family, the focal degree and the centre chosen together by the error of
    /// held-out views ([`crate::pipeline::select`], all 20 candidates), reported in the
    /// file's `"model_selection"`. Refused beside any of the three.
    pub model_auto: bool,
    /// What the bundle adjustment does with the observations' `setting_views`; `None`:
    /// [`SettingViews::Ignored`], the paper's method (stage views only).
    /// [`SettingViews::Joint`] solves them with the stage views, each board in a pose of
    /// its own; refused without setting views, with the per-setting baseline, a robust
    /// loss or any model choice by the data (`auto`: its held-out views are stage views).
    pub setting_views: Option<SettingViews>,
}

/// What a run gives: the proposed method's result or the baseline's.
#[derive(Debug, Clone)]
pub enum Calibrated {
    /// The proposed method (a given model or the one [`select`] chose).
    Proposed(Box<CalibrationResult>),
    /// The per-setting baseline.
    PerSetting(Box<BaselineResult>),
}

impl Calibrated {
    /// The calibration file's content.
    pub fn calibration(&self) -> &Calibration {
        match self {
            Calibrated::Proposed(r) => &r.calibration,
            Calibrated::PerSetting(r) => &r.calibration,
        }
    }

    fn calibration_mut(&mut self) -> &mut Calibration {
        match self {
            Calibrated::Proposed(r) => &mut r.calibration,
            Calibrated::PerSetting(r) => &mut r.calibration,
        }
    }

    /// The calibration file's content, owned.
    pub fn into_calibration(self) -> Calibration {
        match self {
            Calibrated::Proposed(r) => r.calibration,
            Calibrated::PerSetting(r) => r.calibration,
        }
    }

    /// What front ends say as warnings: why there is no focus law, then why the data look
    /// implausible (the calibration's `warnings`, also kept in the file).
    pub fn warnings(&self) -> Vec<&str> {
        let focus_law = match self {
            Calibrated::Proposed(r) => r.focus_law_warning.as_deref(),
            Calibrated::PerSetting(_) => None,
        };
        focus_law.into_iter().chain(self.calibration().warnings.iter().map(String::as_str)).collect()
    }
}

impl CalibrationRequest {
    /// This request with the options `given` taken from `by`, the others kept: a front
    /// end's per-camera options applied on top of the shared ones (`etlcal calibrate-rig
    /// --camera-flags`, Python's `per_camera`). `sigma_z_mm` and `sigma_z_um` both set the
    /// stage prior, `robust` and `robust_k_px` both the robust loss.
    pub fn overridden(&self, by: &CalibrationRequest, given: &[RequestOption]) -> CalibrationRequest {
        let mut r = self.clone();
        for option in given {
            match option {
                RequestOption::Method => r.method = by.method,
                RequestOption::A0 => r.a0 = by.a0,
                RequestOption::Thermal => r.thermal.clone_from(&by.thermal),
                RequestOption::Estimator => r.estimator = by.estimator,
                RequestOption::SigmaZMm | RequestOption::SigmaZUm => r.priors.sigma_z = by.priors.sigma_z,
                RequestOption::SigmaEMa => r.priors.sigma_e_ma = by.priors.sigma_e_ma,
                RequestOption::SigmaPDpt => r.priors.sigma_p_dpt = by.priors.sigma_p_dpt,
                RequestOption::SigmaPx => r.priors.sigma_px = by.priors.sigma_px,
                RequestOption::HoldA0 => r.hold_a0 = by.hold_a0,
                RequestOption::Robust | RequestOption::RobustKPx => r.robust = by.robust,
                RequestOption::Distortion => r.distortion = by.distortion,
                RequestOption::FocalDegree => r.focal_degree = by.focal_degree,
                RequestOption::FixK3 => r.fix_k3 = by.fix_k3,
                RequestOption::ZeroTangent => r.zero_tangent = by.zero_tangent,
                RequestOption::Model => r.model_auto = by.model_auto,
                RequestOption::AcceptIllConditioned => r.accept_ill_conditioned = by.accept_ill_conditioned,
                RequestOption::Centre => r.centre = by.centre,
                RequestOption::SettingViews => r.setting_views = by.setting_views,
            }
        }
        r
    }

    /// The OpenCV flags asked for.
    pub fn flags(&self) -> OpenCvFlags {
        OpenCvFlags { fix_k3: self.fix_k3, zero_tangent: self.zero_tangent }
    }

    /// The family asked for: `Some` a family (the paper's by default), `None` chosen by the
    /// data.
    pub fn family(&self) -> Option<DistortionModel> {
        if self.model_auto {
            return None;
        }
        match self.distortion {
            None => Some(DistortionModel::Paper),
            Some(DistortionChoice::Family(f)) => Some(f),
            Some(DistortionChoice::Auto) => None,
        }
    }

    /// The focal degree asked for: `Some` a degree (3 by default), `None` chosen by the data.
    pub fn degree(&self) -> Option<usize> {
        if self.model_auto {
            return None;
        }
        match self.focal_degree {
            None => Some(PAPER_FOCAL_DEGREE),
            Some(FocalDegreeChoice::Degree(d)) => Some(d),
            Some(FocalDegreeChoice::Auto) => None,
        }
    }

    /// The centre asked for: `Some(true)` moving, `Some(false)` fixed (the default), `None`
    /// chosen by the data.
    pub fn moving_centre(&self) -> Option<bool> {
        if self.model_auto {
            return None;
        }
        match self.centre {
            None | Some(CentreChoice::Fixed) => Some(false),
            Some(CentreChoice::Moving) => Some(true),
            Some(CentreChoice::Auto) => None,
        }
    }

    /// The estimator run: the paper's, or errors-in-variables with each prior given or the
    /// paper's ([`Estimator::EIV_PAPER`]: [`Self::input_noise`]).
    pub fn estimator(&self) -> Estimator {
        if self.estimator == Some(EstimatorChoice::Paper) {
            return Estimator::Paper;
        }
        let n = self.input_noise();
        Estimator::Eiv { sigma_z_mm: n.sigma_z_mm, sigma_e_ma: n.sigma_e_ma, sigma_px: n.sigma_px }
    }

    /// The spread of the recorded stage positions and currents the paper estimator's
    /// covariance accounts for: the priors given, or the paper's ([`InputNoise::PAPER`];
    /// the same flags and defaults as errors-in-variables' priors).
    pub fn input_noise(&self) -> InputNoise {
        let p = &self.priors;
        let paper = InputNoise::PAPER;
        InputNoise {
            sigma_z_mm: p.sigma_z.map_or(paper.sigma_z_mm, StageSigma::mm),
            sigma_e_ma: p.sigma_e_ma.unwrap_or(paper.sigma_e_ma),
            sigma_px: p.sigma_px,
        }
    }

    /// The bundle adjustment's options (the layout is the paper's until a model is fixed).
    pub fn options(&self) -> CalibrateOptions {
        CalibrateOptions {
            input_noise: Some(self.input_noise()),
            estimator: self.estimator(),
            hold_a0: self.hold_a0,
            robust: self.robust,
            layout: Layout::PAPER,
            flags: self.flags(),
            setting: etl_formats::SettingKind::Current,
            setting_views: self.setting_views.unwrap_or_default(),
        }
    }

    /// Refuses what no run can honour, in this order: the baseline's unused options (the
    /// bundle adjustment's, then the model's), a focal degree outside 1..=5, an OpenCV
    /// flag with the paper's family, a standard deviation or robust threshold that is not
    /// a finite number > 0. Reads no input.
    pub fn check(&self) -> std::result::Result<(), Refusal> {
        if self.method == Method::PerSetting {
            let bundle_adjustment = [
                (RequestOption::A0, self.a0.is_some()),
                (RequestOption::Estimator, self.estimator.is_some()),
                (RequestOption::HoldA0, self.hold_a0),
                (RequestOption::Robust, self.robust.is_some()),
            ];
            if let Some(&(given, _)) = bundle_adjustment.iter().find(|(_, g)| *g) {
                return Err(Refusal::PerSettingTakesNoBundleAdjustment { given });
            }
            let model = [
                (RequestOption::Model, self.model_auto),
                (RequestOption::Distortion, self.distortion.is_some()),
                (RequestOption::FocalDegree, self.focal_degree.is_some()),
                (RequestOption::Centre, self.centre.is_some()),
                (RequestOption::FixK3, self.fix_k3),
                (RequestOption::ZeroTangent, self.zero_tangent),
            ];
            if let Some(&(given, _)) = model.iter().find(|(_, g)| *g) {
                return Err(Refusal::PerSettingTakesNoModelOption { given });
            }
        }
        self.check_setting_views()?;
        let choices = [
            (RequestOption::Distortion, self.distortion.is_some()),
            (RequestOption::FocalDegree, self.focal_degree.is_some()),
            (RequestOption::Centre, self.centre.is_some()),
        ];
        if let Some(&(given, _)) = choices.iter().find(|(_, g)| self.model_auto && *g) {
            return Err(Refusal::ModelAutoAlone { given });
        }
        if let Some(FocalDegreeChoice::Degree(degree)) = self.focal_degree {
            if !(1..=MAX_FOCAL_DEGREE).contains(&degree) {
                return Err(Refusal::FocalDegreeOutOfRange { degree });
            }
        }
        if self.family() == Some(DistortionModel::Paper) {
            let flags = [(RequestOption::FixK3, self.fix_k3), (RequestOption::ZeroTangent, self.zero_tangent)];
            if let Some(&(flag, _)) = flags.iter().find(|(_, set)| *set) {
                return Err(Refusal::OpenCvFlagNeedsOpenCv {
                    flag,
                    family: RequestOption::Distortion,
                    auto_allowed: true,
                });
            }
        }
        self.check_numbers()
    }

    /// The setting views in the joint solve: not with the per-setting baseline, a robust
    /// loss or a model choice by the data ([`Refusal::JointNotWith`]).
    fn check_setting_views(&self) -> std::result::Result<(), Refusal> {
        if self.setting_views != Some(SettingViews::Joint) {
            return Ok(());
        }
        let conflicts = [
            (RequestOption::Method, self.method == Method::PerSetting),
            (RequestOption::Robust, self.robust.is_some()),
            (RequestOption::Model, self.model_auto),
            (RequestOption::Distortion, self.distortion == Some(DistortionChoice::Auto)),
            (RequestOption::FocalDegree, self.focal_degree == Some(FocalDegreeChoice::Auto)),
            (RequestOption::Centre, self.centre == Some(CentreChoice::Auto)),
        ];
        match conflicts.iter().find(|(_, given)| *given) {
            Some(&(given, _)) => Err(Refusal::JointNotWith { given }),
            None => Ok(()),
        }
    }

    /// The standard deviations and the robust threshold given: finite numbers > 0.
    fn check_numbers(&self) -> std::result::Result<(), Refusal> {
        let p = &self.priors;
        let given = [
            p.sigma_z.map(StageSigma::given),
            p.sigma_e_ma.map(|s| (RequestOption::SigmaEMa, s)),
            p.sigma_p_dpt.map(|s| (RequestOption::SigmaPDpt, s)),
            p.sigma_px.map(|s| (RequestOption::SigmaPx, s)),
            self.robust.map(|r| match r {
                RobustLoss::Huber { k_px } | RobustLoss::Cauchy { k_px } => (RequestOption::RobustKPx, k_px),
            }),
        ];
        for (option, value) in given.into_iter().flatten() {
            positive(option, value)?;
        }
        Ok(())
    }

    /// [`Self::check`], its refusal as bad input in `spelling`'s words.
    pub fn validate(&self, spelling: &dyn Spelling) -> Result<()> {
        self.check().map_err(|r| r.to_error(spelling))
    }

    /// Calibrates `obs` as asked: the per-setting baseline, the proposed method with the
    /// model given, or the model chosen by held-out views (`auto`, with the comparison in
    /// the file's `"model_selection"`); then refuses a result the data do not determine
    /// ([`super::ill_condition`]) unless [`Self::accept_ill_conditioned`].
    ///
    /// Errors: the refusals of [`Self::check`] and those of the data (no lens-off views
    /// with A0 not given, no setting views for the baseline, a view without E_com and no
    /// thermal calibration), in `spelling`'s words; then
    /// those of the pipeline (e.g. fewer than 3 distinct currents); then
    /// [`Refusal::IllConditioned`].
    pub fn run(&self, obs: &Observations, spelling: &dyn Spelling) -> Result<Calibrated> {
        let mut calibrated = self.run_unchecked(obs, spelling)?;
        if let Some(condition) = super::ill_condition(calibrated.calibration()) {
            if !self.accept_ill_conditioned {
                return Err(Refusal::IllConditioned { condition }.to_error(spelling));
            }
            let note = format!(
                "ill-conditioned, kept by {}: {}",
                spelling.switched_on(RequestOption::AcceptIllConditioned),
                condition.describe()
            );
            calibrated.calibration_mut().warnings.insert(0, note);
        }
        Ok(calibrated)
    }

    /// Refuses the options that apply to currents only, for focal-power views
    /// ([`Refusal::NotForFocalPower`]).
    fn check_focal_power(&self) -> std::result::Result<(), Refusal> {
        let current_only = [
            (RequestOption::Thermal, self.thermal.is_some()),
            (RequestOption::Method, self.method == Method::PerSetting),
            (RequestOption::HoldA0, self.hold_a0),
            (RequestOption::SigmaEMa, self.priors.sigma_e_ma.is_some()),
        ];
        match current_only.iter().find(|(_, given)| *given) {
            Some(&(given, _)) => Err(Refusal::NotForFocalPower { given }),
            None => Ok(()),
        }
    }

    /// [`Self::run`] without the conditioning check.
    fn run_unchecked(&self, obs: &Observations, spelling: &dyn Spelling) -> Result<Calibrated> {
        self.validate(spelling)?;
        let setting = obs.setting_kind()?;
        if setting == etl_formats::SettingKind::FocalPower {
            self.check_focal_power().map_err(|r| r.to_error(spelling))?;
        } else if self.priors.sigma_p_dpt.is_some() {
            return Err(Refusal::OnlyForFocalPower.to_error(spelling));
        }
        let thermal = self.thermal.as_ref();
        if thermal.is_none() {
            let without = |views: &[etl_formats::observations::ViewObs]| {
                views.iter().position(|v| v.e_com_ma.is_none() && v.focal_power_dpt.is_none())
            };
            let missing = without(&obs.views).map(|view| (false, view));
            if let Some((setting, view)) = missing.or_else(|| without(&obs.setting_views).map(|view| (true, view))) {
                return Err(Refusal::NoThermal { setting, view }.to_error(spelling));
            }
        }
        if self.method == Method::PerSetting {
            if obs.setting_views.is_empty() {
                return Err(Refusal::NoSettingViews.to_error(spelling));
            }
            return per_setting(obs, thermal).map(|r| Calibrated::PerSetting(Box::new(r)));
        }
        if self.setting_views == Some(SettingViews::Joint) && obs.setting_views.is_empty() {
            return Err(Refusal::JointNeedsSettingViews.to_error(spelling));
        }
        if self.a0.is_none() && obs.offstate_views.is_empty() {
            return Err(Refusal::NoLensOffViews.to_error(spelling));
        }
        let options = self.options().with_setting(setting, self.priors.sigma_p_dpt);
        let result = match (self.family(), self.degree(), self.moving_centre()) {
            (Some(family), Some(degree), Some(moving)) => {
                let layout = Layout::new(family, degree).map_err(Error::Core)?.with_moving_centre(moving);
                let a0 = match self.a0 {
                    Some(a0) => a0,
                    None => a0_from_offstate_with(obs, &ZhangOptions { model: family, flags: self.flags() })?.a0(),
                };
                calibrate(obs, &a0, thermal, &CalibrateOptions { layout, ..options })?
            }
            (family, degree, moving) => {
                let candidates = Candidates {
                    families: family.map_or(DistortionModel::ALL.to_vec(), |f| vec![f]),
                    focal_degrees: degree.map_or((1..=MAX_FOCAL_DEGREE).collect(), |d| vec![d]),
                    centres: moving.map_or(vec![false, true], |m| vec![m]),
                };
                let source = self.a0.map_or(A0Source::Offstate, A0Source::Given);
                select(obs, &source, thermal, &options, &candidates)?
            }
        };
        Ok(Calibrated::Proposed(Box::new(result)))
    }
}
