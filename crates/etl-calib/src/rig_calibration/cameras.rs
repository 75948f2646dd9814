//! The start of the joint solve: each camera calibrated on its own by the single-camera
//! pipeline (the request of `etlcal calibrate`, the rig's or the camera's own), its
//! inlier points kept per rig view.

use etl_core::calib::{Estimator, Layout, ParamMask, Point};
use etl_core::model::CameraModel;
use etl_formats::calibration::ThermalRef;
use etl_formats::observations::Observations;
use etl_formats::rig_dataset::{RigDataset, ShotKind};
use etl_formats::{Error, Result};
use rayon::prelude::*;

use super::options::RigCalibrationOptions;
use crate::pipeline::{CalibrationResult, SettingViews};
use crate::request::{Calibrated, CalibrationRequest, Method, RequestOption, Spelling};

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
    /// The request it was calibrated with.
    pub request: CalibrationRequest,
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

/// Refuses what the joint solve cannot honour: images (it takes points), then the
/// options ([`RigCalibrationOptions::check`]).
fn check_supported(dataset: &RigDataset, options: &RigCalibrationOptions, spelling: &dyn Spelling) -> Result<()> {
    if dataset.shot_kind() == ShotKind::Images {
        return Err(Error::invalid(
            "views",
            "the rig dataset gives images: detect their boards first (etl_calib::rig_calibration::detect_rig), the joint \
             solve takes points",
        ));
    }
    if !dataset.free_views.is_empty() && matches!(options.request.estimator(), Estimator::Paper) {
        return Err(Error::invalid(
            "free_views",
            "free_views: the paper's estimator calibrates each camera alone on the stage; views of the board in free \
             poses tie the cameras through the board's pose: use the errors-in-variables estimator",
        ));
    }
    options.check(dataset, spelling)
}

impl RigCalibrationOptions {
    /// Refuses, before any calibration (a front end calls it before detecting images),
    /// what [`super::calibrate_rig`] cannot honour of these options for `dataset`'s
    /// cameras: a per-camera request naming no camera of the rig, or one camera twice; a
    /// request that is invalid, per setting or robust, or (a camera's own) with another
    /// estimator or stage prior than the rig's, naming the camera; a camera whose views
    /// record E_in without E_com and which has no temperature surface, named. Refusals
    /// are spelt in `spelling`'s words.
    pub fn check(&self, dataset: &RigDataset, spelling: &dyn Spelling) -> Result<()> {
        let names: Vec<&str> = dataset.cameras.iter().map(|c| c.name.as_str()).collect();
        for (i, c) in self.per_camera.iter().enumerate() {
            if !names.contains(&c.camera.as_str()) {
                let message = format!(
                    "per_camera[{i}]: the rig has no camera {:?} (its cameras: {})",
                    c.camera,
                    names.join(", ")
                );
                return Err(Error::invalid_value(format!("per_camera[{i}].camera"), c.camera.as_str(), message));
            }
            if self.per_camera[..i].iter().any(|o| o.camera == c.camera) {
                let message = format!("per_camera[{i}]: camera {:?} is given its own request twice", c.camera);
                return Err(Error::invalid_value(format!("per_camera[{i}].camera"), c.camera.as_str(), message));
            }
        }
        check_request(&self.request, None, spelling)?;
        for (k, name) in names.iter().enumerate() {
            if self.per_camera.iter().any(|c| c.camera == *name) {
                let in_camera = |e: Error| e.within(format!("camera {k} ({name})"), Some(&format!("cameras[{k}]")));
                check_request(self.request_for(name), Some(&self.request), spelling).map_err(in_camera)?;
            }
        }
        check_surfaces(dataset, self, spelling)
    }
}

/// Refuses a camera's request the joint solve cannot honour: an invalid request, the
/// per-setting method, a robust loss; and, for a camera's own request (`shared` the rig's),
/// another estimator or another stage prior than the shared request's: the joint solve
/// has one estimator, and the stage is one physical stage for every camera.
fn check_request(
    request: &CalibrationRequest,
    shared: Option<&CalibrationRequest>,
    spelling: &dyn Spelling,
) -> Result<()> {
    request.validate(spelling)?;
    if request.method == Method::PerSetting {
        return Err(Error::invalid(
            "method",
            "method: a rig is calibrated by the proposed method only, not per setting",
        ));
    }
    if request.robust.is_some() {
        return Err(Error::invalid(
            "robust",
            "robust: the joint solve is least squares (each camera's own calibration has already left its outliers out)",
        ));
    }
    let Some(shared) = shared else { return Ok(()) };
    let kind = |e: Estimator| matches!(e, Estimator::Paper);
    if kind(request.estimator()) != kind(shared.estimator()) {
        let name = spelling.name(RequestOption::Estimator);
        let message =
            format!("{name}: one estimator serves every camera of the rig (the joint solve's): give it once, for all");
        return Err(Error::invalid(name, message));
    }
    if request.input_noise().sigma_z_mm != shared.input_noise().sigma_z_mm {
        let name = spelling.name(RequestOption::SigmaZMm);
        let message = format!(
            "{name}: the stage is one for every camera of the rig: its prior cannot differ per camera (give it once, for all)"
        );
        return Err(Error::invalid(name, message));
    }
    Ok(())
}

