//! Why a request is refused: one rule per refusal, its message written once and spelled
//! by the front end ([`Spelling`]).

use etl_formats::Error;

use super::conditioning::IllCondition;
use super::option::{RequestOption, Spelling};

/// The options of the bundle adjustment, which the per-setting baseline has no use for,
/// in the order its message lists them.
const BUNDLE_ADJUSTMENT: [RequestOption; 4] =
    [RequestOption::A0, RequestOption::Estimator, RequestOption::HoldA0, RequestOption::Robust];

/// A refused request: the rule broken and the option at fault.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refusal {
    /// The per-setting baseline is Zhang at each current, with no bundle adjustment: an A0,
    /// an estimator (even the default one, given explicitly), hold-A0 or a robust loss
    /// would be silently ignored. `given`: the first of them given.
    PerSettingTakesNoBundleAdjustment {
        /// The option given.
        given: RequestOption,
    },
    /// The per-setting baseline fits the paper's model: a model option would be ignored.
    PerSettingTakesNoModelOption {
        /// The option given.
        given: RequestOption,
    },
    /// An OpenCV flag with the paper's distortion family, which has no k3 and keeps its
    /// decentering terms.
    OpenCvFlagNeedsOpenCv {
        /// The flag given ([`RequestOption::FixK3`] or [`RequestOption::ZeroTangent`]).
        flag: RequestOption,
        /// The option choosing the family ([`RequestOption::Distortion`],
        /// [`RequestOption::Model`]).
        family: RequestOption,
        /// Whether the family may also be chosen by the data (`auto`).
        auto_allowed: bool,
    },
    /// A standard deviation or a robust threshold that is not a finite number > 0 and at
    /// most its [`largest`] value.
    NotPositive {
        /// The option.
        option: RequestOption,
        /// Its value as given.
        value: f64,
    },
    /// A focal degree outside 1..=[`etl_core::model::MAX_FOCAL_DEGREE`].
    FocalDegreeOutOfRange {
        /// The degree given.
        degree: usize,
    },
    /// A0 from Zhang's method on the lens-off views, and the observations have none.
    NoLensOffViews,
    /// The per-setting baseline, and the observations have no setting views.
    NoSettingViews,
    /// A view without a recorded E_com, and no thermal calibration chosen (no surface is
    /// assumed). `setting`: a setting view (else an ETL view); `view`: its index.
    NoThermal {
        /// Whether the view is one of `setting_views` (else of `views`).
        setting: bool,
        /// Its index there.
        view: usize,
    },
    /// Focal-power views (the driver's focal-power mode) with an option that applies to
    /// currents only: a thermal calibration (the driver compensated the temperature), the
    /// per-setting baseline, A0 held (its kf0 is fx at the lens off, not at 0 dpt) or the
    /// current prior (the focal-power prior is in dpt).
    NotForFocalPower {
        /// The option given.
        given: RequestOption,
    },
    /// The focal-power prior given with views at currents.
    OnlyForFocalPower,
    /// `model = auto` beside a choice it makes itself (the distortion family, the focal
    /// degree or the centre).
    ModelAutoAlone {
        /// The option given beside it.
        given: RequestOption,
    },
    /// The setting views in the joint solve, and the observations have none.
    JointNeedsSettingViews,
    /// The setting views in the joint solve with an option it does not go with: the
    /// per-setting baseline (no bundle adjustment), a robust loss (its weights would need
    /// a reference pose per setting view) or a model choice by the data (its held-out
    /// views are stage views: [`RequestOption::Model`], or `auto` of
    /// [`RequestOption::Distortion`], [`RequestOption::FocalDegree`],
    /// [`RequestOption::Centre`]).
    JointNotWith {
        /// The option given.
        given: RequestOption,
    },
    /// A calibration the data do not determine (module `conditioning`), not accepted.
    IllConditioned {
        /// The symptom.
        condition: IllCondition,
    },
}

