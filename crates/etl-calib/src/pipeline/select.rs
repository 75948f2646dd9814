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
//! view's summed error, n_j: its points, weights n_j / N), and its standard error is
//! SE_m = sqrt(K / (K - 1) sum_j (n_j / N)^2 (d_j - D_m)^2) over the K views: paired, so
//! that what every model misses alike cancels. The chosen candidate is the simplest
//! (fewest parameters; then the paper's family, then the lower degree) with D_m <= SE_m:
//! a more flexible model must predict better by more than the noise of the comparison.
//!
//! **What it can tell** (docs/RESULTS.md, "Model selection"): the family, reliably (the
//! paper's on the paper rig and OpenCV's on the strong-distortion rig in every seed tried,
//! 40 and 20); the focal degree less so (the paper's cubic in 36 of 40 seeds of the paper
//! rig, a quartic in the others). A too simple model's misfit m_j against a view's
//! unpredictable part n_j adds m_j^2 + 2 m_j n_j to its held-out error, so the comparison
//! has about half the t-statistic of a likelihood ratio, and a paired standard error over
//! 15 views also measures how uneven the misfit is across views: the quadratic stands at
//! 1.4..2.3 standard errors on the paper rig, and a quartic beats the cubic by more than
//! one standard error by chance in about 1 seed of 10.

use etl_core::calib::jacobian::Projector;
use etl_core::calib::{Estimator, Layout, View, A0};
use etl_core::model::{DistortionModel, OpenCvFlags};
use etl_formats::calibration::ThermalRef;
use etl_formats::model_selection::{ModelCandidate, ModelSelection};
use etl_formats::observations::Observations;
use etl_formats::{Error, Result};
use rayon::prelude::*;

use super::solve::{solve_once, solve_without_outliers, Solved};
use super::{calibration_of, CalibrateOptions, CalibrationResult};
use crate::zhang::ZhangOptions;

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

/// The candidates: every family of `families` with every degree of `focal_degrees`.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidates {
    /// Distortion families tried (the paper's first is the simpler).
    pub families: Vec<DistortionModel>,
    /// Focal degrees tried (1..=5).
    pub focal_degrees: Vec<usize>,
}

/// One candidate's fit to all views, and its held-out errors per view.
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
            let layout = Layout::new(family, degree).map_err(Error::Core)?;
            let options = candidate_options(base, layout);
            let fit = solve_without_outliers(views, &family_a0, &options)
                .map(|solved| Fitted { options, solved })
                .map_err(|e| e.to_string());
            out.push((layout, fit));
        }
    }
    Ok(out)
}

/// The held-out error of view `view` under `model`, over its `scored` points, px^2 (and
/// their count): predicted from the world points and the recorded current and stage
/// position. With the errors-in-variables estimator the recorded stage position and
/// current carry errors (priors sigma_z, sigma_e) that no model predicts: the residual r
/// is then judged by its predictive covariance sigma_px^2 I + J P^-1 J^T (J: d pixels /
/// d (Z_W, E), P = diag(1 / sigma_z^2, 1 / sigma_e^2)), i.e. sigma_px^2 r^T Sigma^-1 r =
/// min over (dZ, dE) of |r + J (dZ, dE)|^2 + sigma_px^2 (dZ^2 / sigma_z^2 + dE^2 / sigma_e^2)
/// (Woodbury; linearised at the recorded values). With the paper's estimator (recorded
/// values exact) it is |r|^2.
fn held_out_error(
    model: &etl_core::model::CameraModel,
    view: &View<'_>,
    scored: &[bool],
    estimator: &Estimator,
    sigma_px: f64,
) -> (f64, usize) {
    let projector = Projector::new(model);
    let (mut rr, mut jtj, mut jtr, mut n) = (0.0, [[0.0; 2]; 2], [0.0; 2], 0);
    for (p, _) in view.points.iter().zip(scored).filter(|(_, &k)| k) {
        n += 1;
        let Ok(q) = projector.project(p.world_mm, view.e_com_ma, true) else {
            rr = f64::INFINITY;
            continue;
        };
        for row in 0..2 {
            let r = q.pixel[row] - p.pixel[row];
            let j = [q.d_z_w[row], q.d_e[row]];
            rr += r * r;
            for a in 0..2 {
                jtr[a] += j[a] * r;
                for b in 0..2 {
                    jtj[a][b] += j[a] * j[b];
                }
            }
        }
    }
    let Estimator::Eiv { sigma_z_mm, sigma_e_ma, .. } = *estimator else {
        return (rr, n);
    };
    if !rr.is_finite() || !(sigma_px > 0.0) {
        return (rr, n);
    }
    // min_d |r + J d|^2 + s^2 d^T P d = r^T r - (J^T r)^T (J^T J + s^2 P)^-1 (J^T r).
    let s2 = sigma_px * sigma_px;
    let a = [
        [jtj[0][0] + s2 / (sigma_z_mm * sigma_z_mm), jtj[0][1]],
        [jtj[1][0], jtj[1][1] + s2 / (sigma_e_ma * sigma_e_ma)],
    ];
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    if !(det > 0.0) {
        return (rr, n);
    }
    let x = [(a[1][1] * jtr[0] - a[0][1] * jtr[1]) / det, (a[0][0] * jtr[1] - a[1][0] * jtr[0]) / det];
    ((rr - jtr[0] * x[0] - jtr[1] * x[1]).max(0.0), n)
}

