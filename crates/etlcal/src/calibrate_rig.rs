//! `etlcal calibrate-rig --dataset F --out rig.json [the model flags of calibrate]
//! [--thermal [CAM=]FILE|paper ...] [--camera-flags CAM="FLAGS" ...]
//! [--solver auto|dense|sparse] [--json]`: a multi-camera ETL rig from an
//! `etlcal.rig-dataset/1` (points per camera and view, or images whose boards are first
//! detected by the detection of `calibrate --dataset`,
//! [`etl_calib::rig_calibration::detect_rig`]: a view whose board is not found in one
//! camera's image is dropped for that camera, with a warning), calibrated jointly
//! ([`etl_calib::rig_calibration`]): each camera first by the flags of `calibrate` (the
//! same request), then every camera's numbers together with the shared stage corrections.
//! A camera may have its own request (module `per_camera`): its lens's temperature surface
//! (`--thermal CAM=FILE|paper`; `--thermal FILE|paper` is every other camera's) and its
//! own method, model and bundle-adjustment flags on top of the shared ones
//! (`--camera-flags CAM="--distortion opencv --centre moving"`).
//! Writes `etlcal.rig/1` with each camera's calibration inline and each camera's pose
//! relative to camera 0 with its 6 x 6 covariance, and the joint covariance of every
//! camera's numbers (`joint_covariance`: what `triangulate` propagates, the
//! cross-covariances between the cameras kept) (atomically: nothing is written on
//! failure); prints per camera the RMS, and per pose the rotation and translation with
//! their standard deviations and the baseline. `--json` prints the rig file's object with
//! a `"summary"`.

mod per_camera;

use std::path::PathBuf;

use serde_json::json;

use super::calibrate::RequestFlags;
use super::print_json;
use etl_calib::pipeline::dataset::default_detector;
use etl_calib::rig_calibration::{
    calibrate_rig_spelled, detect_rig, LinearSolver, RigCalibration, RigCalibrationOptions,
};
use etl_formats::output::Output;
use etl_formats::rig_dataset::{RigDataset, ShotKind};
use etl_formats::{Error, Result};

/// The linear solver of `--solver`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverArg {
    /// Dense below 12 cameras, sparse from 12 on (the benchmark's crossover).
    Auto,
    /// nalgebra's dense Cholesky of the Schur complement over all cameras' numbers.
    Dense,
    /// faer's sparse Cholesky of the system bordered by the stage corrections.
    Sparse,
}

/// Arguments of `etlcal calibrate-rig`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The rig's points or images (etlcal.rig-dataset/1).
    #[arg(long, value_name = "FILE")]
    pub dataset: PathBuf,
    /// Where to write etlcal.rig/1 (its directory is created if missing).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// The linear solver of the joint steps [default: auto].
    #[arg(long, value_enum)]
    pub solver: Option<SolverArg>,
    /// Every camera's calibration options (the flags of `calibrate`).
    #[command(flatten)]
    pub request: RequestFlags,
    /// The lenses' temperature surfaces, for views without e_com_ma: `FILE|paper` (an
    /// etlcal.thermal/1 file, or the paper's surface) for every camera without its own,
    /// `CAM=FILE|paper` for camera CAM's lens (CAM its index or name); repeatable. Each
    /// camera whose views record E_in needs one (none is assumed).
    #[arg(long, value_name = "[CAM=]FILE|paper")]
    pub thermal: Vec<String>,
    /// One camera's own calibration flags, CAM="FLAGS" (CAM its index or name; FLAGS the
    /// method, model and bundle-adjustment flags of calibrate, split at white space),
    /// applied on top of the shared ones for that camera; repeatable, once per camera.
    #[arg(long, value_name = "CAM=FLAGS")]
    pub camera_flags: Vec<String>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The summary `--json` adds and the text prints: per camera its RMS, per pose the
/// numbers, their standard deviations and the baseline.
fn summary(rig: &RigCalibration) -> serde_json::Value {
    let cameras: Vec<_> = rig
        .cameras
        .iter()
        .map(|c| {
            json!({"name": c.name, "rms_px": c.rms_px, "own_rms_px": c.own.rms_reprojection_px,
                "request": per_camera::request_summary(&c.request)})
        })
        .collect();
    let poses: Vec<_> = rig
        .extrinsics
        .iter()
        .map(|e| {
            let std: Vec<f64> = e.covariance.map_or(vec![], |c| (0..6).map(|i| c[i][i].max(0.0).sqrt()).collect());
            json!({"camera": e.camera, "rotation_rodrigues": e.rotation_rodrigues, "translation_mm": e.translation_mm,
                "std": std, "baseline_mm": rig.baseline_mm(e.camera)})
        })
        .collect();
    json!({"cameras": cameras, "extrinsics": poses, "estimator": rig.estimator, "iterations": rig.iterations,
        "solver": if rig.sparse { "sparse" } else { "dense" }})
}

