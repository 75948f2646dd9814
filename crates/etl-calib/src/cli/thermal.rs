//! `etlcal thermal ...`: temperature compensation (section 4.1, 5.2.2).
//!
//! - `eval --t C --e-in MA [--thermal FILE]`: E_T and E_com = E_in - E_T with the paper's
//!   surface or a fitted `etlcal.thermal/1` file;
//! - `fit TABLE.csv --out thermal.json`: fits the cubic surface to a table
//!   `temperature_c,e_in_ma,e_t_ma` and writes `etlcal.thermal/1`.
//!
//! Each subcommand is a variant of [`ThermalCommand`] with its own `*Args` struct and
//! `run_*` function; a new one (e.g. `calibrate`) adds a variant and a match arm in
//! [`run`], and may live in its own file.
//!
//! Out-of-range policy (from etl-core): a temperature or current outside the range the
//! surface was fitted over gives a result flagged `"extrapolated": true` (and a warning
//! on stderr in text mode); outside the lens's operating domain (-40..125 degC,
//! +-292.84 mA) it is an error.

use std::path::PathBuf;

use etl_core::thermal::{ThermalCalibration, ThermalFit};
use serde_json::json;

use super::print_json;
use crate::error::{Error, Result};
use crate::formats::thermal::{read_thermal_table, ThermalFile};

/// Arguments of `etlcal thermal`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: ThermalCommand,
}

/// The subcommands of `etlcal thermal`.
#[derive(clap::Subcommand, Debug)]
pub enum ThermalCommand {
    /// E_T(T, E_in) and E_com = E_in - E_T at one temperature and driver current.
    Eval(EvalArgs),
    /// Fit the cubic surface E_T(T, E_in) to a CSV table and write etlcal.thermal/1.
    Fit(FitArgs),
}

/// Arguments of `etlcal thermal eval`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    /// Lens temperature, degC.
    #[arg(long = "t", value_name = "C")]
    pub t_c: f64,
    /// Driver current E_in, mA.
    #[arg(long = "e-in", value_name = "MA")]
    pub e_in_ma: f64,
    /// A fitted surface (etlcal.thermal/1) instead of the paper's.
    #[arg(long, value_name = "FILE")]
    pub thermal: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `etlcal thermal fit`.
#[derive(clap::Args, Debug)]
pub struct FitArgs {
    /// CSV table with header `temperature_c,e_in_ma,e_t_ma`.
    #[arg(value_name = "TABLE.csv")]
    pub table: PathBuf,
    /// Where to write the fitted surface (etlcal.thermal/1); written only on success.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs `etlcal thermal`.
pub fn run(args: Args) -> Result<()> {
    match args.command {
        ThermalCommand::Eval(a) => run_eval(a),
        ThermalCommand::Fit(a) => run_fit(a),
    }
}

/// Runs `etlcal thermal eval`.
pub fn run_eval(args: EvalArgs) -> Result<()> {
    let cal = match &args.thermal {
        Some(path) => ThermalFile::load(path)?.calibration(),
        None => ThermalCalibration::PAPER,
    };
    let c = cal.compensate(args.t_c, args.e_in_ma)?;
    if args.json {
        print_json(&json!({
            "e_t_ma": c.e_t_ma,
            "e_com_ma": c.e_com_ma,
            "extrapolated": c.extrapolated,
            "t_c": args.t_c,
            "e_in_ma": args.e_in_ma,
        }));
    } else {
        if c.extrapolated {
            eprintln!(
                "etlcal: warning: (T, E_in) = ({} degC, {} mA) is outside the fitted ranges {:?} degC x {:?} mA: extrapolated",
                args.t_c, args.e_in_ma, cal.t_range_c, cal.e_in_range_ma
            );
        }
        println!("E_T = {:.6} mA, E_com = {:.6} mA", c.e_t_ma, c.e_com_ma);
    }
    Ok(())
}

/// Runs `etlcal thermal fit`.
pub fn run_fit(args: FitArgs) -> Result<()> {
    let rows = read_thermal_table(&args.table)?;
    // Scale the fit by the table's own ranges when they are not degenerate (the solve
    // reports degenerate tables by name below).
    let (mut t, mut e) = ([f64::INFINITY, f64::NEG_INFINITY], [f64::INFINITY, f64::NEG_INFINITY]);
    for r in &rows {
        t = [t[0].min(r.temperature_c), t[1].max(r.temperature_c)];
        e = [e[0].min(r.e_in_ma), e[1].max(r.e_in_ma)];
    }
    let mut fit = ThermalFit::with_ranges(t, e).unwrap_or_default();
    for (i, r) in rows.iter().enumerate() {
        fit.add(r.temperature_c, r.e_in_ma, r.e_t_ma)
            .map_err(|err| Error::InvalidInput(format!("{}: data row {}: {err}", args.table.display(), i + 1)))?;
    }
    let (cal, rms_ma) = fit
        .solve_calibration()
        .map_err(|err| Error::InvalidInput(format!("{}: cannot fit the surface: {err}", args.table.display())))?;
    let file = ThermalFile::new(&cal, rms_ma);
    file.save(&args.out)?;
    if args.json {
        print_json(&json!({
            "format": file.format,
            "coefficients": file.coefficients,
            "rms_ma": file.rms_ma,
            "t_range_c": file.t_range_c,
            "e_in_range_ma": file.e_in_range_ma,
            "samples": rows.len(),
            "out": args.out.display().to_string(),
        }));
    } else {
        println!(
            "Fitted E_T(T, E_in) to {} samples: RMS {:.4} mA over {:?} degC x {:?} mA; wrote {}",
            rows.len(),
            rms_ma,
            cal.t_range_c,
            cal.e_in_range_ma,
            args.out.display()
        );
    }
    Ok(())
}
