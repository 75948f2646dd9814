//! The observations' setting views in the bundle adjustment (`calibrate --setting-views
//! joint`, Python `setting_views="joint"`): each a board at one current in a pose of its
//! own, solved together with the stage views
//! ([`etl_core::calib::bundle_adjust_free_views`], docs/METHOD.md "Free-pose views").
//!
//! Why: with one fronto-parallel stage view per current fx(E) and a moving centre's
//! dz(E) trade exactly; tilted boards at each current carry the perspective that tells
//! them apart. The stage views are solved first as without the option (screen, outliers,
//! re-solves); that solution is the start of the joint solve, and each setting view's
//! pose starts at planar PnP ([`etl_core::pnp::solve_pnp`]) through it at the view's
//! current. With a moving centre a second joint solve starts from the linear
//! initialisation with the move held at zero, then released, and the lower objective wins (docs/METHOD.md, "Free-pose views"). The
//! setting views keep all their points (no outlier screen of their own).

use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::calib::{
    bundle_adjust_free_views, bundle_adjust_free_views_scratch, BundleAdjustOptions, BundleAdjustReport, Estimator,
    FreeView, JointScratch, Layout, ParamMask, Point, View, ViewCorrection, MIN_FREE_VIEW_POINTS,
};
use etl_core::model::CameraModel;
use etl_core::pnp::solve_pnp;
use etl_formats::calibration::SettingViewSummary;
use etl_formats::observations::Observations;
use etl_formats::{Error, Result, ThermalRef};

use super::solve::{distances, subset, Solved};
use super::CalibrateOptions;

/// What the bundle adjustment does with the observations' `setting_views`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SettingViews {
    /// Not used (the default, the paper's method): only `--method per-setting` reads them.
    #[default]
    Ignored,
    /// Solved together with the stage views, each in a free pose (module docs).
    Joint,
}

impl SettingViews {
    /// The word of the CLI and Python: `ignored`, `joint`.
    pub const fn word(self) -> &'static str {
        match self {
            SettingViews::Ignored => "ignored",
            SettingViews::Joint => "joint",
        }
    }

    /// The choice of a word ([`Self::word`]), or `None`.
    pub fn from_word(word: &str) -> Option<Self> {
        [SettingViews::Ignored, SettingViews::Joint].into_iter().find(|c| c.word() == word)
    }
}

/// The setting views' points as core points (board frame, Z = 0), each view with at
/// least [`MIN_FREE_VIEW_POINTS`]. Errors: no setting views; a view with fewer points,
/// naming it.
fn setting_points(obs: &Observations) -> Result<Vec<Vec<Point>>> {
    if obs.setting_views.is_empty() {
        return Err(Error::invalid(
            "setting_views",
            "the joint solve with setting views needs setting_views (tilted board views at each current)",
        ));
    }
    obs.setting_views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            if v.points.len() < MIN_FREE_VIEW_POINTS {
                return Err(Error::invalid(
                    format!("setting_views[{i}].points"),
                    format!(
                        "setting view {i} has {} points: its board pose in the joint solve needs at least \
                         {MIN_FREE_VIEW_POINTS}",
                        v.points.len()
                    ),
                ));
            }
            Ok(v.points.iter().map(|p| Point { world_mm: p.world_mm, pixel: p.pixel }).collect())
        })
        .collect()
}

/// Checks the setting views the joint solve needs (before any solve): those of
/// [`setting_points`].
pub(super) fn check_setting_views(obs: &Observations) -> Result<()> {
    setting_points(obs).map(|_| ())
}

