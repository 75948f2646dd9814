//! `etlcal report --calibration FILE [--observations FILE] [--thermal FILE] --out DIR
//! [--json]`: PNG and SVG plots of a calibration (fx, fy against current with every
//! view's own estimate; k1, p1, p2 against current; with observations, a residual vector
//! map and a residual histogram) and an index.html that shows them with the numbers.
//!
//! DIR is created if missing; its parent must exist.

use std::path::PathBuf;

use etl_core::thermal::ThermalCalibration;
use serde_json::json;

use super::print_json;
use etl_formats::calibration::Calibration;
use etl_formats::observations::Observations;
use etl_formats::thermal::ThermalFile;
use etl_formats::{Error, Result};
use etl_report::write_report;

/// Arguments of `etlcal report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The calibration (etlcal.calibration/1).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The observations it was made from (etlcal.observations/1), for the residual plots.
    #[arg(long, value_name = "FILE")]
    pub observations: Option<PathBuf>,
    /// Thermal surface (etlcal.thermal/1) for views without e_com_ma (default: the
    /// calibration's own, else the paper's).
    #[arg(long, value_name = "FILE")]
    pub thermal: Option<PathBuf>,
    /// Output directory (created if missing; its parent must exist).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print the files written as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Creates `dir` if missing, refusing when its parent does not exist.
pub fn ensure_out_dir(dir: &std::path::Path) -> Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    };
    if !parent.is_dir() {
        return Err(Error::Io {
            path: dir.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the parent directory does not exist"),
        });
    }
    std::fs::create_dir(dir).map_err(|source| Error::Io { path: dir.to_owned(), source })
}

/// Runs `etlcal report`.
pub fn run(args: Args) -> Result<()> {
    let cal = Calibration::load(&args.calibration)?;
    let obs = args.observations.as_deref().map(Observations::load).transpose()?;
    let thermal = match &args.thermal {
        Some(p) => ThermalFile::load(p)?.calibration(),
        None => ThermalCalibration { surface: cal.thermal_surface()?, ..ThermalCalibration::PAPER },
    };
    ensure_out_dir(&args.out)?;
    let r = write_report(&cal, obs.as_ref(), &thermal, &args.out)?;
    if args.json {
        print_json(&json!({"files": r.files, "text": r.text}));
    } else {
        outln!("wrote {} files to {} (open index.html)", r.files.len(), args.out.display());
    }
    Ok(())
}
