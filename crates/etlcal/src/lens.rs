//! `etlcal lens (--port PATH | --virtual) info|set-current MA|get-current|temperature|hold
//! --e-com MA [--thermal FILE]` (add `--json` for one JSON object on stdout). `--port`,
//! `--virtual` and `--json` go before or after the subcommand.
//!
//! Safety policy of `set-current`: a request beyond the driver's software limits is
//! **clamped** to the nearest limit, sent so, and reported with a warning on stderr
//! (`"clamped": true` in JSON); NaN and infinities are refused (exit 1). Nothing outside
//! the limits is ever sent. `set-current MA --shaped F` steps there by the zero-vibration
//! shaper of the lens dynamics in F (`etlcal.lens-dynamics/1`, e.g. measured by
//! `characterise --out`): the shaper's fraction of the step at once, the target its delay
//! later (`LensClient::set_current_shaped_ma`); `--json` adds `"shaper"`:
//! `{"first_fraction", "delay_ms", "first_ma", "late_ms"}`.
//!
//! `--port` opens a real driver without the `Start` handshake (which would zero the
//! current), unless `--handshake` is given. `--virtual` starts an in-process virtual lens
//! (`etl_hw::virtual_lens`) and talks to it through its pseudo-terminal with the same
//! client: each invocation gets a fresh lens at 0 mA; for a lens that persists between
//! invocations run `etlcal lens-sim` and pass its path to `--port`.

use std::path::PathBuf;
use std::time::Duration;

use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::codec::scaling::SENSOR_RANGE_C;
use etl_hw::hold::{duration_from_s, hold, HoldConfig, HoldError, RATE_RANGE_HZ};
use etl_hw::virtual_lens::{ThermalModel, VirtualLens, VirtualLensConfig, MAX_TIME_SCALE};
use serde_json::json;

use super::print_json;
use etl_formats::calibration::ThermalRef;
use etl_formats::{compact, Error, Result};

/// `set-current MA --shaped F`: the shaper of the dynamics in `f`, the step taken by it;
/// the target's write and the shaper as `--json` gives it. A file whose membrane is not
/// underdamped has no shaper: refused in one line.
fn set_shaped(
    client: &LensClient,
    ma: f64,
    f: &std::path::Path,
) -> Result<(etl_hw::client::SetCurrent, serde_json::Value)> {
    let dynamics = etl_formats::LensDynamicsFile::load(f)?.dynamics();
    let Some(z) = etl_core::physics::shaping::ZvShaper::of(&dynamics) else {
        let why = format!(
            "--shaped {}: damping {} is not below 1: a step does not ring, no shaper",
            f.display(),
            dynamics.damping
        );
        return Err(Error::invalid("--shaped", why));
    };
    let s = client.set_current_shaped_ma(ma, &z).map_err(Error::lens)?;
    if s.late_s > 0.1 * z.delay_s {
        eprintln!(
            "etlcal: warning: the target went out {:.2} ms late (the first write's read-back)",
            1000.0 * s.late_s
        );
    }
    let j = json!({"first_fraction": z.first_fraction, "delay_ms": 1000.0 * z.delay_s,
        "first_ma": s.first.commanded_ma, "late_ms": 1000.0 * s.late_s});
    Ok((s.target, j))
}

/// Arguments of `etlcal lens`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Which lens.
    #[command(flatten)]
    pub target: Target,
    /// Send the `Start` handshake on open (zeroes the current).
    #[arg(long)]
    pub handshake: bool,
    /// Reply timeout, ms (1..=60000).
    #[arg(long, default_value_t = 500, value_name = "MS")]
    pub timeout_ms: u64,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: LensCommand,
}

/// A real port or the virtual lens: exactly one, before or after the subcommand
/// (`etlcal lens --virtual info` or `etlcal lens info --virtual`).
// Global arguments cannot be required nor grouped by clap, so `target_path` checks "exactly
// one".
#[derive(clap::Args, Debug)]
pub struct Target {
    /// Serial port of the Optotune Lens Driver 4 (e.g. /dev/ttyACM0).
    #[arg(long, value_name = "PATH", global = true)]
    pub port: Option<PathBuf>,
    /// An in-process virtual lens (paper physics and thermal surface).
    #[arg(long = "virtual", global = true)]
    pub virtual_lens: bool,
    /// With `--virtual`: the lens's dynamics (`etlcal.lens-dynamics/1`: step response,
    /// creep, hysteresis, self-heating); without it the optics follow the current at once.
    #[arg(long, value_name = "FILE", global = true)]
    pub dynamics: Option<PathBuf>,
}

