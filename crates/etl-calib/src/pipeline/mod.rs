//! The calibration pipeline: dataset (images) or observations (corners) -> E_com through
//! the thermal surface -> A0 (Zhang on the lens-off views, or given) -> RAC -> focal
//! polynomial -> distortion -> bundle adjustment -> `etlcal.calibration/1`.
//!
//! [`calibrate`] starts from observations; [`dataset::observations_from_dataset`] turns a
//! dataset's images into observations first (views whose board is not found are reported
//! and skipped); [`view_focal`] gives each view's own focal-length estimate for reports;
//! [`focus_law`] fits the distance in focus against the current from the views.

pub mod centre;
pub mod dataset;
pub mod focus_law;
pub mod measure;
mod planar_views;
pub mod select;
mod setting_views;
mod solve;
mod view_focal;

pub use planar_views::{detect_views, PlanarViews};
pub use setting_views::SettingViews;
pub use view_focal::view_focal;

use etl_core::calib::{
    BundleAdjustOptions, BundleAdjustReport, Estimator, InputNoise, Layout, ParamMask, RobustLoss, View, A0,
};
use etl_core::model::{CameraModel, OpenCvFlags};

use etl_formats::calibration::{
    Calibration, CovarianceNoise, ModelStd, TemperatureCompensation, ThermalRef, ViewSummary,
};
use etl_formats::observations::Observations;
use etl_formats::{Error, Result, SettingKind};
use rayon::prelude::*;

/// Options of [`calibrate`]. The default is errors-in-variables with the paper's noise
/// levels ([`Estimator::EIV_PAPER`]), no robust loss, A0 free, the paper's model (its
/// distortion family, cubic focal polynomials); [`Estimator::Paper`] is the paper's Eq. 24.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrateOptions {
    /// The estimator of the bundle adjustment (default: [`Estimator::EIV_PAPER`]).
    pub estimator: Estimator,
    /// Hold A0 fixed in the bundle adjustment.
    pub hold_a0: bool,
    /// Robust loss.
    pub robust: Option<RobustLoss>,
    /// The model calibrated: distortion family and focal degree (default
    /// [`Layout::PAPER`]). [`select`] chooses one by held-out views.
    pub layout: Layout,
    /// OpenCV's fix-k3 and zero-tangent flags (the opencv family only; default none).
    pub flags: OpenCvFlags,
    /// The spread of the recorded stage positions and currents that the paper
    /// estimator's covariance accounts for (default: the paper's, [`InputNoise::PAPER`];
    /// [`BundleAdjustOptions::input_noise`]). Errors-in-variables takes its priors instead.
    pub input_noise: Option<InputNoise>,
    /// The views' kind of setting ([`SettingKind`]); [`calibrate`] sets it from the
    /// observations. A focal power fits kf0 ([`etl_core::calib::Kf0::Solved`]) and puts
    /// [`FOCAL_POWER_SIGMA_DPT`] in place of the current's prior.
    pub setting: SettingKind,
    /// What the bundle adjustment does with the observations' `setting_views` (default
    /// [`SettingViews::Ignored`], the paper's method: the stage views alone);
    /// [`SettingViews::Joint`] solves them with the stage views, each in a free pose
    /// (module `setting_views`).
    pub setting_views: SettingViews,
}

/// The prior on a focal-power view's setting, dpt (the errors-in-variables prior, and
/// the spread the paper estimator's covariance accounts for): half of the "typically
/// 0.1 dpt" reproducibility Optotune states for the Lens Driver 4's temperature-compensated
/// focal-power mode over 10-50 degC (MAN16 section 4.3), read as a 2-sigma band.
pub const FOCAL_POWER_SIGMA_DPT: f64 = 0.05;

