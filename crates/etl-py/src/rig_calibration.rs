//! `calibrate_rig`: a multi-camera ETL rig calibrated jointly from an
//! `etlcal.rig-dataset/1` (etl-calib's `rig_calibration`, the run of `etlcal
//! calibrate-rig`), images detected first as the command line does, without the GIL.

use std::path::{Path, PathBuf};

use etl_calib::pipeline::dataset::default_detector;
use etl_calib::request::{CalibrationRequest, RequestOption};
use etl_calib::rig_calibration::{
    calibrate_rig_spelled, detect_rig, CameraRequest, LinearSolver, RigCalibrationOptions,
};
use etl_core::progress::NoProgress;
use etl_formats::rig_dataset::RigDataset;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{input_error, invalid_value, CoreResultExt};
use crate::observations::A0;
use crate::pipeline::{request_of, Keywords};
use crate::rig_runtime::Rig;

/// `solver=`: "auto", "dense" or "sparse".
fn parse_solver(solver: &str) -> PyResult<LinearSolver> {
    match solver {
        "auto" => Ok(LinearSolver::Auto),
        "dense" => Ok(LinearSolver::Dense),
        "sparse" => Ok(LinearSolver::Sparse),
        other => Err(invalid_value(
            "solver",
            other,
            format!("solver must be \"auto\", \"dense\" or \"sparse\", got {other:?}"),
        )),
    }
}

/// The points of the rig dataset at `path`: its own, or its images' detected corners
/// (image paths resolved against it).
fn load(path: &Path) -> etl_formats::Result<RigDataset> {
    let d = RigDataset::load(path)?;
    Ok(detect_rig(&d, path, &default_detector(), &NoProgress)?.0)
}

