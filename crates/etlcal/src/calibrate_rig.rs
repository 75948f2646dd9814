//! `etlcal calibrate-rig --dataset F --out rig.json [the model flags of calibrate]
//! [--solver auto|dense|sparse] [--json]`: a multi-camera ETL rig from an
//! `etlcal.rig-dataset/1` (points per camera and view, or images whose boards are first
//! detected by the detection of `calibrate --dataset`,
//! [`etl_calib::rig_calibration::detect_rig`]: a view whose board is not found in one
//! camera's image is dropped for that camera, with a warning), calibrated jointly
//! ([`etl_calib::rig_calibration`]): each camera first by the flags of `calibrate` (the
//! same request), then every camera's numbers together with the shared stage corrections.
//! Writes `etlcal.rig/1` with each camera's calibration inline and each camera's pose
//! relative to camera 0 with its 6 x 6 covariance, and the joint covariance of every
//! camera's numbers (`joint_covariance`: what `triangulate` propagates, the
//! cross-covariances between the cameras kept) (atomically: nothing is written on
//! failure); prints per camera the RMS, and per pose the rotation and translation with
//! their standard deviations and the baseline. `--json` prints the rig file's object with
//! a `"summary"`.

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
        .map(|c| json!({"name": c.name, "rms_px": c.rms_px, "own_rms_px": c.own.rms_reprojection_px}))
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

/// Runs `etlcal calibrate-rig`.
pub fn run(args: Args) -> Result<()> {
    let flags = &args.request;
    let thermal_file = crate::output::thermal_file(flags.thermal.as_deref());
    crate::output::check(
        [Some(args.dataset.as_path()), flags.a0.as_deref(), thermal_file],
        &[Output::File(&args.out)],
    )?;
    let spelling = flags.spelling();
    let request = flags.request()?;
    request.validate(&spelling)?;
    let dataset = detected(&RigDataset::load(&args.dataset)?, &args)?;
    let solver = match args.solver.unwrap_or(SolverArg::Auto) {
        SolverArg::Auto => LinearSolver::Auto,
        SolverArg::Dense => LinearSolver::Dense,
        SolverArg::Sparse => LinearSolver::Sparse,
    };
    let options = RigCalibrationOptions { request, solver, max_iterations: 0 };
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
