//! The start of the joint solve: each camera calibrated on its own by the single-camera
//! pipeline (the request of `etlcal calibrate`), its inlier points kept per rig view.

use etl_core::calib::{Estimator, Layout, ParamMask, Point};
use etl_core::model::CameraModel;
use etl_formats::observations::Observations;
use etl_formats::rig_dataset::{RigDataset, ShotKind};
use etl_formats::{Error, Result};
use rayon::prelude::*;

use super::options::RigCalibrationOptions;
use crate::pipeline::CalibrationResult;
use crate::request::{Calibrated, Method, Spelling};

/// One camera's view in the joint problem: the rig view it belongs to, its setting (E_com
/// mA, or the focal power dpt) and its inlier points (world X, Y, z_w_mm).
#[derive(Debug, Clone)]
pub(super) struct CameraView {
    pub view: usize,
    pub e: f64,
    pub points: Vec<Point>,
}

/// One camera of the rig: its own calibration and its part of the joint problem.
#[derive(Debug, Clone)]
pub(super) struct CameraPart {
    pub own: CalibrationResult,
    pub joint: JointCamera,
}

/// What the joint problem takes of one camera: its views, its start and its noise.
#[derive(Debug, Clone)]
pub struct JointCamera {
    pub(super) views: Vec<CameraView>,
    pub(super) start: CameraModel,
    pub(super) layout: Layout,
    /// The pixel noise its rows are normalised by (its own solve's, used or estimated), px.
    pub(super) sigma_px: f64,
    /// The prior of its setting corrections (mA or dpt; errors-in-variables only).
    pub(super) sigma_e: f64,
    /// The numbers held at their start.
    pub(super) hold: ParamMask,
}

/// Refuses what the joint solve cannot honour: images (it takes points), the per-setting
/// method, a robust loss.
fn check_supported(dataset: &RigDataset, options: &RigCalibrationOptions) -> Result<()> {
    if dataset.shot_kind() == ShotKind::Images {
        return Err(Error::invalid(
            "views",
            "the rig dataset gives images: detect their boards first (etl_calib::rig_calibration::detect_rig), the joint \
             solve takes points",
        ));
    }
    if options.request.method == Method::PerSetting {
        return Err(Error::invalid(
            "method",
            "method: a rig is calibrated by the proposed method only, not per setting",
        ));
    }
    if !dataset.free_views.is_empty() && matches!(options.request.estimator(), Estimator::Paper) {
        return Err(Error::invalid(
            "free_views",
            "free_views: the paper's estimator calibrates each camera alone on the stage; views of the board in free \
             poses tie the cameras through the board's pose: use the errors-in-variables estimator",
        ));
    }
    if options.request.robust.is_some() {
        return Err(Error::invalid(
            "robust",
            "robust: the joint solve is least squares (each camera's own calibration has already left its outliers out)",
        ));
    }
    Ok(())
}

/// Camera `k` calibrated on its own, with its inlier views. Errors name the camera.
fn camera_part(
    dataset: &RigDataset,
    k: usize,
    options: &RigCalibrationOptions,
    spelling: &dyn Spelling,
) -> Result<CameraPart> {
    let name = dataset.cameras[k].name.clone();
    let split = dataset.camera_observations(k);
    let obs = &split.observations;
    let in_camera = |e: Error| e.within(format!("camera {k} ({name})"), Some(&format!("cameras[{k}]")));
    let own = match options.request.run(obs, spelling).map_err(in_camera)? {
        Calibrated::Proposed(r) => *r,
        Calibrated::PerSetting(_) => return Err(Error::invalid("method", "method: per-setting is not a rig method")),
    };
    let e = obs.e_com_ma(options.request.thermal.as_ref()).map_err(in_camera)?;
    let outliers = &own.calibration.outliers;
    let views = obs
        .views
        .iter()
        .enumerate()
        .map(|(i, v)| CameraView {
            view: split.view_index[i],
            e: e[i],
            points: v
                .points
                .iter()
                .enumerate()
                .filter(|(p, _)| !outliers.iter().any(|o| o.view == i && o.point == *p))
                .map(|(_, p)| Point { world_mm: p.world_mm, pixel: p.pixel })
                .collect(),
        })
        .collect::<Vec<_>>();
    let mut views = views;
    views.extend(free_views(dataset, k, options).map_err(in_camera)?);
    let setting = obs.setting_kind()?;
    let calibrate_options = options.request.options().with_setting(setting, options.request.priors.sigma_p_dpt);
    let layout = own.report.model.layout();
    let hold = crate::pipeline::CalibrateOptions { layout, ..calibrate_options }.bundle_adjust()?.hold;
    let sigma_e = match calibrate_options.estimator {
        Estimator::Eiv { sigma_e_ma, .. } => sigma_e_ma,
        Estimator::Paper => calibrate_options.input_noise.map_or(0.0, |n| n.sigma_e_ma),
    };
    let joint = JointCamera { views, start: own.report.model, layout, sigma_px: own.report.sigma_px, sigma_e, hold };
    Ok(CameraPart { own, joint })
}

/// Camera `k`'s free views as joint-problem views (rig view index: the stage views', then
/// the free view's), each at its E_com (the request's temperature surface) and with every
/// point (its own calibration has not seen them, so none is an outlier of it).
fn free_views(dataset: &RigDataset, k: usize, options: &RigCalibrationOptions) -> Result<Vec<CameraView>> {
    let (free, index) = dataset.camera_free_views(k);
    let size = dataset.cameras[k].image_size;
    free.into_iter()
        .zip(index)
        .map(|(v, f)| {
            let points = v.points.iter().map(|p| Point { world_mm: p.world_mm, pixel: p.pixel }).collect();
            let one = Observations { setting_views: vec![v], ..Observations::new(size) };
            let e = one.setting_e_com_ma(options.request.thermal.as_ref()).map_err(|e| {
                Error::invalid(
                    format!("free_views[{f}]"),
                    format!("free_views[{f}]: {}", e.to_string().replace("setting view 0", "its setting")),
                )
            })?;
            Ok(CameraView { view: dataset.views.len() + f, e: e[0], points })
        })
        .collect()
}

/// Every camera calibrated on its own (in parallel: each is its own computation), in the
/// dataset's order. Errors: [`check_supported`]'s, then the first camera's that fails,
/// naming it.
pub(super) fn calibrate_cameras(
    dataset: &RigDataset,
    options: &RigCalibrationOptions,
    spelling: &(dyn Spelling + Sync),
) -> Result<Vec<CameraPart>> {
    dataset.validate()?;
    check_supported(dataset, options)?;
    options.request.validate(spelling)?;
    (0..dataset.cameras.len()).into_par_iter().map(|k| camera_part(dataset, k, options, spelling)).collect()
}