impl Refusal {
    /// The option the user must change.
    pub fn option(&self) -> RequestOption {
        match *self {
            Refusal::PerSettingTakesNoBundleAdjustment { given } | Refusal::PerSettingTakesNoModelOption { given } => {
                given
            }
            Refusal::OpenCvFlagNeedsOpenCv { flag, .. } => flag,
            Refusal::NotPositive { option, .. } => option,
            Refusal::FocalDegreeOutOfRange { .. } => RequestOption::FocalDegree,
            Refusal::NoLensOffViews => RequestOption::A0,
            Refusal::NoSettingViews => RequestOption::Method,
            Refusal::NoThermal { .. } => RequestOption::Thermal,
            Refusal::NotForFocalPower { given } => given,
            Refusal::OnlyForFocalPower => RequestOption::SigmaPDpt,
            Refusal::ModelAutoAlone { given } => given,
            Refusal::JointNeedsSettingViews => RequestOption::SettingViews,
            Refusal::JointNotWith { given } => given,
            Refusal::IllConditioned { .. } => RequestOption::AcceptIllConditioned,
        }
    }

    /// The one-line message in `spelling`'s vocabulary.
    pub fn message(&self, spelling: &dyn Spelling) -> String {
        let s = spelling;
        let per_setting = || s.with_word(RequestOption::Method, "per-setting");
        match *self {
            Refusal::PerSettingTakesNoBundleAdjustment { .. } => {
                let [a, b, c, d] = BUNDLE_ADJUSTMENT.map(|o| s.name(o));
                format!(
                    "{} takes no {a}, {b}, {c} or {d}: the baseline is Zhang at each current, with no bundle \
                     adjustment; drop them or use the proposed method",
                    per_setting()
                )
            }
            Refusal::PerSettingTakesNoModelOption { given } => format!(
                "{} takes no {}: the baseline fits the paper's model (cubic, paper distortion)",
                per_setting(),
                s.name(given)
            ),
            Refusal::OpenCvFlagNeedsOpenCv { flag, family, auto_allowed } => {
                let mut needs = s.with_word(family, "opencv");
                if auto_allowed {
                    needs = format!("{needs} or {}", s.word("auto"));
                }
                format!(
                    "{} is an OpenCV flag: it needs {needs} (the paper's distortion has no k3 and keeps its \
                     decentering terms)",
                    s.switched_on(flag)
                )
            }
            Refusal::NotPositive { option, .. } => match largest(option) {
                Some((max, unit)) => format!("{} must be positive and finite, at most {max} {unit}", s.name(option)),
                None => format!("{} must be positive and finite", s.name(option)),
            },
            Refusal::FocalDegreeOutOfRange { degree } => format!(
                "{} must be 1..{} or {}, got {degree}",
                s.name(RequestOption::FocalDegree),
                etl_core::model::MAX_FOCAL_DEGREE,
                s.word("auto")
            ),
            Refusal::NoLensOffViews => format!(
                "no lens-off views (offstate_views) in the observations: pass {} (the lens-off intrinsics)",
                s.name(RequestOption::A0)
            ),
            Refusal::NoSettingViews => {
                format!("{} needs setting_views (several board views at each current)", per_setting())
            }
            Refusal::NotForFocalPower { given } => format!(
                "{} does not apply to views at a focal power (focal_power_dpt): {}",
                s.name(given),
                match given {
                    RequestOption::Thermal => "the lens driver compensates the temperature in focal-power mode",
                    RequestOption::Method => "the per-setting baseline takes views at currents",
                    RequestOption::HoldA0 => "A0's kf0 is fx at the lens off, not at 0 dpt, so kf0 is fitted",
                    _ => "the prior on a focal-power view's setting is in dpt",
                }
            ),
            Refusal::ModelAutoAlone { given } => format!(
                "{} chooses the distortion family, the focal degree and the centre itself: drop {}",
                s.with_word(RequestOption::Model, "auto"),
                s.name(given)
            ),
            Refusal::OnlyForFocalPower => format!(
                "{} is the prior on a focal-power view's setting, and these views are at currents: give {} instead",
                s.name(RequestOption::SigmaPDpt),
                s.name(RequestOption::SigmaEMa)
            ),
            Refusal::NoThermal { setting, view } => format!(
                "{} {view} has no e_com_ma and no thermal calibration was chosen: give one ({} with a thermal \
                 calibration, or {} for the paper's surface)",
                if setting { "setting view" } else { "view" },
                s.name(RequestOption::Thermal),
                s.with_word(RequestOption::Thermal, "paper")
            ),
            Refusal::JointNeedsSettingViews => format!(
                "{} needs setting_views (tilted board views at each current) in the observations",
                s.with_word(RequestOption::SettingViews, "joint")
            ),
            Refusal::JointNotWith { given } => {
                let (option, why) = match given {
                    RequestOption::Method => (per_setting(), "the baseline has no bundle adjustment"),
                    RequestOption::Robust => {
                        (s.name(given), "a robust loss would need a reference pose of each setting view")
                    }
                    _ => (
                        s.with_word(given, "auto"),
                        "the held-out model selection scores the stage views alone; choose the model",
                    ),
                };
                format!("{} does not go with {option}: {why}", s.with_word(RequestOption::SettingViews, "joint"))
            }
            Refusal::IllConditioned { condition } => format!(
                "refused: the calibration means nothing, {} ({} keeps it, marked in its warnings)",
                condition.describe(),
                s.switched_on(RequestOption::AcceptIllConditioned)
            ),
        }
    }