impl Default for CalibrateOptions {
    fn default() -> Self {
        // Errors-in-variables: under the paper's own noise model it reaches the Cramer-Rao
        // bound where Eq. 24 does not (docs/RESULTS.md).
        CalibrateOptions {
            estimator: Estimator::EIV_PAPER,
            hold_a0: false,
            robust: None,
            layout: Layout::PAPER,
            flags: OpenCvFlags::NONE,
            input_noise: Some(InputNoise::PAPER),
            setting: SettingKind::Current,
            setting_views: SettingViews::Ignored,
        }
    }
}

impl CalibrateOptions {
    /// These options for views of `setting`: a focal power's prior on the setting is
    /// `sigma_p_dpt` or else [`FOCAL_POWER_SIGMA_DPT`] (in the estimator and in the input
    /// noise), a current's is left as it is. Options already for `setting` are kept as
    /// they are (a prior chosen stays).
    pub fn with_setting(&self, setting: SettingKind, sigma_p_dpt: Option<f64>) -> CalibrateOptions {
        let mut o = CalibrateOptions { setting, ..*self };
        if setting == SettingKind::FocalPower && self.setting != SettingKind::FocalPower {
            let sigma = sigma_p_dpt.unwrap_or(FOCAL_POWER_SIGMA_DPT);
            if let Estimator::Eiv { sigma_e_ma, .. } = &mut o.estimator {
                *sigma_e_ma = sigma;
            }
            if let Some(n) = &mut o.input_noise {
                n.sigma_e_ma = sigma;
            }
        }
        o
    }

    /// The bundle adjustment's options: the estimator, the robust loss, and the numbers
    /// held (A0 if asked, and those OpenCV's flags hold). Errors: a flag with the paper
    /// family (naming it).
    pub fn bundle_adjust(&self) -> Result<BundleAdjustOptions> {
        let a0 = if self.hold_a0 { self.layout.a0_mask() } else { ParamMask::NONE };
        let flags = self.layout.opencv_mask(self.flags).map_err(Error::Core)?;
        Ok(BundleAdjustOptions {
            estimator: self.estimator,
            hold: a0 | flags,
            robust: self.robust,
            input_noise: self.input_noise,
            ..BundleAdjustOptions::default()
        })
    }
}

/// The result: the file content and the solver's report.
#[derive(Debug, Clone)]
pub struct CalibrationResult {
    /// What `etlcal calibrate` writes.
    pub calibration: Calibration,
    /// The bundle adjustment's report (covariance included).
    pub report: BundleAdjustReport,
    /// The initial (linear) model.
    pub initial: CameraModel,
    /// Why the calibration has no focus law (`calibration.focus_law` is `None`), e.g. too
    /// few distinct currents; `None` when it has one. Front ends print it as a warning.
    pub focus_law_warning: Option<String>,
}

/// What the covariance accounts for: the pixel noise the solve used or estimated, and the
/// spread of the recorded stage positions and currents (the errors-in-variables priors,
/// or the paper estimator's [`CalibrateOptions::input_noise`]; absent when it is none).
fn covariance_noise(options: &CalibrateOptions, report: &BundleAdjustReport) -> CovarianceNoise {
    let inputs = match options.estimator {
        Estimator::Eiv { sigma_z_mm, sigma_e_ma, .. } => Some((sigma_z_mm, sigma_e_ma)),
        Estimator::Paper => options.input_noise.map(|n| (n.sigma_z_mm, n.sigma_e_ma)),
    };
    CovarianceNoise {
        sigma_px: report.sigma_px,
        sigma_z_mm: inputs.map(|i| i.0),
        sigma_e_ma: inputs.map(|i| i.1),
        sigma_p_dpt: None,
    }
}

/// Refuses an image whose size is not the `expected` one, which `whose` names (e.g. "the
/// dataset says"): corners of another sensor or crop would calibrate a wrong camera.
pub(crate) fn check_image_size(path: &std::path::Path, got: [u32; 2], expected: [u32; 2], whose: &str) -> Result<()> {
    if got == expected {
        return Ok(());
    }
    Err(Error::Image {
        path: path.to_owned(),
        message: format!("the image is {} x {} px, {whose} {} x {}", got[0], got[1], expected[0], expected[1]),
    })
}

