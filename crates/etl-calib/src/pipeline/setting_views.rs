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
//! current. The setting views keep all their points (no outlier screen of their own).

use etl_core::calib::{
    bundle_adjust_free_views, bundle_adjust_free_views_scratch, FreeView, JointScratch, Point, View,
    MIN_FREE_VIEW_POINTS,
};
use etl_core::pnp::solve_pnp;
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
    let start = solved.report.model;
    let mut free = Vec::with_capacity(pts.len());
    for (i, (p, &e)) in pts.iter().zip(&e_com).enumerate() {
        let board: Vec<[f64; 3]> = p.iter().map(|q| q.world_mm).collect();
        let pixels: Vec<[f64; 2]> = p.iter().map(|q| q.pixel).collect();
        let pose = solve_pnp(&start, e, &board, &pixels).map_err(|err| {
            Error::invalid(format!("setting_views[{i}]"), format!("setting view {i}: its start pose by PnP: {err}"))
        })?;
        free.push(FreeView {
            e_com_ma: e,
            points: p,
            rotation_rodrigues: pose.rotation_rodrigues,
            translation_mm: pose.translation_mm,
        });
    }
    let stage_pts = subset(views, &solved.used);
    let stage: Vec<View<'_>> =
        views.iter().zip(&stage_pts).map(|(v, p)| View { e_com_ma: v.e_com_ma, points: p }).collect();
    let mut scratch = vec![JointScratch::ZERO; bundle_adjust_free_views_scratch(stage.len(), free.len())];
    let report = bundle_adjust_free_views(&stage, &free, &start, &options.bundle_adjust()?, &mut scratch)?;
    let corrections: Vec<_> = scratch.iter().take(stage.len()).map(JointScratch::correction).collect();
    let distances_px = distances(&report.model, views, &corrections);
    Ok(Solved { report, corrections, distances_px, ..solved })
}