/// The subcommands of `etlcal lens`.
#[derive(clap::Subcommand, Debug)]
pub enum LensCommand {
    /// Firmware, lens serial, max current, limits and temperature.
    Info,
    /// Set the driver current (clamped to the driver's limits, with a warning).
    #[command(allow_negative_numbers = true)]
    SetCurrent {
        /// Current, mA.
        #[arg(value_name = "MA")]
        ma: f64,
        /// Step there by the zero-vibration shaper of these dynamics
        /// (etlcal.lens-dynamics/1): faster settling, no ringing.
        #[arg(long, value_name = "FILE")]
        shaped: Option<PathBuf>,
    },
    /// The driver current, mA.
    GetCurrent,
    /// The lens temperature, degC.
    Temperature,
    /// Hold a compensated current E_com while the temperature changes (section 2.2.1 iii).
    #[command(allow_negative_numbers = true)]
    Hold(HoldArgs),
    /// Focal-power mode: send the temperature window, switch the mode, set the power (dpt).
    #[command(allow_negative_numbers = true)]
    SetFocalPower(crate::lens_focal::SetFocalPowerArgs),
    /// The focal power the driver reports, dpt.
    FocalPower,
    /// Switch the driver to current or focal-power mode (the latter with its window).
    #[command(allow_negative_numbers = true)]
    Mode(crate::lens_focal::ModeArgs),
    /// Measure the lens's dynamics from frames: settling, hysteresis, creep, repeatability.
    Characterise(crate::lens_characterise::CharacteriseArgs),
}

/// Arguments of `etlcal lens hold`.
#[derive(clap::Args, Debug)]
pub struct HoldArgs {
    /// The E_com to hold, mA.
    #[arg(long = "e-com", value_name = "MA")]
    pub e_com_ma: f64,
    /// The thermal calibration: an etlcal.thermal/1 file, or `paper` for the paper's
    /// surface (none is assumed).
    #[arg(long, value_name = "FILE|paper")]
    pub thermal: PathBuf,
    /// Loop rate, Hz: 0 for as fast as the link allows, else 0.001..=10000.
    #[arg(long, default_value_t = 10.0, value_name = "HZ")]
    pub rate: f64,
    /// Stop after this many seconds, 0..=1e7 (default: run until killed).
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    /// Virtual lens only: heat it towards this many degC above its start (the target
    /// must stay in the sensor's -40..=125 degC).
    #[arg(long, value_name = "C")]
    pub warm: Option<f64>,
    /// Virtual lens only: model seconds per wall second, (0, 1e6].
    #[arg(long, default_value_t = 1.0, value_name = "X")]
    pub time_scale: f64,
}