/// One keyword of a `per_camera` entry: `None` when absent or None, else its value as `T`
/// (refused naming the camera and the keyword).
fn keyword<'py, T>(keywords: &Bound<'py, PyDict>, camera: &str, key: &str) -> PyResult<Option<T>>
where
    for<'a> T: FromPyObject<'a, 'py>,
{
    let Some(v) = keywords.get_item(key)?.filter(|v| !v.is_none()) else { return Ok(None) };
    v.extract::<T>().map(Some).map_err(|_| {
        input_error(format!(
            "per_camera[{camera:?}][{key:?}]: {} is not a value of calibrate's {key}",
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    })
}

/// Camera `camera`'s request: `shared` with the keywords of `keywords` (those of
/// `calibrate(...)`) on top. Raises InputError (a ValueError) naming the camera and the
/// keyword: a key that is not a keyword of `calibrate`, a value it refuses.
fn camera_request(
    shared: &CalibrationRequest,
    camera: &str,
    keywords: &Bound<'_, PyDict>,
) -> PyResult<CalibrationRequest> {
    let mut given = vec![];
    for key in keywords.keys() {
        let key: String =
            key.extract().map_err(|_| input_error(format!("per_camera[{camera:?}]: its keys must be str")))?;
        let option = RequestOption::from_key(&key).ok_or_else(|| {
            let keys: Vec<&str> = RequestOption::ALL.iter().map(|o| o.key()).collect();
            invalid_value(
                "per_camera",
                key.as_str(),
                format!("per_camera[{camera:?}]: {key:?} is not a keyword of calibrate (one of {})", keys.join(", ")),
            )
        })?;
        given.push(option);
    }
    let k = |key| keyword::<String>(keywords, camera, key);
    let f = |key| keyword::<f64>(keywords, camera, key);
    let b = |key| Ok::<bool, PyErr>(keyword::<bool>(keywords, camera, key)?.unwrap_or(false));
    let a0 = keyword::<PyRef<'_, A0>>(keywords, camera, "a0")?;
    let thermal = keywords.get_item("thermal")?.filter(|v| !v.is_none());
    let focal_degree = keywords.get_item("focal_degree")?.filter(|v| !v.is_none());
    let (method, estimator, robust) = (k("method")?, k("estimator")?, k("robust")?);
    let (distortion, centre, model) = (k("distortion")?, k("centre")?, k("model")?);
    let mut own = request_of(
        (
            method.as_deref().unwrap_or("proposed"),
            a0.as_deref(),
            thermal.as_ref(),
            estimator.as_deref(),
            b("hold_a0")?,
            robust.as_deref(),
            f("robust_k_px")?,
        ),
        (f("sigma_z_mm")?, f("sigma_e_ma")?, f("sigma_px")?, f("sigma_z_um")?, f("sigma_p_dpt")?),
        (
            distortion.as_deref(),
            focal_degree.as_ref(),
            b("fix_k3")?,
            b("zero_tangent")?,
            b("accept_ill_conditioned")?,
            centre.as_deref(),
            model.as_deref(),
        ),
    )
    .map_err(|e| input_error(format!("per_camera[{camera:?}]: {}", Python::attach(|py| e.value(py).to_string()))))?;
    // `setting_views` is a keyword of `calibrate` outside `request_of`'s groups: read here
    // too, or a camera's "setting_views" would be accepted and dropped.
    own.setting_views = k("setting_views")?.as_deref().map(crate::pipeline::parse_setting_views).transpose()?;
    Ok(shared.overridden(&own, &given))
}

/// The cameras' own requests of `per_camera` ({camera name: {keyword: value}}).
fn camera_requests(shared: &CalibrationRequest, per_camera: &Bound<'_, PyDict>) -> PyResult<Vec<CameraRequest>> {
    let mut out = vec![];
    for (camera, keywords) in per_camera.iter() {
        let camera: String =
            camera.extract().map_err(|_| input_error("per_camera: its keys must be camera names (str)"))?;
        let keywords = keywords
            .cast::<PyDict>()
            .map_err(|_| input_error(format!("per_camera[{camera:?}] must be a dict of calibrate's keywords")))?;
        let request = camera_request(shared, &camera, keywords)?;
        out.push(CameraRequest { camera, request });
    }
    Ok(out)
}

/// Calibrates a multi-camera ETL rig jointly from an `etlcal.rig-dataset/1` file, as
/// `etlcal calibrate-rig --dataset` does (the same request, the same numbers): each camera
/// first alone with the keywords of `calibrate(...)` (one request for every camera), then
/// every camera's numbers together with one stage correction per view shared by the
/// cameras that saw it. A dataset of images is detected first as `calibrate --dataset`
/// detects (a view whose board is not found in a camera's image is dropped for that
/// camera).
///
/// Args:
///     dataset: the path of the rig dataset (points or images; image paths relative to it).
///     solver: the joint steps' linear solver: "auto" (dense below 12 cameras), "dense"
///         or "sparse".
///     the other keywords: those of `calibrate(...)` (method "proposed" only, no robust
///         loss: the joint solve is least squares), every camera's; `setting_views="joint"`
///         gives each camera's own calibration the rig's free views as tilted views
///         (`calibrate-rig --setting-views joint`).
///     per_camera: each camera's own keywords, {camera name: {keyword: value}} with the
///         keywords of `calibrate(...)`, applied on top of the shared ones for that camera:
///         its lens's temperature surface (`"thermal"`: a `ThermalCalibration` or
///         "paper"), its model (`"distortion"`, `"focal_degree"`, `"centre"`, ...).
///         The estimator and the stage prior are the rig's (a camera's own is refused).
///
/// Returns: the run-time `Rig` (what `Rig.load` gives of the written `etlcal.rig/1`: each
/// camera's `Calibration`, the poses relative to camera 0 with their covariance);
/// `rig.save(path)` writes it.
///
/// Raises: InputError (a ValueError) / FileError in one line naming the input (a missing
/// image, a camera whose board is never found, a bad key of the dataset, an unsupported
/// keyword; a `per_camera` camera the rig does not have or a key that is not a keyword of
/// `calibrate`, named; a camera whose views record E_in with no temperature surface of
/// its own or shared, named).
#[pyfunction]
#[pyo3(signature = (dataset, solver="auto", a0=None, thermal=None, estimator=None, hold_a0=false, robust=None,
    robust_k_px=None, sigma_z_mm=None, sigma_e_ma=None, sigma_px=None, method="proposed",
    distortion=None, focal_degree=None, fix_k3=false, zero_tangent=false, sigma_z_um=None,
    accept_ill_conditioned=false, centre=None, sigma_p_dpt=None, model=None, setting_views=None, per_camera=None))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate_rig(
    py: Python<'_>,
    dataset: PathBuf,
    solver: &str,
    a0: Option<&A0>,
    thermal: Option<&Bound<'_, PyAny>>,
    estimator: Option<&str>,
    hold_a0: bool,
    robust: Option<&str>,
    robust_k_px: Option<f64>,
    sigma_z_mm: Option<f64>,
    sigma_e_ma: Option<f64>,
    sigma_px: Option<f64>,
    method: &str,
    distortion: Option<&str>,
    focal_degree: Option<&Bound<'_, PyAny>>,
    fix_k3: bool,
    zero_tangent: bool,
    sigma_z_um: Option<f64>,
    accept_ill_conditioned: bool,
    centre: Option<&str>,
    sigma_p_dpt: Option<f64>,
    model: Option<&str>,
    setting_views: Option<&str>,
    per_camera: Option<&Bound<'_, PyDict>>,
) -> PyResult<Rig> {
    let solver = parse_solver(solver)?;
    let mut request = request_of(
        (method, a0, thermal, estimator, hold_a0, robust, robust_k_px),
        (sigma_z_mm, sigma_e_ma, sigma_px, sigma_z_um, sigma_p_dpt),
        (distortion, focal_degree, fix_k3, zero_tangent, accept_ill_conditioned, centre, model),
    )?;
    request.setting_views = setting_views.map(crate::pipeline::parse_setting_views).transpose()?;
    request.validate(&Keywords).py()?;
    let per_camera = per_camera.map(|p| camera_requests(&request, p)).transpose()?.unwrap_or_default();
    let options = RigCalibrationOptions { request, solver, max_iterations: 0, per_camera };
    let rig = crate::pool::detach(py, || {
        let points = load(&dataset)?;
        let calibrated = calibrate_rig_spelled(&points, &options, &Keywords)?;
        etl_calib::rig::Rig::from_file(calibrated.rig_file(), dataset.parent().unwrap_or(Path::new(".")))
    })
    .py()?;
    Rig::from_core(py, rig)
}
