//! Choosing the model by the data (`calibrate --distortion auto`, `--focal-degree auto`):
//! each candidate model (distortion family x focal degree) is judged by how well it
//! predicts views it was not fitted to.
//!
//! **Held-out prediction: leave one view out.** For each ETL view j, the candidate is
//! fitted to the other views (the same estimator, robust loss and A0, started from its
//! fit to all views, with its outliers set aside) and view j's pixels are predicted from
//! its world points and its recorded current and stage position by that fit. Leave one
//! view out rather than k-fold: an ETL calibration has few views (the paper's 15, one per
//! current), each view is one current, and what the candidates differ in is how they carry
//! the focal length and the distortion from one current to the next, which is exactly what
//! predicting a left-out current tests (the end views test extrapolation, where a too
//! flexible polynomial fails first); every view is tested once, and nothing is random. Its
//! cost is one solve per view and candidate, each started near its optimum.
//!
//! **The error of a prediction** is measured in the estimator's own noise model. With
//! the paper's estimator (Eq. 24: recorded stage positions and currents exact) it is the
//! sum of squared pixel distances. With errors-in-variables, a view's recorded stage
//! position and current are off by errors of known spread (the priors sigma_z, sigma_e)
//! that no model can predict; they are the same for every candidate but, squared, they
//! would add to each candidate's misfit a random cross term larger than the differences
//! between candidates (on the paper rig, 0.4 mA is 1.4 px of focal length at 225 mA). The
//! residual r of the view is then judged by its predictive covariance,
//! sigma_px^2 I + J diag(sigma_z^2, sigma_e^2) J^T (J = d pixels / d (Z_W, E)): the error
//! is sigma_px^2 r^T Sigma^-1 r, in px^2. On the paper rig this is
//! what makes the family choice reliable (plain squared distances chose the opencv family
//! in 4 of 20 seeds; this measure in none of 40).
//!
//! **The points scored** are the same for every candidate: all points but those every
//! fitted candidate sets aside as gross outliers (a point only a rigid model misfits is
//! scored: that misfit is the evidence against the model).
//!
//! **The rule: one standard error** (Hastie, Tibshirani, Friedman, *The Elements of
//! Statistical Learning*, 7.10). Let mse_m be candidate m's held-out mean error per point
//! and b the candidate of least mse. Candidate m's excess D_m = mse_m - mse_b is a
//! weighted mean over views of the per-view differences d_j = (S_mj - S_bj) / n_j (S: the
//! view's summed error, n_j: its points, weights n_j / N). The chosen candidate is the
//! simplest (fewest parameters; then the paper's family, then the lower degree) with
//! D_m <= SE_m: a more flexible model must predict better by more than the noise of the
//! comparison. SE_m is the larger of two estimates of that noise:
//! - the spread over views, sqrt(K / (K - 1) sum_j (n_j / N)^2 (d_j - D_m)^2) over the K
//!   views: paired, so that what every model misses alike cancels, and blind to what
//!   the noise model leaves out;
//! - the noise model's, sqrt(sum_j Var(S_mj - S_bj)) / N, each view's variance from its
//!   residual's predictive covariance: its own noise and the uncertainty of b's numbers
//!   fitted to the other views (module `held_out`).
//!
//! Why both: the difference between two polynomials in E is carried by one or two views,
//! the end ones, where they extrapolate; a paired spread over 15 views then measures how
//! uneven the differences are more than how noisy, and a difference carried by a single
//! view stands at one spread whatever its size (at 1.4 for two). With the spread alone a
//! quartic beat the paper rig's cubic by more than one standard error by chance in 6 of
//! 60 seeds (the t-statistic had nowhere to go) and the rule chose it; the noise model
//! scales the standard error with the size of the difference, not its shape.
//!
//! **What it can tell** (docs/RESULTS.md, "Model selection"): the family, reliably (the
//! paper's on the paper rig and OpenCV's on the strong-distortion rig in every seed
//! tried); the focal degree on the paper rig in about 19 of 20 seeds (paper + cubic in 57
//! of seeds 1..60). A held-out error has about half the t-statistic of a likelihood
//! ratio: a too simple model's misfit m_j against a view's unpredictable part n_j adds
//! m_j^2 + 2 m_j n_j to it. On the paper rig the quadratic's excess is 1.1..5 standard
//! errors, and a quartic still beats the cubic by 1.2..2.4 by chance in 1 seed of 20.

mod held_out;
mod rule;

use etl_core::calib::{Layout, View, A0};
use etl_core::model::{DistortionModel, OpenCvFlags};
use etl_formats::calibration::ThermalRef;
use etl_formats::observations::Observations;
use etl_formats::{Error, Result};

use super::centre::undetermined_move;
use super::solve::{solve_without_outliers, Solved};
use super::{calibration_of, CalibrateOptions, CalibrationResult};
use crate::zhang::ZhangOptions;
use held_out::{cross_validate, HeldOut};

/// The `"method"` of the table.
pub const METHOD: &str = "leave-one-view-out";
/// The `"rule"` of the table.
pub const RULE: &str = "one-standard-error";

/// Where each candidate's A0 comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum A0Source {
    /// The same A0 for every candidate (e.g. an `etlcal.a0/1` file).
    Given(A0),
    /// Zhang's method on the observations' lens-off views with the candidate's own
    /// distortion family ([`super::a0_from_offstate_with`]).
    Offstate,
}

