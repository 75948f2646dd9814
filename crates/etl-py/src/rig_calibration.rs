//! `calibrate_rig`: a multi-camera ETL rig calibrated jointly from an
//! `etlcal.rig-dataset/1` (etl-calib's `rig_calibration`, the run of `etlcal
//! calibrate-rig`), images detected first as the command line does, without the GIL.

use std::path::{Path, PathBuf};

use etl_calib::pipeline::dataset::default_detector;
use etl_calib::rig_calibration::{calibrate_rig_spelled, detect_rig, LinearSolver, RigCalibrationOptions};
use etl_core::progress::NoProgress;
use etl_formats::rig_dataset::RigDataset;
use pyo3::prelude::*;

use crate::errors::{invalid_value, CoreResultExt};
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
///         loss: the joint solve is least squares).
///
/// Returns: the run-time `Rig` (what `Rig.load` gives of the written `etlcal.rig/1`: each
/// camera's `Calibration`, the poses relative to camera 0 with their covariance);
/// `rig.save(path)` writes it.
///
/// Raises: InputError / FileError in one line naming the input (a missing image, a camera
/// whose board is never found, a bad key of the dataset, an unsupported keyword).
#[pyfunction]
#[pyo3(signature = (dataset, solver="auto", a0=None, thermal=None, estimator=None, hold_a0=false, robust=None,
    robust_k_px=None, sigma_z_mm=None, sigma_e_ma=None, sigma_px=None, method="proposed",
    distortion=None, focal_degree=None, fix_k3=false, zero_tangent=false, sigma_z_um=None,
    accept_ill_conditioned=false, centre=None, sigma_p_dpt=None, model=None))]
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
) -> PyResult<Rig> {
    let solver = parse_solver(solver)?;
    let request = request_of(
        (method, a0, thermal, estimator, hold_a0, robust, robust_k_px),
        (sigma_z_mm, sigma_e_ma, sigma_px, sigma_z_um, sigma_p_dpt),
        (distortion, focal_degree, fix_k3, zero_tangent, accept_ill_conditioned, centre, model),
    )?;
    request.validate(&Keywords).py()?;
    let options = RigCalibrationOptions { request, solver, ..Default::default() };
    let rig = crate::pool::detach(py, || {
        let points = load(&dataset)?;
        let calibrated = calibrate_rig_spelled(&points, &options, &Keywords)?;
        etl_calib::rig::Rig::from_file(calibrated.rig_file(), dataset.parent().unwrap_or(Path::new(".")))
    })
    .py()?;
    Rig::from_core(py, rig)
}