/// Prints the summary as text.
fn print_summary(rig: &RigCalibration, out: &std::path::Path) {
    outln!(
        "calibrated {} cameras jointly ({} estimator, {} iterations, {} solver)",
        rig.cameras.len(),
        rig.estimator,
        rig.iterations,
        if rig.sparse { "sparse" } else { "dense" }
    );
    for c in &rig.cameras {
        outln!("  {}: rms {:.4} px (alone {:.4} px)", c.name, c.rms_px, c.own.rms_reprojection_px);
        outln!("    request: {}", per_camera::request_summary(&c.request));
    }
    for e in &rig.extrinsics {
        let c = e.covariance.unwrap_or([[0.0; 6]; 6]);
        let s: Vec<f64> = (0..6).map(|i| c[i][i].max(0.0).sqrt()).collect();
        let (r, t) = (e.rotation_rodrigues, e.translation_mm);
        outln!(
            "  {} from {}: rotation [{:.6}, {:.6}, {:.6}] +- [{:.2e}, {:.2e}, {:.2e}] rad, translation [{:.4}, {:.4}, {:.4}] +- [{:.4}, {:.4}, {:.4}] mm, baseline {:.4} mm",
            rig.cameras[e.camera].name,
            rig.cameras[0].name,
            r[0], r[1], r[2], s[0], s[1], s[2], t[0], t[1], t[2], s[3], s[4], s[5],
            rig.baseline_mm(e.camera).unwrap_or(f64::NAN)
        );
    }
    outln!("wrote {}", out.display());
}

/// The points of `dataset`: its own, or its images' detected corners, each view whose
/// board was not found in a camera's image reported on stderr.
fn detected(dataset: &RigDataset, args: &Args) -> Result<RigDataset> {
    if dataset.shot_kind() == ShotKind::Points {
        return Ok(dataset.clone());
    }
    let bar = crate::progress::Bar::new(!args.json);
    let (points, summary) = detect_rig(dataset, &args.dataset, &default_detector(), &bar)?;
    for (name, camera) in &summary.cameras {
        for s in &camera.skipped {
            eprintln!("etlcal: warning: camera {name}: {} ({} image) skipped: {}", s.image.display(), s.kind, s.reason);
        }
    }
    Ok(points)
}

/// The options of the command line for `dataset`'s cameras: the shared request (with
/// `--thermal FILE`), each camera's own, the solver; checked against the dataset
/// (etl-calib's [`RigCalibrationOptions::check`]) before any detection.
fn rig_options(
    args: &Args,
    dataset: &RigDataset,
    camera_flags: &[per_camera::CameraFlags],
) -> Result<RigCalibrationOptions> {
    let names: Vec<&str> = dataset.cameras.iter().map(|c| c.name.as_str()).collect();
    let surfaces = per_camera::surfaces(&args.thermal, &names)?;
    let request = args.request.request(surfaces.shared.as_deref())?;
    let per_camera = per_camera::camera_requests(&request, camera_flags, &surfaces.per_camera, &names)?;
    let solver = match args.solver.unwrap_or(SolverArg::Auto) {
        SolverArg::Auto => LinearSolver::Auto,
        SolverArg::Dense => LinearSolver::Dense,
        SolverArg::Sparse => LinearSolver::Sparse,
    };
    let options = RigCalibrationOptions { request, solver, max_iterations: 0, per_camera };
    options.check(dataset, &args.request.spelling())?;
    Ok(options)
}

/// Runs `etlcal calibrate-rig`.
pub fn run(args: Args) -> Result<()> {
    let flags = &args.request;
    let camera_flags: Vec<per_camera::CameraFlags> =
        args.camera_flags.iter().map(|v| per_camera::parse_camera_flags(v)).collect::<Result<_>>()?;
    let thermal_files = per_camera::thermal_paths(&args.thermal);
    let a0_files = camera_flags.iter().filter_map(|f| f.flags.a0.as_deref());
    let inputs = [Some(args.dataset.as_path()), flags.a0.as_deref()]
        .into_iter()
        .chain(thermal_files.iter().map(|p| Some(p.as_path())))
        .chain(a0_files.map(Some));
    crate::output::check(inputs, &[Output::File(&args.out)])?;
    let spelling = flags.spelling();
    flags.request(None)?.validate(&spelling)?;
    let dataset = RigDataset::load(&args.dataset)?;
    let options = rig_options(&args, &dataset, &camera_flags)?;
    let dataset = detected(&dataset, &args)?;
    let rig = calibrate_rig_spelled(&dataset, &options, &spelling)?;
    crate::output::create_parent(&args.out)?;
    rig.save(&args.out)?;
    if args.json {
        let mut value = serde_json::to_value(rig.rig_file()).map_err(|e| Error::invalid("--json", e.to_string()))?;
        value["summary"] = summary(&rig);
        print_json(&value);
    } else {
        print_summary(&rig, &args.out);
    }
    Ok(())
}
