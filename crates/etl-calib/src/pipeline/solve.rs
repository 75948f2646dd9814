//! The robust solve of [`super::calibrate`]: the homography screen, the linear
//! initialisation on the screened points, the bundle adjustment, the outlier test and the
//! re-solve without the outliers (see [`super::robust`]), and the plausibility warnings.

use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise_model_with, BundleAdjustOptions, BundleAdjustReport, Estimator,
    Kf0, Point, View, ViewCorrection, ViewScratch, A0,
};
use etl_core::model::CameraModel;
use etl_formats::calibration::{Calibration, Outlier, SettingViewSummary};
use etl_formats::{Result, SettingKind};

use rayon::prelude::*;

use super::CalibrateOptions;
use crate::robust::{homography_inliers, outlier_limit_px, OUTLIER_FLOOR_PX, OUTLIER_SIGMAS};

/// Solves after the first at most: the outlier set is re-tested after each solve; when it
/// still changes after this many the last solve stands and a warning says so.
const MAX_RESOLVES: usize = 4;

/// The corner noise, px, the method is specified for (the paper's pixel noise, 0.2 px)
/// and the reference of the RMS warning when the estimator is not given a pixel sigma.
pub const DETECTOR_NOISE_PX: f64 = 0.2;

/// An RMS reprojection error above this many times the pixel noise (the estimator's
/// `sigma_px` if given, else [`DETECTOR_NOISE_PX`]) is reported as implausible.
pub const RMS_NOISE_FACTOR: f64 = 3.0;

/// A view correction (errors-in-variables) above this many prior standard deviations is
/// reported as implausible: the recorded currents or stage positions do not fit the
/// data (e.g. permuted current labels: 11.5 times). Not 3: the estimated corrections
/// carry their own estimation noise, and on clean paper-rig data (seeds 100..139) the
/// stage corrections reached 3.7 times their prior, 3 times in 3 of 40 runs.
pub const PRIOR_FACTOR: f64 = 4.0;

/// What the solve found; `used[j][i]` says whether point i of view j was in the final
/// solve, `distances_px[j][i]` is its reprojection distance under the final model.
pub(super) struct Solved {
    pub report: BundleAdjustReport,
    pub initial: CameraModel,
    pub corrections: Vec<ViewCorrection>,
    pub used: Vec<Vec<bool>>,
    pub distances_px: Vec<Vec<f64>>,
    pub outliers: Vec<Outlier>,
    pub rounds: Rounds,
    /// The setting views as the joint solve left them (`--setting-views joint`; empty
    /// otherwise).
    pub setting_views: Vec<SettingViewSummary>,
}

/// How the outlier iteration went.
pub(super) struct Rounds {
    /// Whether the outlier set stopped changing within [`MAX_RESOLVES`].
    pub converged: bool,
    /// All points.
    pub points: usize,
}