    /// The refusal as bad input: `what` the option as `spelling` names it (the
    /// observations' key for the two refusals of data), the value when there is one, and
    /// [`Refusal::message`].
    pub fn to_error(&self, spelling: &dyn Spelling) -> Error {
        let message = self.message(spelling);
        match *self {
            Refusal::NotPositive { option, value } => Error::invalid_value(spelling.name(option), value, message),
            Refusal::FocalDegreeOutOfRange { degree } => {
                Error::invalid_value(spelling.name(RequestOption::FocalDegree), degree, message)
            }
            Refusal::NoLensOffViews => Error::invalid("offstate_views", message),
            Refusal::NoSettingViews | Refusal::JointNeedsSettingViews => Error::invalid("setting_views", message),
            Refusal::NoThermal { setting, view } => {
                let key = if setting { "setting_views" } else { "views" };
                Error::invalid(format!("{key}[{view}].e_com_ma"), message)
            }
            _ => Error::invalid(spelling.name(self.option()), message),
        }
    }
}

/// The largest standard deviation or robust threshold an option takes, and its unit: the
/// simulation's noise caps (docs/RELIABILITY.md), far above any real rig's noise and small
/// enough that a variance and its inverse stay normal floats (a sigma of 1e155 px squared
/// is infinite, and the Cramer-Rao bound it gave was 0).
pub const fn largest(option: RequestOption) -> Option<(f64, &'static str)> {
    match option {
        RequestOption::SigmaZMm => Some((10.0, "mm")),
        RequestOption::SigmaZUm => Some((10_000.0, "um")),
        RequestOption::SigmaEMa => Some((50.0, "mA")),
        RequestOption::SigmaPDpt => Some((5.0, "dpt")),
        RequestOption::SigmaPx | RequestOption::RobustKPx => Some((100.0, "px")),
        _ => None,
    }
}

/// `value` if it is a finite number > 0 and at most its [`largest`], else the refusal
/// naming `option`.
pub fn positive(option: RequestOption, value: f64) -> Result<f64, Refusal> {
    let max = match largest(option) {
        Some((max, _)) => max,
        None => f64::MAX,
    };
    if value > 0.0 && value <= max {
        Ok(value)
    } else {
        Err(Refusal::NotPositive { option, value })
    }
}
