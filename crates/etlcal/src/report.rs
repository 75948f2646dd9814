//! `etlcal report --calibration FILE [--observations FILE] [--thermal FILE|paper] --out DIR
//! [--json]`: PNG and SVG figures of a calibration with its uncertainty (fx, fy, k1, p1, p2
//! against current with 1- and 3-sigma bands; the projection-uncertainty map; the
//! distortion field; the correlation matrix; with observations, the coverage per current,
//! residual vectors by view, per-view RMS and a residual histogram) and an index.html that
//! shows them with the parameter table and the provenance (`etl_report::REPORT_FIGURES`).
//!
//! DIR is created if missing (with its missing parents).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::output::write_dir_set;
use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::observations::Observations;
use etl_formats::output::Output;
use etl_formats::Result;
use etl_report::{write_report, Provenance, REPORT_FIGURES};

/// The names a report writes: index.html and each figure as SVG and PNG.
fn report_files() -> Vec<String> {
    let figures = REPORT_FIGURES.iter().flat_map(|(name, _)| [format!("{name}.svg"), format!("{name}.png")]);
    std::iter::once("index.html".to_string()).chain(figures).collect()
}

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
    let written_unix_s = crate::output::source_date_epoch()?;
    let cal = Calibration::load(&args.calibration)?;
    let obs = args.observations.as_deref().map(Observations::load).transpose()?;
    // Views without E_com are compensated by the thermal calibration chosen here, else
    // the one the calibration keeps; none is assumed.
    let chosen = args.thermal.as_deref().map(ThermalRef::choose).transpose()?;
    let thermal = chosen.as_ref().or(cal.thermal.as_ref());
    let mut inputs = vec![("calibration".to_string(), args.calibration.display().to_string())];
    if let Some(o) = &args.observations {
        inputs.push(("observations".to_string(), o.display().to_string()));
    }
    if let Some(t) = &args.thermal {
        inputs.push(("thermal".to_string(), t.display().to_string()));
    }
    // The calibration file does not record the estimator's priors: the report says so.
    let provenance = Provenance { inputs, priors: None, written_unix_s };
    let files = report_files();
    let names: Vec<&str> = files.iter().map(String::as_str).collect();
    // The plots and index.html of one run, swapped in whole (a kill leaves the earlier set).
    let r = write_dir_set(&args.out, &names, |staging| {
        let mut r = write_report(&cal, obs.as_ref(), thermal, &provenance, staging)?;
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