/// Refuses a camera whose views record E_in without E_com while its request has no
/// temperature surface (neither the shared one nor its own): none is assumed.
fn check_surfaces(dataset: &RigDataset, options: &RigCalibrationOptions, spelling: &dyn Spelling) -> Result<()> {
    for (k, camera) in dataset.cameras.iter().enumerate() {
        if options.request_for(&camera.name).thermal.is_some() {
            continue;
        }
        let missing = dataset.views.iter().enumerate().find_map(|(j, v)| {
            v.cameras
                .iter()
                .position(|s| s.camera == k && s.e_com_ma.is_none() && s.focal_power_dpt.is_none())
                .map(|c| (j, c))
        });
        if let Some((j, c)) = missing {
            let message = format!(
                "camera {k} ({}): views[{j}].cameras[{c}] records e_in_ma without e_com_ma, and no temperature surface \
                 was given for this camera's lens: give its surface ({} for every camera, or one for camera {:?} alone)",
                camera.name,
                spelling.name(RequestOption::Thermal),
                camera.name
            );
            return Err(Error::invalid(format!("views[{j}].cameras[{c}].e_com_ma"), message));
        }
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
    let request = options.request_for(&name);
    let mut split = dataset.camera_observations(k);
    if request.setting_views == Some(SettingViews::Joint) {
        // The rig's free views are this camera's tilted views: its own calibration, the
        // joint solve's start, then sees a moving centre the stage views alone cannot.
        split.observations.setting_views = dataset.camera_free_views(k).0;
    }
    let obs = &split.observations;
    let in_camera = |e: Error| e.within(format!("camera {k} ({name})"), Some(&format!("cameras[{k}]")));
    let own = match request.run(obs, spelling).map_err(in_camera)? {
        Calibrated::Proposed(r) => *r,
        Calibrated::PerSetting(_) => return Err(Error::invalid("method", "method: per-setting is not a rig method")),
    };
    let e = obs.e_com_ma(request.thermal.as_ref()).map_err(in_camera)?;
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
    views.extend(free_views(dataset, k, request.thermal.as_ref()).map_err(in_camera)?);
    let setting = obs.setting_kind()?;
    let calibrate_options = request.options().with_setting(setting, request.priors.sigma_p_dpt);
    let layout = own.report.model.layout();
    let hold = crate::pipeline::CalibrateOptions { layout, ..calibrate_options }.bundle_adjust()?.hold;
    let sigma_e = match calibrate_options.estimator {
        Estimator::Eiv { sigma_e_ma, .. } => sigma_e_ma,
        Estimator::Paper => calibrate_options.input_noise.map_or(0.0, |n| n.sigma_e_ma),
    };
    let joint = JointCamera { views, start: own.report.model, layout, sigma_px: own.report.sigma_px, sigma_e, hold };
    Ok(CameraPart { own, joint, request: request.clone() })
}

/// Camera `k`'s free views as joint-problem views (rig view index: the stage views', then
/// the free view's), each at its E_com (the request's temperature surface) and with every
/// point (its own calibration has not seen them, so none is an outlier of it).
fn free_views(dataset: &RigDataset, k: usize, thermal: Option<&ThermalRef>) -> Result<Vec<CameraView>> {
    let (free, index) = dataset.camera_free_views(k);
    let size = dataset.cameras[k].image_size;
    free.into_iter()
        .zip(index)
        .map(|(v, f)| {
            let points = v.points.iter().map(|p| Point { world_mm: p.world_mm, pixel: p.pixel }).collect();
            let one = Observations { setting_views: vec![v], ..Observations::new(size) };
            let e = one.setting_e_com_ma(thermal).map_err(|e| {
                Error::invalid(
                    format!("free_views[{f}]"),
                    format!("free_views[{f}]: {}", e.to_string().replace("setting view 0", "its setting")),
                )
            })?;
            Ok(CameraView { view: dataset.views.len() + f, e: e[0], points })
        })
        .collect()
}

/// Every camera calibrated on its own with its request (in parallel: each is its own
/// computation), in the dataset's order. Errors: [`check_supported`]'s, then a camera's
/// that fails, naming it.
pub(super) fn calibrate_cameras(
    dataset: &RigDataset,
    options: &RigCalibrationOptions,
    spelling: &(dyn Spelling + Sync),
) -> Result<Vec<CameraPart>> {
    dataset.validate()?;
    check_supported(dataset, options, spelling)?;
    (0..dataset.cameras.len()).into_par_iter().map(|k| camera_part(dataset, k, options, spelling)).collect()
}
