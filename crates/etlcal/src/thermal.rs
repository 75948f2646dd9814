//! `etlcal thermal ...`: temperature compensation (section 4.1, 5.2.2).
//!
//! - `eval --e-in MA --t C [--thermal FILE]`: E_T and E_com = E_in - E_T with the paper's
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

use etl_core::runtime::ThermalTrust;
use etl_core::thermal::Compensation;
use serde_json::json;

use super::print_json;
use etl_formats::calibration::ThermalRef;
use etl_formats::output::Output;
use etl_formats::thermal::{read_thermal_table, ThermalFile};
use etl_formats::{compact, Error, Result};

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
    /// The temperature-calibration procedure (section 4.1) against the virtual lens and the
    /// synthetic camera: refocus at every temperature step, fit, write the surface and table.
    Calibrate(CalibrateArgs),
}

/// Arguments of `etlcal thermal calibrate`.
#[derive(clap::Args, Debug)]
pub struct CalibrateArgs {
    /// Run against the virtual lens (on a pseudo-terminal, through the real client) and the
    /// synthetic camera. Required: a real rig needs a camera binding (from Python or Rust).
    #[arg(long, required = true)]
    pub r#virtual: bool,
    /// The virtual lens's dynamics (`etlcal.lens-dynamics/1`); without it the optics
    /// follow the current at once.
    #[arg(long, value_name = "FILE")]
    pub dynamics: Option<PathBuf>,
    /// How long the camera waits for the lens to settle before each frame, ms (model time;
    /// 0..=10000). With dynamics, a frame taken too early sees the lens still moving.
    #[arg(long, default_value_t = 0.0, value_name = "MS")]
    pub settle_ms: f64,
    /// Where to write the fitted surface (etlcal.thermal/1; its directory is created if
    /// missing).
    #[arg(long, value_name = "thermal.json")]
    pub out: PathBuf,
    /// Where to write the raw table (CSV `temperature_c,e_in_ma,e_t_ma`; default: beside
    /// --out, with .csv; its directory is created if missing).
    #[arg(long, value_name = "TABLE.csv")]
    pub table: Option<PathBuf>,
    /// Half width of each refocus search, mA.
    #[arg(long, default_value_t = 20.0)]
    pub search_ma: f64,
    /// A 5 x 5 grid (40..240 mA by 50, 27..37 degC by 2.5) instead of the paper's 11 x 11.
    #[arg(long)]
    pub quick: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Arguments of `etlcal thermal eval`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    /// Driver current E_in, mA.
    #[arg(long = "e-in", value_name = "MA")]
    pub e_in_ma: f64,
    /// Lens temperature, degC.
    #[arg(long = "t", value_name = "C")]
    pub t_c: f64,
    /// The thermal calibration: an etlcal.thermal/1 file, or `paper` for the paper's
    /// surface (none is assumed).
    #[arg(long, value_name = "FILE|paper")]
    pub thermal: PathBuf,
    /// Evaluate outside the calibrated temperature and current ranges too (the result is
    /// marked `"extrapolated": true`); refused otherwise.
    #[arg(long)]
    pub allow_extrapolation: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Arguments of `etlcal thermal fit`.
#[derive(clap::Args, Debug)]
pub struct FitArgs {
    /// CSV table with header `temperature_c,e_in_ma,e_t_ma`.
    #[arg(value_name = "TABLE.csv")]
    pub table: PathBuf,
    /// Where to write the fitted surface (etlcal.thermal/1); written only on success (its
    /// directory is created if missing).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal thermal` (`json`: the global `--json`).
pub fn run(args: Args, json: bool) -> Result<()> {
    match args.command {
        ThermalCommand::Eval(a) => run_eval(EvalArgs { json, ..a }),
        ThermalCommand::Fit(a) => run_fit(FitArgs { json, ..a }),
        ThermalCommand::Calibrate(a) => run_calibrate(CalibrateArgs { json, ..a }),
    }
}

/// Runs `etlcal thermal calibrate --virtual`.
pub fn run_calibrate(args: CalibrateArgs) -> Result<()> {
    use etl_calib::thermal_calibration::ProcedureOptions;
    let max_ms = 1000.0 * etl_sim::virtual_rig::MAX_SETTLE_S;
    if !(args.settle_ms.is_finite() && (0.0..=max_ms).contains(&args.settle_ms)) {
        let message = format!("--settle-ms {} must lie in 0..={} ms", compact(args.settle_ms), compact(max_ms));
        return Err(Error::invalid_value("--settle-ms", args.settle_ms, message));
    }
    let lens = etl_sim::virtual_rig::VirtualRigLens {
        dynamics: crate::lens_sim::dynamics(args.dynamics.as_deref())?,
        settle_s: args.settle_ms / 1000.0,
    };
    crate::signals::remove_lens_folders_on_signal()?;
    let table = args.table.clone().unwrap_or_else(|| args.out.with_extension("csv"));
    crate::output::check([], &[Output::File(&args.out), Output::File(&table)])?;
    for p in [&args.out, &table] {
        crate::output::create_parent(p)?;
    }
    let mut options = ProcedureOptions { search_half_width_ma: args.search_ma, ..ProcedureOptions::default() };
    if args.quick {
        options.e_in_grid_ma = vec![40.0, 90.0, 140.0, 190.0, 240.0];
        options.temperatures_c = vec![27.0, 29.5, 32.0, 34.5, 37.0];
    }
    let v = etl_sim::virtual_rig::run_virtual_procedure(&options, &lens, &crate::progress::Bar::new(!args.json))
        // The options the user sets are flags, in `what` and in the message.
        .map_err(|e| e.rename_input("search_half_width_ma", "--search-ma"))?;
    let (r, t0) = (&v.result, v.t_ref_c);
    let (referenced, absolute) = (v.surface_error_ma, v.surface_error_absolute_ma);
    let file = ThermalFile::new(&r.calibration, r.rms_ma);
    // The surface and the table it was fitted to, both or neither.
    etl_formats::output::write_file_set(&[&args.out, &table], |tmp| {
        file.save(&tmp[0])?;
        etl_formats::thermal::write_thermal_table(&tmp[1], &r.samples)
    })?;
    if args.json {
        print_json(&file_json(
            &file,
            json!({
                "samples": r.samples.len(),
                "frames": r.frames,
                "surface_error_ma": referenced,
                "surface_error_absolute_ma": absolute,
                "out": args.out.display().to_string(),
                "table": table.display().to_string(),
            }),
        ));
    } else {
        outln!(
            "{} samples from {} frames; fit RMS {:.3} mA; against the virtual lens's true surface: {:.3} mA RMS \
             (referenced to {t0} degC as the procedure is), {:.3} mA absolute; wrote {} and {}",
            r.samples.len(),
            r.frames,
            r.rms_ma,
            referenced,
            absolute,
            args.out.display(),
            table.display()
        );
    }
    Ok(())
}

/// Runs `etlcal thermal eval`.
pub fn run_eval(args: EvalArgs) -> Result<()> {
    let cal = ThermalRef::choose(&args.thermal)?.calibration()?;
    let trust = crate::trust(args.allow_extrapolation);
    let (e_t_ma, flags) = ThermalTrust::from_calibration(&cal).e_t_ma(args.e_in_ma, args.t_c, trust)?;
    let c = Compensation {
        e_in_ma: args.e_in_ma,
        e_t_ma,
        e_com_ma: args.e_in_ma - e_t_ma,
        extrapolated: flags.temperature || flags.e_in,
    };
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
                "etlcal: warning: (E_in, T) = ({} mA, {} degC) is outside the fitted ranges {:?} mA x {:?} degC: extrapolated",
                args.e_in_ma, args.t_c, cal.e_in_range_ma, cal.t_range_c
            );
        }
        outln!("E_T = {:.6} mA, E_com = {:.6} mA", c.e_t_ma, c.e_com_ma);
    }
    Ok(())
}

/// Runs `etlcal thermal fit`.
pub fn run_fit(args: FitArgs) -> Result<()> {
    crate::output::check([Some(args.table.as_path())], &[Output::File(&args.out)])?;
    let rows = read_thermal_table(&args.table)?;
    let (cal, rms_ma) =
        etl_calib::thermal_calibration::fit_samples(&rows).map_err(|err| err.within(args.table.display(), None))?;
    let file = ThermalFile::new(&cal, rms_ma);
    crate::output::create_parent(&args.out)?;
    file.save(&args.out)?;
    if args.json {
        print_json(&file_json(&file, json!({"samples": rows.len(), "out": args.out.display().to_string()})));
    } else {
        outln!(
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

/// The `--json` object of a verb that wrote `file`: the file's keys, then `extra`'s.
fn file_json(file: &ThermalFile, extra: serde_json::Value) -> serde_json::Value {
    let mut j = json!(file);
    if let (Some(j), serde_json::Value::Object(extra)) = (j.as_object_mut(), extra) {
        j.extend(extra);
    }
    j
}