/// The candidates: every family of `families` with every degree of `focal_degrees` and
/// every centre of `centres`.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidates {
    /// Distortion families tried (the paper's first is the simpler).
    pub families: Vec<DistortionModel>,
    /// Focal degrees tried (1..=5).
    pub focal_degrees: Vec<usize>,
    /// Centres tried: `false` the fixed centre, `true` the moving one (Eq. C1-C3).
    pub centres: Vec<bool>,
}

impl Candidates {
    /// `families` x `focal_degrees`, each with the fixed centre.
    pub fn fixed_centre(families: Vec<DistortionModel>, focal_degrees: Vec<usize>) -> Self {
        Candidates { families, focal_degrees, centres: vec![false] }
    }
}

/// One candidate's fit to all views.
struct Fitted {
    options: CalibrateOptions,
    solved: Solved,
}

/// The options of candidate `layout`: `base`'s, with OpenCV's flags for the opencv family
/// only (with `auto` they apply to the candidates they mean something for).
fn candidate_options(base: &CalibrateOptions, layout: Layout) -> CalibrateOptions {
    let flags = if layout.model() == DistortionModel::OpenCv { base.flags } else { OpenCvFlags::NONE };
    CalibrateOptions { layout, flags, ..*base }
}

/// Fits every candidate to all views; a candidate that cannot be fitted keeps its error.
fn fit_all(
    obs: &Observations,
    views: &[View<'_>],
    a0: &A0Source,
    base: &CalibrateOptions,
    candidates: &Candidates,
) -> Result<Vec<(Layout, std::result::Result<Fitted, String>)>> {
    let mut out = vec![];
    let a0_of = |family: DistortionModel, flags: OpenCvFlags| -> Result<A0> {
        match a0 {
            A0Source::Given(a) => Ok(*a),
            A0Source::Offstate => Ok(super::a0_from_offstate_with(obs, &ZhangOptions { model: family, flags })?.a0()),
        }
    };
    for &family in &candidates.families {
        let flags = if family == DistortionModel::OpenCv { base.flags } else { OpenCvFlags::NONE };
        let family_a0 = a0_of(family, flags)?;
        for &degree in &candidates.focal_degrees {
            for &moving in &candidates.centres {
                let layout = Layout::new(family, degree).map_err(Error::Core)?.with_moving_centre(moving);
                let options = candidate_options(base, layout);
                let fit =
                    solve_without_outliers(views, &family_a0, &options).map_err(|e| e.to_string()).and_then(|solved| {
                        match undetermined_move(&solved.report.model, &solved.report.covariance, views, options.setting)
                        {
                            // A move the data do not determine is no candidate (module centre).
                            Some(why) => Err(why),
                            None => Ok(Fitted { options, solved }),
                        }
                    });
                out.push((layout, fit));
            }
        }
    }
    Ok(out)
}

/// The points scored: all but those every fitted candidate sets aside.
fn scored_points(views: &[View<'_>], fits: &[&Fitted]) -> Vec<Vec<bool>> {
    views
        .iter()
        .enumerate()
        .map(|(j, v)| (0..v.points.len()).map(|i| fits.iter().any(|f| f.solved.used[j][i])).collect())
        .collect()
}

/// Calibrates with the candidate model that predicts held-out views best by the
/// one-standard-error rule (module docs), and records the comparison in the
/// calibration's `"model_selection"`. `options`' layout is ignored (the candidates give
/// it); its OpenCV flags apply to the opencv candidates.
///
/// Errors: no candidate, or none that could be fitted and cross-validated (the table's
/// errors are then in the message); a lens-off Zhang that fails (with
/// [`A0Source::Offstate`]).
pub fn select(
    obs: &Observations,
    a0: &A0Source,
    thermal: Option<&ThermalRef>,
    options: &CalibrateOptions,
    candidates: &Candidates,
) -> Result<CalibrationResult> {
    obs.validate()?;
    let options = &options.with_setting(obs.setting_kind()?, None);
    if candidates.families.is_empty() || candidates.focal_degrees.is_empty() || candidates.centres.is_empty() {
        return Err(Error::invalid(
            "candidates",
            "model selection needs at least one family, one focal degree and one centre",
        ));
    }
    let e_com = obs.e_com_ma(thermal)?;
    let pts = obs.core_points();
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    if views.len() < 3 {
        return Err(Error::invalid_value(
            "views",
            views.len(),
            format!("model selection holds out one view at a time: it needs at least 3 ETL views, got {}", views.len()),
        ));
    }
    let fits = fit_all(obs, &views, a0, options, candidates)?;
    let fitted: Vec<&Fitted> = fits.iter().filter_map(|(_, f)| f.as_ref().ok()).collect();
    let scored = scored_points(&views, &fitted);
    let held_out: Vec<std::result::Result<Vec<HeldOut>, String>> = fits
        .iter()
        .map(|(_, f)| f.as_ref().map_err(Clone::clone).and_then(|f| cross_validate(&views, f, &scored)))
        .collect();
    let (table, chosen) = rule::table(&fits, &held_out)?;
    let fit = fits
        .into_iter()
        .nth(chosen)
        .and_then(|(_, f)| f.ok())
        .ok_or_else(|| Error::invalid("model_selection", "model selection: the chosen candidate has no fit"))?;
    let mut result = calibration_of(obs, &views, fit.solved, thermal, &fit.options)?;
    result.calibration.model_selection = Some(table);
    Ok(result)
}
