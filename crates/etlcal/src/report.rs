//! `etlcal report --calibration FILE [--observations FILE] [--thermal FILE|paper] --out DIR
//! [--json]`: PNG and SVG plots of a calibration (fx, fy against current with every
//! view's own estimate; k1, p1, p2 against current; with observations, a residual vector
//! map and a residual histogram) and an index.html that shows them with the numbers.
//!
//! DIR is created if missing (with its missing parents).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::observations::Observations;
use etl_formats::output::{write_dir_set, Output};
use etl_formats::Result;

/// The names a report writes (with observations, the residual plots too).
const REPORT_FILES: &[&str] = &[
    "index.html",
    "focal.png",
    "focal.svg",
    "distortion.png",
    "distortion.svg",
    "residual_map.png",
    "residual_map.svg",
    "residual_hist.png",
    "residual_hist.svg",
];
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
    /// Thermal calibration (etlcal.thermal/1, or `paper`) for views without e_com_ma
    /// (default: the calibration's own; none is assumed).
    #[arg(long, value_name = "FILE")]
    pub thermal: Option<PathBuf>,
    /// Output directory (created with its missing parents).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal report`.
pub fn run(args: Args) -> Result<()> {
    let thermal_file = crate::output::thermal_file(args.thermal.as_deref());
    crate::output::check(
        [Some(args.calibration.as_path()), args.observations.as_deref(), thermal_file],
        &[Output::Dir(&args.out)],
    )?;
    let cal = Calibration::load(&args.calibration)?;
    let obs = args.observations.as_deref().map(Observations::load).transpose()?;
    // Views without E_com are compensated by the thermal calibration chosen here, else
    // the one the calibration keeps; none is assumed.
    let chosen = args.thermal.as_deref().map(ThermalRef::choose).transpose()?;
    let thermal = chosen.as_ref().or(cal.thermal.as_ref());
    // The plots and index.html of one run, swapped in whole (a kill leaves the earlier set).
    let r = write_dir_set(&args.out, REPORT_FILES, |staging| {
        let mut r = write_report(&cal, obs.as_ref(), thermal, staging)?;
        r.files = crate::output::moved(r.files, staging, &args.out);
        Ok(r)
    })?;
    if args.json {
        print_json(&json!({"files": r.files, "text": r.text}));
    } else {
        outln!("wrote {} files to {} (open index.html)", r.files.len(), args.out.display());
    }
    Ok(())
}
