//! `etlcal lens-sim`: runs a virtual Optotune lens + Lens Driver 4 on a pseudo-terminal,
//! prints the port path (first line of stdout; `{"port": ...}` with `--json`) and serves
//! until killed. Point any client at it: `etlcal lens --port PATH info`.

use std::io::Write;

use etl_hw::codec::scaling::{current_code, SENSOR_RANGE_C};
use etl_hw::virtual_lens::{ThermalModel, VirtualLens, VirtualLensConfig, MAX_TIME_SCALE};

use serde_json::json;

use super::print_json;
use etl_core::physics::dynamics::LensDynamics;
use etl_formats::{compact, Error, LensDynamicsFile, Result};

/// Arguments of `etlcal lens-sim`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Model seconds per wall second (thermal time runs this much faster), (0, 1e6].
    #[arg(long, default_value_t = 1.0, value_name = "X")]
    pub time_scale: f64,
    /// Ambient temperature, degC, within the lens sensor's -40..=125.
    #[arg(long, default_value_t = 25.0, value_name = "C")]
    pub ambient: f64,
    /// Upper software current limit, mA.
    #[arg(long, default_value_t = 292.84, value_name = "MA")]
    pub upper_limit: f64,
    /// Lower software current limit, mA.
    #[arg(long, default_value_t = -292.84, value_name = "MA")]
    pub lower_limit: f64,
    /// The lens's dynamics (`etlcal.lens-dynamics/1`: step response, creep, hysteresis,
    /// self-heating; fixtures/lens-dynamics has the published EL-10-30's). Without it the
    /// optics follow the current at once.
    #[arg(long, value_name = "FILE")]
    pub dynamics: Option<std::path::PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The dynamics of `--dynamics FILE` (checked as the format says), or None.
pub fn dynamics(path: Option<&std::path::Path>) -> Result<Option<LensDynamics>> {
    path.map(|p| LensDynamicsFile::load(p).map(|f| f.dynamics())).transpose()
}

/// Runs `etlcal lens-sim` (does not return unless spawning fails).
pub fn run(args: Args) -> Result<()> {
    let [lo, hi] = [args.lower_limit, args.upper_limit];
    if !(lo.is_finite() && hi.is_finite() && lo <= hi && lo >= -292.84 && hi <= 292.84) {
        let message =
            format!("limits [{}, {}] mA must satisfy -292.84 <= lower <= upper <= 292.84", compact(lo), compact(hi));
        // The lower limit is blamed unless it alone is fine.
        let (what, value) =
            if (-292.84..=hi.min(292.84)).contains(&lo) { ("--upper-limit", hi) } else { ("--lower-limit", lo) };
        return Err(Error::invalid_value(what, value, message));
    }
    if !(SENSOR_RANGE_C[0]..=SENSOR_RANGE_C[1]).contains(&args.ambient) {
        return Err(Error::invalid_value(
            "--ambient",
            args.ambient,
            format!("--ambient {} degC must lie in -40..=125 degC", compact(args.ambient)),
        ));
    }
    if !(args.time_scale > 0.0 && args.time_scale <= MAX_TIME_SCALE) {
        return Err(Error::invalid_value(
            "--time-scale",
            args.time_scale,
            format!("--time-scale {} must lie in (0, 1e6]", compact(args.time_scale)),
        ));
    }
    let dynamics = dynamics(args.dynamics.as_deref())?;
    let config = VirtualLensConfig {
        dynamics,
        time_scale: args.time_scale,
        thermal: ThermalModel { ambient_c: args.ambient, ..Default::default() },
        upper_limit_code: current_code(hi, 292.84),
        lower_limit_code: current_code(lo, 292.84),
        ..Default::default()
    };
    crate::signals::remove_lens_folders_on_signal()?;
    let lens = VirtualLens::spawn(config).map_err(Error::lens)?;
    if args.json {
        print_json(&json!({ "port": lens.path().display().to_string() }));
    } else {
        outln!("{}", lens.path().display());
        eprintln!("etlcal: virtual lens serving on {} (kill to stop)", lens.path().display());
    }
    let _ = std::io::stdout().flush();
    loop {
        std::thread::sleep(std::time::Duration::from_secs(3600));
    }
}