/// The joint solve of the stage `views` (the points `solved.used`) and the observations'
/// setting views, from the stage solve `solved` (module docs).
///
/// Errors: those of [`setting_points`]; a setting view PnP cannot place (naming it);
/// those of [`bundle_adjust_free_views`].
pub(super) fn solve_with_setting_views(
    obs: &Observations,
    thermal: Option<&ThermalRef>,
    views: &[View<'_>],
    solved: Solved,
    options: &CalibrateOptions,
) -> Result<Solved> {
    let pts = setting_points(obs)?;
    let e_com = obs.setting_e_com_ma(thermal)?;
    let stage_pts = subset(views, &solved.used);
    let stage: Vec<View<'_>> =
        views.iter().zip(&stage_pts).map(|(v, p)| View { e_com_ma: v.e_com_ma, points: p }).collect();
    let ba = options.bundle_adjust()?;
    let start = solved.report.model;
    let direct = free_views(&pts, &e_com, &start).and_then(|free| joint(&stage, &free, &start, &ba));
    let best = if start.centre.is_none() {
        direct?
    } else {
        // The stage solve's moving centre lies anywhere along the fx(E) ~ dz(E) valley:
        // a joint solve started there can settle in another minimum, and far enough
        // along it a tilted view's PnP puts the board behind the camera. A second start,
        // off the valley: the linear initialisation (the stage solve's own start) with
        // the centre held still while the tilted views fix fx(E), the move released from
        // there. Of the starts that succeed, the lower objective wins (both at the first
        // solve's pixel sigma); the first start's error when neither does.
        match (direct, released_centre(&stage, (&pts, &e_com), &solved.initial, &ba)) {
            (Ok(a), Ok(b)) => {
                let sigma_px = a.report.sigma_px;
                if b.objective(&ba.estimator, sigma_px) < a.objective(&ba.estimator, sigma_px) {
                    b
                } else {
                    a
                }
            }
            (Ok(a), Err(_)) => a,
            (Err(_), Ok(b)) => b,
            (Err(e), Err(_)) => return Err(e),
        }
    };
    let JointSolve { report, corrections, free_poses, .. } = best;
    let distances_px = distances(&report.model, views, &corrections);
    let setting_views = summaries(&report.model, (&pts, &e_com), &free_poses);
    Ok(Solved { report, corrections, distances_px, setting_views, ..solved })
}

/// Each setting view's summary under the calibrated `model`: its pose and correction
/// `poses`, and the RMS distance of its points `pts` reprojected at E_com `e_com` + dE
/// through the model posed by the board (Eq. 24b: the model's own pose replaced by the
/// board's).
fn summaries(
    model: &CameraModel,
    (pts, e_com): (&[Vec<Point>], &[f64]),
    poses: &[FreePose],
) -> Vec<SettingViewSummary> {
    pts.iter()
        .zip(e_com)
        .zip(poses)
        .map(|((p, &e), &(rotation_rodrigues, translation_mm, de_ma))| {
            let posed = CameraModel { rotation_rodrigues, translation_mm, ..*model };
            let view = View { e_com_ma: e, points: p };
            let d = distances(&posed, &[view], &[ViewCorrection { dz_mm: 0.0, de_ma }]).remove(0);
            let rms_px = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
            SettingViewSummary { e_com_ma: e, points: p.len(), rms_px, de_ma, rotation_rodrigues, translation_mm }
        })
        .collect()
}

/// The joint solve from `start` with its centre held still (its move zero) while the tilted
/// views fix fx(E), then released ([`solve_with_setting_views`]).
fn released_centre(
    stage: &[View<'_>],
    (pts, e_com): (&[Vec<Point>], &[f64]),
    start: &CameraModel,
    ba: &BundleAdjustOptions,
) -> Result<JointSolve> {
    let (fixed, hold) = centre_held_still(start);
    let still = BundleAdjustOptions { hold: ba.hold | hold, ..*ba };
    let released = joint(stage, &free_views(pts, e_com, &fixed)?, &fixed, &still)?.report.model;
    joint(stage, &free_views(pts, e_com, &released)?, &released, ba)
}

/// `model` with its centre's move (dz1, dz2, u1, v1) set to zero, and the mask that holds
/// those numbers there.
fn centre_held_still(model: &CameraModel) -> (CameraModel, ParamMask) {
    let layout = Layout::of(model);
    let mut x = to_params(model);
    let mut hold = ParamMask::NONE;
    for span in [layout.centre_dz(), layout.centre_principal_point()] {
        for i in span.start..span.end() {
            x[i] = 0.0;
            hold = hold.with(i);
        }
    }
    (from_params(&layout, &x), hold)
}

/// A free view's board pose (Rodrigues, translation mm: board to camera) and its current
/// correction dE_f, mA.
type FreePose = ([f64; 3], [f64; 3], f64);

/// A joint solve's result.
struct JointSolve {
    report: BundleAdjustReport,
    /// The stage views' corrections (dZ, dE).
    corrections: Vec<ViewCorrection>,
    /// The free views' poses and current corrections.
    free_poses: Vec<FreePose>,
    /// The points of all views.
    points: usize,
}

impl JointSolve {
    /// The objective the solve minimised, at pixel sigma `sigma_px`: the squared
    /// reprojection errors over sigma_px^2 plus, errors-in-variables, each correction's
    /// squared prior z-score (docs/METHOD.md, Eq. 24b-24e).
    fn objective(&self, estimator: &Estimator, sigma_px: f64) -> f64 {
        let JointSolve { report, corrections, free_poses, points } = self;
        let pixels = report.rms_px.powi(2) * *points as f64 / sigma_px.powi(2);
        let Estimator::Eiv { sigma_z_mm, sigma_e_ma, .. } = *estimator else { return pixels };
        let stage: f64 =
            corrections.iter().map(|c| (c.dz_mm / sigma_z_mm).powi(2) + (c.de_ma / sigma_e_ma).powi(2)).sum();
        pixels + stage + free_poses.iter().map(|(_, _, de)| (de / sigma_e_ma).powi(2)).sum::<f64>()
    }
}

/// The joint solve of `stage` and `free` from `start`.
fn joint(
    stage: &[View<'_>],
    free: &[FreeView<'_>],
    start: &CameraModel,
    options: &BundleAdjustOptions,
) -> Result<JointSolve> {
    let mut scratch = vec![JointScratch::ZERO; bundle_adjust_free_views_scratch(stage.len(), free.len())];
    let report = bundle_adjust_free_views(stage, free, start, options, &mut scratch)?;
    let corrections = scratch.iter().take(stage.len()).map(JointScratch::correction).collect();
    let free_poses = scratch.iter().skip(stage.len()).take(free.len()).map(JointScratch::board_pose).collect();
    let points = stage.iter().map(|v| v.points.len()).chain(free.iter().map(|f| f.points.len())).sum();
    Ok(JointSolve { report, corrections, free_poses, points })
}

/// The setting views as free views, each pose started by planar PnP through `start` at
/// its current. Errors: a view PnP cannot place (naming it).
fn free_views<'a>(pts: &'a [Vec<Point>], e_com: &[f64], start: &CameraModel) -> Result<Vec<FreeView<'a>>> {
    let mut free = Vec::with_capacity(pts.len());
    for (i, (p, &e)) in pts.iter().zip(e_com).enumerate() {
        let board: Vec<[f64; 3]> = p.iter().map(|q| q.world_mm).collect();
        let pixels: Vec<[f64; 2]> = p.iter().map(|q| q.pixel).collect();
        let pose = solve_pnp(start, e, &board, &pixels).map_err(|err| {
            Error::invalid(format!("setting_views[{i}]"), format!("setting view {i}: its start pose by PnP: {err}"))
        })?;
        free.push(FreeView {
            e_com_ma: e,
            points: p,
            rotation_rodrigues: pose.rotation_rodrigues,
            translation_mm: pose.translation_mm,
        });
    }
    Ok(free)
}