/// Runs `etlcal lens`.
pub fn run(args: Args) -> Result<()> {
    if !(1..=60_000).contains(&args.timeout_ms) {
        return Err(Error::invalid_value(
            "--timeout-ms",
            args.timeout_ms,
            format!("--timeout-ms {} must lie in 1..=60000 ms", args.timeout_ms),
        ));
    }
    if let LensCommand::Hold(h) = &args.command {
        check_hold_args(h)?;
    }
    let (device, path) = open_target(&args)?;
    let options = OpenOptions {
        handshake: args.handshake,
        timeout: Duration::from_millis(args.timeout_ms),
        ..Default::default()
    };
    let mut client = LensClient::open(&path, options).map_err(Error::lens)?;
    match args.command {
        LensCommand::Info => {
            let info = client.identify().map_err(Error::lens)?;
            let t = client.temperature_c().ok();
            if args.json {
                print_json(&json!({
                    "firmware_type": info.firmware_type.letter().to_string(),
                    "firmware_version": info.firmware_version,
                    "lens_serial": info.lens_serial,
                    "max_current_ma": info.max_current_ma,
                    "upper_limit_ma": info.upper_limit_ma,
                    "lower_limit_ma": info.lower_limit_ma,
                    "temperature_c": t,
                }));
            } else {
                outln!("port:             {}", path.display());
                outln!("firmware:         type {} version {}", info.firmware_type.letter(), info.firmware_version);
                outln!("lens serial:      {}", info.lens_serial);
                outln!("max current:      {:.2} mA", info.max_current_ma);
                outln!("limits:           [{:.3}, {:.3}] mA", info.lower_limit_ma, info.upper_limit_ma);
                match t {
                    Some(t) => outln!("temperature:      {t:.4} degC"),
                    None => outln!("temperature:      no sensor"),
                }
            }
        }
        LensCommand::SetCurrent { ma, shaped } => {
            // The client confirms the write by reading it back: a rejected `Aw` is an error here.
            let (r, shaper) = match shaped {
                Some(f) => set_shaped(&client, ma, &f)?,
                None => (client.set_current_ma(ma).map_err(Error::lens)?, serde_json::Value::Null),
            };
            let now = client.current_ma().map_err(Error::lens)?;
            if r.clamped {
                let [lo, hi] = client.limits_ma();
                eprintln!(
                    "etlcal: warning: {ma} mA is outside the driver's limits [{lo:.3}, {hi:.3}] mA: clamped to {:.3} mA",
                    r.commanded_ma
                );
            }
            if args.json {
                print_json(&json!({
                    "requested_ma": ma,
                    "commanded_ma": r.commanded_ma,
                    "code": r.code,
                    "clamped": r.clamped,
                    "current_ma": now,
                    "shaper": shaper,
                }));
            } else {
                outln!("current set to {:.4} mA (code {})", r.commanded_ma, r.code);
            }
        }
        LensCommand::GetCurrent => {
            print_reading(args.json, "current_ma", client.current_ma().map_err(Error::lens)?, "mA")
        }
        LensCommand::Temperature => {
            print_reading(args.json, "temperature_c", client.temperature_c().map_err(Error::lens)?, "degC")
        }
        LensCommand::Hold(h) => run_hold(&client, device.as_ref(), h, args.json)?,
        LensCommand::SetFocalPower(a) => crate::lens_focal::set_focal_power(&client, &a, args.json)?,
        LensCommand::FocalPower => crate::lens_focal::focal_power(&client, args.json)?,
        LensCommand::Mode(a) => crate::lens_focal::mode(&client, &a, args.json)?,
        LensCommand::Characterise(a) => {
            let dynamics = args.target.dynamics.is_some();
            crate::lens_characterise::run(&mut client, device.as_ref(), dynamics, &a, args.json)?
        }
    }
    Ok(())
}

/// The lens to talk to: the `--port` path, or a fresh virtual lens and its pseudo-terminal.
fn open_target(args: &Args) -> Result<(Option<VirtualLens>, PathBuf)> {
    let target = match (&args.target.port, args.target.virtual_lens) {
        (Some(_), true) => return Err(Error::invalid("--port", "pass --port PATH or --virtual, not both")),
        (None, false) => return Err(Error::invalid("--port", "pass --port PATH (a Lens Driver 4) or --virtual")),
        (Some(_), false) if args.target.dynamics.is_some() => {
            return Err(Error::invalid(
                "--dynamics",
                "--dynamics FILE describes the virtual lens: pass it with --virtual",
            ));
        }
        (Some(p), false) => (None, p.clone()),
        (None, true) => {
            let time_scale = match &args.command {
                LensCommand::Hold(h) => h.time_scale,
                // The simulated camera drives the model's clock frame by frame: wall time
                // (serial round trips) must not move it.
                LensCommand::Characterise(_) => 1e-6,
                _ => 1.0,
            };
            let config = VirtualLensConfig {
                time_scale,
                thermal: ThermalModel { ambient_c: 27.0, ..Default::default() },
                dynamics: crate::lens_sim::dynamics(args.target.dynamics.as_deref())?,
                ..Default::default()
            };
            crate::signals::remove_lens_folders_on_signal()?;
            let d = VirtualLens::spawn(config).map_err(Error::lens)?;
            let p = d.path().to_owned();
            (Some(d), p)
        }
    };
    Ok(target)
}

