//! The options of a request, as stable keys, and how a front end spells them.
//!
//! A refusal names the option the user must change. The CLI says `--hold-a0`, Python
//! `hold_a0`: the request carries the option as a [`RequestOption`] and each front end
//! turns it into its own words through a [`Spelling`], so that one rule gives the same
//! message in both, each in the user's vocabulary.

/// An option of a [`super::CalibrationRequest`] or a [`super::ZhangRequest`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RequestOption {
    /// The method: the paper's (proposed) or the per-setting baseline.
    Method,
    /// The lens-off intrinsics A0, given (else Zhang's method on the lens-off views).
    A0,
    /// The thermal calibration for views without a recorded E_com.
    Thermal,
    /// The bundle adjustment's estimator.
    Estimator,
    /// The errors-in-variables prior on the stage position, given in mm.
    SigmaZMm,
    /// The errors-in-variables prior on the stage position, given in um.
    SigmaZUm,
    /// The errors-in-variables prior on the current, mA.
    SigmaEMa,
    /// The errors-in-variables prior on a focal-power view's setting, dpt.
    SigmaPDpt,
    /// The errors-in-variables pixel noise, px.
    SigmaPx,
    /// Hold A0 in the bundle adjustment.
    HoldA0,
    /// The robust loss.
    Robust,
    /// The robust loss's threshold / scale, px.
    RobustKPx,
    /// The calibration's distortion family (or `auto`).
    Distortion,
    /// The degree of fx(E), fy(E) (or `auto`).
    FocalDegree,
    /// OpenCV's `CALIB_FIX_K3`.
    FixK3,
    /// OpenCV's `CALIB_ZERO_TANGENT_DIST`.
    ZeroTangent,
    /// Zhang's distortion family; for a calibration, `auto`: every model choice to the
    /// data.
    Model,
    /// Keep a calibration the data do not determine (marked in its warnings).
    AcceptIllConditioned,
    /// The projection centre: fixed, moving with the setting, or `auto`.
    Centre,
    /// What the bundle adjustment does with the setting views (`ignored`, `joint`).
    SettingViews,
}

impl RequestOption {
    /// Every option, in the order of the enum.
    pub const ALL: [RequestOption; 20] = [
        RequestOption::Method,
        RequestOption::A0,
        RequestOption::Thermal,
        RequestOption::Estimator,
        RequestOption::SigmaZMm,
        RequestOption::SigmaZUm,
        RequestOption::SigmaEMa,
        RequestOption::SigmaPDpt,
        RequestOption::SigmaPx,
        RequestOption::HoldA0,
        RequestOption::Robust,
        RequestOption::RobustKPx,
        RequestOption::Distortion,
        RequestOption::FocalDegree,
        RequestOption::FixK3,
        RequestOption::ZeroTangent,
        RequestOption::Model,
        RequestOption::AcceptIllConditioned,
        RequestOption::Centre,
        RequestOption::SettingViews,
    ];

    /// The option whose [`Self::key`] is `key`, or `None`.
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|o| o.key() == key)
    }

    /// The stable key: the option's name in snake case (`"hold_a0"`), which is Python's
    /// argument and, with dashes, the CLI's flag.
    pub const fn key(self) -> &'static str {
        match self {
            RequestOption::Method => "method",
            RequestOption::A0 => "a0",
            RequestOption::Thermal => "thermal",
            RequestOption::Estimator => "estimator",
            RequestOption::SigmaZMm => "sigma_z_mm",
            RequestOption::SigmaZUm => "sigma_z_um",
            RequestOption::SigmaEMa => "sigma_e_ma",
            RequestOption::SigmaPDpt => "sigma_p_dpt",
            RequestOption::SigmaPx => "sigma_px",
            RequestOption::HoldA0 => "hold_a0",
            RequestOption::Robust => "robust",
            RequestOption::RobustKPx => "robust_k_px",
            RequestOption::Distortion => "distortion",
            RequestOption::FocalDegree => "focal_degree",
            RequestOption::FixK3 => "fix_k3",
            RequestOption::ZeroTangent => "zero_tangent",
            RequestOption::Model => "model",
            RequestOption::AcceptIllConditioned => "accept_ill_conditioned",
            RequestOption::Centre => "centre",
            RequestOption::SettingViews => "setting_views",
        }
    }
}

/// How a front end writes options in its messages. Every method has the front end's
/// vocabulary: the CLI `--distortion opencv`, Python `distortion="opencv"`.
pub trait Spelling {
    /// The option's name: `--hold-a0` (CLI), `hold_a0` (Python).
    fn name(&self, option: RequestOption) -> String;
    /// A word of a choice as a value: `auto` (CLI), `"auto"` (Python).
    fn word(&self, word: &str) -> String;
    /// The option set to a word: `--method per-setting`, `method="per-setting"`.
    fn with_word(&self, option: RequestOption, word: &str) -> String;
    /// A switch turned on: `--fix-k3`, `fix_k3=True`.
    fn switched_on(&self, option: RequestOption) -> String;
}

/// The stable keys as they are, for Rust callers (the request's own field names):
/// `hold_a0`, `distortion = opencv`, `fix_k3 = true`.
#[derive(Debug, Clone, Copy, Default)]
pub struct KeySpelling;

impl Spelling for KeySpelling {
    fn name(&self, option: RequestOption) -> String {
        option.key().to_owned()
    }
    fn word(&self, word: &str) -> String {
        word.to_owned()
    }
    fn with_word(&self, option: RequestOption, word: &str) -> String {
        format!("{} = {word}", option.key())
    }
    fn switched_on(&self, option: RequestOption) -> String {
        format!("{} = true", option.key())
    }
}