/// A0 from the observations' lens-off views by Zhang's method (section 4.2) with the
/// paper's distortion family ([`a0_from_offstate_with`]).
pub fn a0_from_offstate(obs: &Observations) -> Result<crate::zhang::ZhangResult> {
    a0_from_offstate_with(obs, &crate::zhang::ZhangOptions::default())
}

/// A0 from the observations' lens-off views by Zhang's method with the distortion family
/// (and OpenCV's flags) of `options`: the same family as the calibration's, so that a
/// strongly distorting lens does not bias the principal point and focal lengths A0 gives.
///
/// Errors: no lens-off views (pass an A0 file instead), or those of
/// [`crate::zhang::zhang_with`].
pub fn a0_from_offstate_with(
    obs: &Observations,
    options: &crate::zhang::ZhangOptions,
) -> Result<crate::zhang::ZhangResult> {
    if obs.offstate_views.is_empty() {
        return Err(etl_formats::Error::invalid(
            "offstate_views",
            "no lens-off views (offstate_views) in the observations: pass --a0 A0.json",
        ));
    }
    let views: Vec<crate::zhang::PlanarView> = obs
        .offstate_views
        .iter()
        .map(|v| crate::zhang::PlanarView {
            board_mm: v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect(),
            pixels: v.points.iter().map(|p| p.pixel).collect(),
        })
        .collect();
    crate::zhang::zhang_with(&views, obs.image_size, options)
        .map_err(|e| crate::zhang::in_list(e, "offstate_views", None))
}

/// Calibrates from observations with a given A0.
///
/// Errors name the unmet precondition (e.g. fewer than 3 distinct currents).
///
/// ```
/// use etl_calib::pipeline::{calibrate, CalibrateOptions};
/// use etl_sim::simulate::{paper_rig, NoiseModel};
/// use etl_core::calib::Estimator;
/// use etl_formats::ThermalRef;
///
/// let sim = paper_rig(&NoiseModel::PAPER, 1);
/// // The simulated rig's lens follows the paper's surface: chosen explicitly, recorded.
/// let th = ThermalRef::paper();
/// // The default: errors-in-variables, each view's stage and current corrected.
/// let eiv = calibrate(&sim.observations, &sim.a0, Some(&th), &CalibrateOptions::default())?;
/// assert_eq!(eiv.calibration.estimator, "eiv");
/// assert!(eiv.calibration.views.iter().any(|v| v.dz_mm != 0.0));
/// // The paper's Eq. 24: recorded stage positions and currents taken as exact.
/// let opts = CalibrateOptions { estimator: Estimator::Paper, ..CalibrateOptions::default() };
/// let paper = calibrate(&sim.observations, &sim.a0, Some(&th), &opts)?;
/// assert_eq!(paper.calibration.estimator, "paper");
/// let fx_true = sim.truth.focal_lengths(150.0).0;
/// assert!((eiv.report.model.focal_lengths(150.0).0 / fx_true - 1.0).abs() < 0.005);
/// # Ok::<(), etl_calib::Error>(())
/// ```
pub fn calibrate(
    obs: &Observations,
    a0: &A0,
    thermal: Option<&ThermalRef>,
    options: &CalibrateOptions,
) -> Result<CalibrationResult> {
    obs.validate()?;
    if obs.views.is_empty() {
        return Err(etl_formats::Error::invalid(
            "views",
            "no ETL views (views) in the observations: the proposed method needs the board on the stage at >= 3 currents",
        ));
    }
    let options = &options.with_setting(obs.setting_kind()?, None);
    if options.setting_views == SettingViews::Joint {
        setting_views::check_setting_views(obs)?;
    }
    let e_com = obs.e_com_ma(thermal)?;
    let pts = obs.core_points();
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let mut solved = solve::solve_without_outliers(&views, a0, options)?;
    if options.setting_views == SettingViews::Joint {
        solved = setting_views::solve_with_setting_views(obs, thermal, &views, solved, options)?;
    }
    calibration_of(obs, &views, solved, thermal, options)
}