fn run_hold(client: &LensClient, device: Option<&VirtualLens>, h: HoldArgs, json_out: bool) -> Result<()> {
    let cal = ThermalRef::choose(&h.thermal)?.calibration()?;
    // Checked by `check_hold_args` before anything was opened.
    let duration = h.duration.map(duration_from_s).transpose().map_err(Error::Core)?;
    if let (Some(d), Some(w)) = (device, h.warm) {
        let target_c = d.state().temperature_c + w;
        if !(SENSOR_RANGE_C[0]..=SENSOR_RANGE_C[1]).contains(&target_c) {
            return Err(Error::invalid_value(
                "--warm",
                w,
                format!(
                    "--warm {} degC takes the lens to {} degC, outside the sensor's -40..=125 degC",
                    compact(w),
                    compact(target_c)
                ),
            ));
        }
        d.set_target_temperature_c(target_c);
    } else if h.warm.is_some() {
        return Err(Error::invalid("--warm", "--warm only applies to --virtual"));
    }
    let cfg = HoldConfig { e_com_ma: h.e_com_ma, rate_hz: h.rate, duration };
    let mut last_print = std::time::Instant::now();
    let report = hold(&mut LensRef(client), &cal, &cfg, |s| {
        if !json_out && last_print.elapsed() >= Duration::from_secs(1) {
            last_print = std::time::Instant::now();
            eprintln!(
                "T = {:.4} degC, E_in = {:.3} mA, E_com = {:.3} mA{}",
                s.temperature_c,
                s.e_in_ma,
                s.e_com_ma,
                if s.extrapolated { " (extrapolated)" } else { "" }
            );
        }
        true
    })
    .map_err(|e| match e {
        HoldError::Lens(e) => Error::lens(e),
        HoldError::Core(e) => Error::Core(e),
        e @ HoldError::Unreachable { e_com_ma, .. } => Error::invalid_value("--e-com", e_com_ma, e.to_string()),
    })?;
    let unsolicited = client.take_unsolicited().len();
    if json_out {
        print_json(&json!({
            "e_com_ma": h.e_com_ma,
            "commands_sent": report.commands_sent,
            "elapsed_s": report.elapsed.as_secs_f64(),
            "achieved_rate_hz": report.achieved_rate_hz,
            "worst_e_com_error_ma": report.worst_e_com_error_ma,
            "temperature_range_c": report.temperature_range_c,
            "extrapolated_steps": report.extrapolated_steps,
            "last_e_in_ma": report.last.map(|s| s.e_in_ma),
            "unsolicited_errors": unsolicited,
        }));
    } else {
        outln!(
            "held E_com = {} mA: {} commands in {:.2} s ({:.1} Hz), worst E_com error {:.4} mA, T {:.3}..{:.3} degC{}",
            h.e_com_ma,
            report.commands_sent,
            report.elapsed.as_secs_f64(),
            report.achieved_rate_hz,
            report.worst_e_com_error_ma,
            report.temperature_range_c[0],
            report.temperature_range_c[1],
            if unsolicited > 0 { format!(", {unsolicited} error frames from the driver") } else { String::new() }
        );
    }
    Ok(())
}

/// Refuses `lens hold` flags outside their ranges before the lens is opened: the rate
/// (0 or [`RATE_RANGE_HZ`]), the duration (0..=[`etl_hw::hold::MAX_DURATION_S`]), the time scale
/// ((0, [`MAX_TIME_SCALE`]]).
fn check_hold_args(h: &HoldArgs) -> Result<()> {
    if h.rate != 0.0 && !(RATE_RANGE_HZ[0]..=RATE_RANGE_HZ[1]).contains(&h.rate) {
        return Err(Error::invalid_value(
            "--rate",
            h.rate,
            format!("--rate {} Hz must be 0 (as fast as possible) or lie in 0.001..=10000 Hz", compact(h.rate)),
        ));
    }
    if let Some(s) = h.duration.filter(|&s| duration_from_s(s).is_err()) {
        return Err(Error::invalid_value(
            "--duration",
            s,
            format!("--duration {} s must lie in 0..=1e7 s", compact(s)),
        ));
    }
    if !(h.time_scale > 0.0 && h.time_scale <= MAX_TIME_SCALE) {
        return Err(Error::invalid_value(
            "--time-scale",
            h.time_scale,
            format!("--time-scale {} must lie in (0, 1e6]", compact(h.time_scale)),
        ));
    }
    Ok(())
}

/// `&LensClient` as a [`etl_core::lens::Lens`] (the client locks internally).
struct LensRef<'a>(&'a LensClient);

impl etl_core::lens::Lens for LensRef<'_> {
    type Error = etl_hw::HwError;
    fn set_current_ma(&mut self, e_in_ma: f64) -> std::result::Result<f64, Self::Error> {
        self.0.set_current_ma(e_in_ma).map(|r| r.commanded_ma)
    }
    fn current_ma(&mut self) -> std::result::Result<f64, Self::Error> {
        self.0.current_ma()
    }
    fn temperature_c(&mut self) -> std::result::Result<f64, Self::Error> {
        self.0.temperature_c()
    }
}

/// One reading of the lens: `{"<key>": value}` with --json, else the value (4 decimals)
/// and its unit.
fn print_reading(json: bool, key: &str, value: f64, unit: &str) {
    if json {
        print_json(&json!({ key: value }));
    } else {
        outln!("{value:.4} {unit}");
    }
}