/// The points of `views` where `used` says so.
pub(super) fn subset(views: &[View<'_>], used: &[Vec<bool>]) -> Vec<Vec<Point>> {
    views
        .iter()
        .zip(used)
        .map(|(v, u)| v.points.iter().zip(u).filter(|&(_, &k)| k).map(|(p, _)| *p).collect())
        .collect()
}

/// Each point's reprojection distance, px, under `model` with its view's correction
/// (infinite where the point does not project).
pub(super) fn distances(model: &CameraModel, views: &[View<'_>], corrections: &[ViewCorrection]) -> Vec<Vec<f64>> {
    views
        .iter()
        .zip(corrections)
        .map(|(v, c)| {
            v.points
                .iter()
                .map(|p| {
                    let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + c.dz_mm];
                    match model.project(w, v.e_com_ma + c.de_ma) {
                        Ok(q) => ((q[0] - p.pixel[0]).powi(2) + (q[1] - p.pixel[1]).powi(2)).sqrt(),
                        Err(_) => f64::INFINITY,
                    }
                })
                .collect()
        })
        .collect()
}

/// The homography screen of every view whose points share one Z_W (a board on the
/// stage); other views keep all their points. The views in parallel (rayon): each view's
/// screen is its own deterministic computation, so the result does not depend on the
/// threads, and the 100 LMedS hypotheses per view are a fifth of a calibration's time.
fn screen(views: &[View<'_>]) -> Vec<Vec<bool>> {
    views
        .par_iter()
        .map(|v| {
            let z = v.points.first().map_or(0.0, |p| p.world_mm[2]);
            if v.points.iter().any(|p| p.world_mm[2] != z) {
                return vec![true; v.points.len()];
            }
            let board: Vec<[f64; 2]> = v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect();
            let pixels: Vec<[f64; 2]> = v.points.iter().map(|p| p.pixel).collect();
            homography_inliers(&board, &pixels)
        })
        .collect()
}

/// One bundle adjustment over the `used` points of `views`, from `start`.
pub(super) fn solve_once(
    views: &[View<'_>],
    used: &[Vec<bool>],
    start: &CameraModel,
    ba: &BundleAdjustOptions,
) -> Result<(BundleAdjustReport, Vec<ViewCorrection>)> {
    let pts = subset(views, used);
    let sub: Vec<View<'_>> = views.iter().zip(&pts).map(|(v, p)| View { e_com_ma: v.e_com_ma, points: p }).collect();
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(sub.len())];
    let report = bundle_adjust(&sub, start, ba, &mut scratch)?;
    Ok((report, scratch.iter().map(ViewCorrection::from).collect()))
}

/// The linear initialisation on the screened points, the bundle adjustment, then while
/// the outliers (distance > [`outlier_limit_px`] of all distances) are not
/// the points left out, a new solve from the linear initialisation without them.
///
/// The model is that of `options` (family, focal degree, OpenCV's flags held).
///
/// Errors: those of [`initialise_model`] and [`bundle_adjust`] on the points used.
pub(super) fn solve_without_outliers(views: &[View<'_>], a0: &A0, options: &CalibrateOptions) -> Result<Solved> {
    let ba = &options.bundle_adjust()?;
    let mut used = screen(views);
    let pts = subset(views, &used);
    let sub: Vec<View<'_>> = views.iter().zip(&pts).map(|(v, p)| View { e_com_ma: v.e_com_ma, points: p }).collect();
    let kf0 = match options.setting {
        SettingKind::Current => Kf0::Known([a0.kf0x, a0.kf0y]),
        SettingKind::FocalPower => Kf0::Solved,
    };
    let initial = initialise_model_with(&sub, a0, kf0, options.layout, options.flags)?;
    let mut converged = false;
    let (mut report, mut corrections) = solve_once(views, &used, &initial, ba)?;
    let mut d = distances(&report.model, views, &corrections);
    for round in 0..=MAX_RESOLVES {
        let all: Vec<f64> = d.iter().flatten().copied().collect();
        let limit = outlier_limit_px(&all);
        let inliers: Vec<Vec<bool>> = d.iter().map(|v| v.iter().map(|&x| x <= limit).collect()).collect();
        if inliers == used {
            converged = true;
            break;
        }
        if round == MAX_RESOLVES {
            break;
        }
        used = inliers;
        (report, corrections) = solve_once(views, &used, &initial, ba)?;
        d = distances(&report.model, views, &corrections);
    }
    let mut outliers = vec![];
    for (j, (u, dv)) in used.iter().zip(&d).enumerate() {
        for (i, (&k, &x)) in u.iter().zip(dv).enumerate() {
            if !k {
                outliers.push(Outlier { view: j, point: i, residual_px: if x.is_finite() { x } else { f64::MAX } });
            }
        }
    }
    let points = d.iter().map(Vec::len).sum();
    let rounds = Rounds { converged, points };
    Ok(Solved { report, initial, corrections, used, distances_px: d, outliers, rounds, setting_views: vec![] })
}

/// Sentences saying why `cal` may be implausible (none when it looks sound): outliers
/// found (how many), an outlier iteration that did not settle, an RMS above
/// [`RMS_NOISE_FACTOR`] times the pixel noise, view corrections beyond [`PRIOR_FACTOR`]
/// prior standard deviations.
pub(super) fn plausibility_warnings(cal: &Calibration, rounds: &Rounds, options: &CalibrateOptions) -> Vec<String> {
    let mut w = vec![];
    if !cal.outliers.is_empty() {
        let pct = 100.0 * cal.outliers.len() as f64 / rounds.points.max(1) as f64;
        w.push(format!(
            "{} of {} corners ({pct:.2} %) are outliers (reprojection error > {OUTLIER_SIGMAS} robust sigmas and > {OUTLIER_FLOOR_PX} px) and were left out",
            cal.outliers.len(),
            rounds.points
        ));
    }
    if !rounds.converged {
        w.push(format!("the outlier set still changed after {MAX_RESOLVES} re-solves: the last solve is reported"));
    }
    let (noise, whose) = match options.estimator {
        Estimator::Eiv { sigma_px: Some(s), .. } => (s, "the estimator's sigma_px"),
        _ => (DETECTOR_NOISE_PX, "the detector's nominal noise"),
    };
    if cal.rms_reprojection_px > RMS_NOISE_FACTOR * noise {
        w.push(format!(
            "RMS reprojection error {:.3} px is {:.1} times {whose} ({noise} px): check the corners and the recorded currents",
            cal.rms_reprojection_px,
            cal.rms_reprojection_px / noise
        ));
    }
    if let Estimator::Eiv { sigma_z_mm, sigma_e_ma, .. } = options.estimator {
        let worst = |f: &dyn Fn(&etl_formats::calibration::ViewSummary) -> f64| {
            cal.views.iter().enumerate().map(|(j, v)| (j, f(v).abs())).max_by(|a, b| a.1.total_cmp(&b.1))
        };
        if let Some((j, de)) = worst(&|v| v.de_ma).filter(|&(_, de)| de > PRIOR_FACTOR * sigma_e_ma) {
            let (what, unit, labels) = match options.setting {
                SettingKind::Current => ("current", "mA", "current labels"),
                SettingKind::FocalPower => ("focal-power", "dpt", "recorded focal powers"),
            };
            w.push(format!(
                "the {what} correction of view {j} is {de:.3} {unit}, {:.1} times its prior ({sigma_e_ma} {unit}): are the {labels} right?",
                de / sigma_e_ma
            ));
        }
        if let Some((j, dz)) = worst(&|v| v.dz_mm).filter(|&(_, dz)| dz > PRIOR_FACTOR * sigma_z_mm) {
            w.push(format!(
                "the stage correction of view {j} is {dz:.4} mm, {:.1} times its prior ({sigma_z_mm} mm): are the stage positions right?",
                dz / sigma_z_mm
            ));
        }
    }
    w
}