/// Each view's held-out (sum of squared distances, points) for one fitted candidate.
fn cross_validate(
    views: &[View<'_>],
    fit: &Fitted,
    scored: &[Vec<bool>],
) -> std::result::Result<Vec<(f64, usize)>, String> {
    let mut ba = fit.options.bundle_adjust().map_err(|e| e.to_string())?;
    // The pixel noise is the data's, not the fold's: the full fit's estimate, held (it
    // spares the folds the errors-in-variables rounds that re-estimate it).
    if let Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: None } = ba.estimator {
        ba.estimator = Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: Some(fit.solved.report.sigma_px) };
    }
    (0..views.len())
        .into_par_iter()
        .map(|j| {
            let rest: Vec<View<'_>> = views.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, v)| *v).collect();
            let used: Vec<Vec<bool>> =
                fit.solved.used.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, u)| u.clone()).collect();
            let (report, _) = solve_once(&rest, &used, &fit.solved.report.model, &ba)
                .map_err(|e| format!("with view {j} held out: {e}"))?;
            Ok(held_out_error(&report.model, &views[j], &scored[j], &ba.estimator, report.sigma_px))
        })
        .collect()
}

/// The points scored: all but those every fitted candidate sets aside.
fn scored_points(views: &[View<'_>], fits: &[&Fitted]) -> Vec<Vec<bool>> {
    views
        .iter()
        .enumerate()
        .map(|(j, v)| (0..v.points.len()).map(|i| fits.iter().any(|f| f.solved.used[j][i])).collect())
        .collect()
}

/// The excess of `m` over the best `b` and its paired standard error (module docs), px^2.
fn excess(m: &[(f64, usize)], b: &[(f64, usize)]) -> (f64, f64) {
    let total: usize = m.iter().map(|x| x.1).sum();
    let k = m.iter().filter(|x| x.1 > 0).count();
    if total == 0 || k < 2 {
        return (0.0, 0.0);
    }
    let w = |n: usize| n as f64 / total as f64;
    let d: Vec<(f64, f64)> =
        m.iter().zip(b).filter(|(x, _)| x.1 > 0).map(|(x, y)| (w(x.1), (x.0 - y.0) / x.1 as f64)).collect();
    let mean: f64 = d.iter().map(|(w, d)| w * d).sum();
    let var: f64 = d.iter().map(|(w, d)| w * w * (d - mean).powi(2)).sum::<f64>() * k as f64 / (k - 1) as f64;
    (mean, var.sqrt())
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
    if candidates.families.is_empty() || candidates.focal_degrees.is_empty() {
        return Err(Error::invalid("candidates", "model selection needs at least one family and one focal degree"));
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
    let errors: Vec<std::result::Result<Vec<(f64, usize)>, String>> = fits
        .iter()
        .map(|(_, f)| f.as_ref().map_err(Clone::clone).and_then(|f| cross_validate(&views, f, &scored)))
        .collect();
    let (table, chosen) = table(&fits, &errors)?;
    let fit = fits
        .into_iter()
        .nth(chosen)
        .and_then(|(_, f)| f.ok())
        .ok_or_else(|| Error::invalid("model_selection", "model selection: the chosen candidate has no fit"))?;
    let mut result = calibration_of(obs, &views, fit.solved, thermal, &fit.options)?;
    result.calibration.model_selection = Some(table);
    Ok(result)
}

/// The comparison table and the index of the chosen candidate (module docs' rule).
fn table(
    fits: &[(Layout, std::result::Result<Fitted, String>)],
    errors: &[std::result::Result<Vec<(f64, usize)>, String>],
) -> Result<(ModelSelection, usize)> {
    let mse =
        |e: &[(f64, usize)]| e.iter().map(|x| x.0).sum::<f64>() / e.iter().map(|x| x.1).sum::<usize>().max(1) as f64;
    let ok: Vec<(usize, &Vec<(f64, usize)>)> = errors
        .iter()
        .enumerate()
        .filter_map(|(i, e)| e.as_ref().ok().map(|e| (i, e)))
        .filter(|(_, e)| mse(e).is_finite())
        .collect();
    let best = ok.iter().min_by(|a, b| mse(a.1).total_cmp(&mse(b.1))).map(|(i, _)| *i).ok_or_else(|| {
        let why: Vec<String> = fits
            .iter()
            .zip(errors)
            .filter_map(|((l, _), e)| {
                e.as_ref().err().map(|e| format!("{} degree {}: {e}", l.model().name(), l.focal_degree()))
            })
            .collect();
        Error::invalid("model_selection", format!("model selection: no candidate could be fitted ({})", why.join("; ")))
    })?;
    let best_errors = errors[best].as_ref().map_err(|e| Error::invalid("model_selection", e.clone()))?;
    let simplicity = |l: &Layout| (l.len(), l.model() != DistortionModel::Paper, l.focal_degree());
    let mut chosen = best;
    let mut rows = vec![];
    for (i, ((layout, fit), e)) in fits.iter().zip(errors).enumerate() {
        let mut row = ModelCandidate {
            distortion_model: layout.model().name().into(),
            focal_degree: layout.focal_degree(),
            parameters: layout.len(),
            fit_rms_px: fit.as_ref().ok().map(|f| f.solved.report.rms_px),
            prediction_rms_px: None,
            excess_mse_px2: None,
            excess_se_px2: None,
            chosen: false,
            error: e.as_ref().err().cloned(),
        };
        if let Ok(e) = e {
            let (d, se) = excess(e, best_errors);
            row.prediction_rms_px = Some(mse(e).sqrt());
            row.excess_mse_px2 = Some(d.max(0.0));
            row.excess_se_px2 = Some(se);
            if mse(e).is_finite() && d <= se && simplicity(layout) < simplicity(&fits[chosen].0) {
                chosen = i;
            }
        }
        rows.push(row);
    }
    rows[chosen].chosen = true;
    Ok((ModelSelection { method: METHOD.into(), rule: RULE.into(), candidates: rows }, chosen))
}

/// Refuses OpenCV's flags where they mean nothing: `flags` set while the family is the
/// paper's (`family` None: chosen by the data, which may pick opencv: allowed). The error
/// names the flag as the front end spells it (`names`: fix-k3's, zero-tangent's) and what
/// it needs (`needs`, e.g. `--distortion opencv or auto`).
pub fn refuse_opencv_flags(
    family: Option<DistortionModel>,
    flags: OpenCvFlags,
    names: [&str; 2],
    needs: &str,
) -> Result<()> {
    if family != Some(DistortionModel::Paper) {
        return Ok(());
    }
    match [flags.fix_k3, flags.zero_tangent].iter().position(|&set| set) {
        Some(k) => Err(Error::invalid(
            names[k],
            format!(
                "{} is an OpenCV flag: it needs {needs} (the paper's distortion has no k3 and keeps its decentering terms)",
                names[k]
            ),
        )),
        None => Ok(()),
    }
}
