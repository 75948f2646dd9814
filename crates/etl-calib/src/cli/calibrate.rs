//! `etlcal calibrate --observations FILE --a0 A0.json --out calibration.json
//! [--estimator paper|eiv] [--hold-a0] [--thermal FILE] [--json]`.
//!
//! Observations (`etlcal.observations/1`) in, `etlcal.calibration/1` out (written
//! atomically; nothing is written on failure). `--json` prints the object written.
//! Without `--a0`, A0 comes from the file's lens-off views by Zhang's method. `--dataset`
//! (images) is not implemented yet, and asking for it is an error that says so.

use std::path::PathBuf;

use etl_core::calib::{Estimator, RobustLoss};
use etl_core::thermal::ThermalCalibration;

use super::print_json;
use crate::error::{Error, Result};
use crate::formats::a0::A0File;
use crate::formats::observations::Observations;
use crate::formats::thermal::ThermalFile;
use crate::pipeline::{calibrate, CalibrateOptions};

/// The bundle adjustment's estimator.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimatorArg {
    /// The paper's Eq. 24: recorded stage positions and currents are exact.
    Paper,
    /// Errors-in-variables: per-view stage/current corrections with Gaussian priors.
    Eiv,
}

/// Arguments of `etlcal calibrate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Corner observations (etlcal.observations/1).
    #[arg(long, value_name = "FILE")]
    pub observations: Option<PathBuf>,
    /// A dataset of images (etlcal.dataset/1): not implemented yet.
    #[arg(long, value_name = "FILE", conflicts_with = "observations")]
    pub dataset: Option<PathBuf>,
    /// Lens-off intrinsics (etlcal.a0/1); default: Zhang's method on the lens-off views.
    #[arg(long, value_name = "FILE")]
    pub a0: Option<PathBuf>,
    /// Where to write etlcal.calibration/1 (its directory must exist).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Bundle-adjustment estimator.
    #[arg(long, value_enum, default_value = "paper")]
    pub estimator: EstimatorArg,
    /// Prior standard deviation of the stage position for --estimator eiv, um.
    #[arg(long, default_value_t = 10.0)]
    pub sigma_z_um: f64,
    /// Prior standard deviation of the current for --estimator eiv, mA.
    #[arg(long, default_value_t = 0.4)]
    pub sigma_e_ma: f64,
    /// Hold A0 (kf0x, kf0y, u0, v0) fixed in the bundle adjustment.
    #[arg(long)]
    pub hold_a0: bool,
    /// Huber loss with this threshold (px) for bad corners.
    #[arg(long, value_name = "PX")]
    pub huber_px: Option<f64>,
    /// Thermal surface (etlcal.thermal/1) for views without e_com_ma (default: the paper's).
    #[arg(long, value_name = "FILE")]
    pub thermal: Option<PathBuf>,
    /// Print the calibration object written, as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Runs `etlcal calibrate`.
pub fn run(args: Args) -> Result<()> {
    if args.dataset.is_some() {
        return Err(Error::InvalidInput(
            "--dataset (images) is not implemented yet: detect corners elsewhere and pass --observations".into(),
        ));
    }
    let obs_path = args
        .observations
        .as_ref()
        .ok_or_else(|| Error::InvalidInput("pass --observations FILE (etlcal.observations/1)".into()))?;
    let obs = Observations::load(obs_path)?;
    let a0 = match &args.a0 {
        Some(p) => A0File::load(p)?.a0(),
        None => crate::pipeline::a0_from_offstate(&obs)?.a0(),
    };
    let thermal = match &args.thermal {
        Some(p) => ThermalFile::load(p)?.calibration(),
        None => ThermalCalibration::PAPER,
    };
    if !(args.sigma_z_um > 0.0 && args.sigma_e_ma > 0.0) {
        return Err(Error::InvalidInput("--sigma-z-um and --sigma-e-ma must be positive".into()));
    }
    let robust = match args.huber_px {
        Some(k) if k > 0.0 => Some(RobustLoss::Huber { k_px: k }),
        Some(_) => return Err(Error::InvalidInput("--huber-px must be positive".into())),
        None => None,
    };
    let estimator = match args.estimator {
        EstimatorArg::Paper => Estimator::Paper,
        EstimatorArg::Eiv => {
            Estimator::Eiv { sigma_z_mm: args.sigma_z_um / 1000.0, sigma_e_ma: args.sigma_e_ma, sigma_px: None }
        }
    };
    let opts = CalibrateOptions { estimator, hold_a0: args.hold_a0, robust };
    let result = calibrate(&obs, &a0, &thermal, &opts)?;
    result.calibration.save(&args.out)?;
    if args.json {
        print_json(&serde_json::to_value(&result.calibration).map_err(|e| Error::InvalidInput(e.to_string()))?);
    } else {
        let c = &result.calibration;
        println!(
            "calibrated {} views: rms {:.4} px (before BA {:.4} px), {} iterations, estimator {}",
            c.views.len(),
            c.rms_reprojection_px,
            c.initial_rms_px,
            c.iterations,
            c.estimator
        );
        println!("wrote {}", args.out.display());
    }
    Ok(())
}