/// Each view's summary under the calibrated `m`: its points in the solve, their RMS
/// distance, its corrections and its own focal lengths ([`view_focal`], from its points
/// in the solve, not its outliers). The views in parallel (rayon): each summary is its
/// own computation, the same whatever the threads.
fn view_summaries(m: &CameraModel, views: &[View<'_>], solved: &solve::Solved) -> Vec<ViewSummary> {
    views
        .par_iter()
        .zip(&solved.corrections)
        .zip(&solved.distances_px)
        .zip(&solved.used)
        .map(|(((v, c), d), used)| {
            let (s, n) = d.iter().zip(used).filter(|&(_, &u)| u).fold((0.0, 0usize), |(s, n), (d, _)| {
                if d.is_finite() {
                    (s + d * d, n + 1)
                } else {
                    (s, n)
                }
            });
            let kept: Vec<_> = v.points.iter().zip(used).filter(|&(_, &u)| u).map(|(p, _)| *p).collect();
            let kept_view = View { e_com_ma: v.e_com_ma, points: &kept };
            let (fx_px, fy_px) = view_focal(m, &kept_view, c.dz_mm).unwrap_or((0.0, 0.0));
            ViewSummary {
                e_com_ma: v.e_com_ma,
                focal_power_dpt: None,
                points: used.iter().filter(|&&u| u).count(),
                rms_px: if n > 0 { (s / n as f64).sqrt() } else { 0.0 },
                dz_mm: c.dz_mm,
                de_ma: c.de_ma,
                de_dpt: None,
                fx_px,
                fy_px,
            }
        })
        .collect()
}

/// The calibration file's content from the solve's result.
fn calibration_of(
    obs: &Observations,
    views: &[View<'_>],
    solved: solve::Solved,
    thermal: Option<&ThermalRef>,
    options: &CalibrateOptions,
) -> Result<CalibrationResult> {
    let (report, initial) = (solved.report, solved.initial);
    let m = report.model;
    let summaries = view_summaries(&m, views, &solved);
    let (focus_law, focus_law_warning) = match focus_law::fit_focus_law(&m, views) {
        Ok(law) => (Some(law), None),
        Err(why) => (None, Some(why)),
    };
    let lo = views.iter().map(|v| v.e_com_ma).fold(f64::INFINITY, f64::min);
    let hi = views.iter().map(|v| v.e_com_ma).fold(f64::NEG_INFINITY, f64::max);
    let mut calibration = Calibration {
        thermal: thermal.cloned(),
        temperature_compensation: TemperatureCompensation::of(thermal),
        rms_reprojection_px: report.rms_px,
        std: ModelStd::from_params(&m.layout(), &report.std),
        estimator: match options.estimator {
            Estimator::Paper => "paper".into(),
            Estimator::Eiv { .. } => "eiv".into(),
        },
        iterations: report.iterations,
        initial_rms_px: report.initial_rms_px,
        views: summaries,
        focus_law,
        ..Calibration::from_model(&m, obs.image_size, [lo, hi])
    };
    calibration.outliers = solved.outliers;
    calibration.setting_views = solved.setting_views;
    calibration.warnings = solve::plausibility_warnings(&calibration, &solved.rounds, options);
    // The covariance of the 25 shared numbers (for errors-in-variables, with the view
    // corrections marginalised out by the solver's Schur complement); std is its diagonal.
    calibration.set_covariance(&report.covariance)?;
    calibration.covariance_noise = Some(covariance_noise(options, &report));
    calibration.warnings.extend(centre::undetermined_move(&m, &report.covariance, views, options.setting));
    if options.setting == SettingKind::FocalPower {
        let t = obs.views.iter().map(|v| v.temperature_c);
        let t_range_c = [t.clone().fold(f64::INFINITY, f64::min), t.fold(f64::NEG_INFINITY, f64::max)];
        calibration = calibration.into_focal_power(Some(t_range_c));
    }
    Ok(CalibrationResult { calibration, report, initial, focus_law_warning })
}
