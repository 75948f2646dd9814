//! `etlcal lens set-focal-power | focal-power | mode`: the Lens Driver 4 in focal-power
//! (controlled) mode, entered in the documented order (the temperature window, `PwTA`,
//! then the mode switch, `MwCA`: `LensClient::enter_focal_power_mode`), the status bits
//! it returns named, and a power outside the range it reports refused.

use etl_hw::client::{ControlledRange, LensClient};
use etl_hw::codec::scaling::SENSOR_RANGE_C;
use etl_hw::codec::Mode;
use serde_json::json;

use super::print_json;
use etl_formats::{compact, Error, Result};

/// The half width of the default temperature window about the lens's measured
/// temperature, degC.
pub const DEFAULT_WINDOW_HALF_C: f64 = 10.0;

/// The temperature window of focal-power mode.
#[derive(clap::Args, Debug)]
pub struct WindowArgs {
    /// The temperature window the firmware compensates over, degC, low then high (default:
    /// the lens's measured temperature +-10 degC, printed). A narrower window gives a
    /// wider reachable range of focal power.
    #[arg(long, num_args = 2, value_names = ["LO_C", "HI_C"], allow_negative_numbers = true)]
    pub window: Option<Vec<f64>>,
}

/// Arguments of `etlcal lens set-focal-power`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct SetFocalPowerArgs {
    /// The focal power, dpt (within the range the driver reports for the window).
    #[arg(value_name = "DPT")]
    pub dpt: f64,
    #[command(flatten)]
    pub window: WindowArgs,
}

/// The modes `etlcal lens mode` switches to.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeChoice {
    /// The driver current is commanded (the default after power-up).
    Current,
    /// The focal power is commanded, temperature-compensated by the firmware.
    FocalPower,
}

/// Arguments of `etlcal lens mode`.
#[derive(clap::Args, Debug)]
pub struct ModeArgs {
    /// The mode to switch to.
    #[arg(value_enum)]
    pub mode: ModeChoice,
    #[command(flatten)]
    pub window: WindowArgs,
}

/// The window of `--window`, or the lens's temperature +-10 degC (said on stderr);
/// refused in one line when it is not LO < HI within the sensor's range.
fn window_c(client: &LensClient, w: &WindowArgs) -> Result<(f64, f64)> {
    let (lo, hi) = match w.window.as_deref() {
        Some([lo, hi]) => (*lo, *hi),
        _ => {
            let t = client.temperature_c().map_err(Error::lens)?;
            let (lo, hi) = (t - DEFAULT_WINDOW_HALF_C, t + DEFAULT_WINDOW_HALF_C);
            eprintln!(
                "etlcal: temperature window {}..{} degC (the lens's {} degC +-{DEFAULT_WINDOW_HALF_C}; --window sets it)",
                compact(lo),
                compact(hi),
                compact(t)
            );
            (lo, hi)
        }
    };
    let [min, max] = SENSOR_RANGE_C;
    if !(lo.is_finite() && hi.is_finite() && min <= lo && lo < hi && hi <= max) {
        let message = format!("--window {} {} degC must satisfy -40 <= LO < HI <= 125", compact(lo), compact(hi));
        return Err(Error::invalid_value("--window", lo, message));
    }
    Ok((lo, hi))
}

/// Enters focal-power mode over the window; warns of any status bit the driver sets.
fn enter(client: &LensClient, w: &WindowArgs) -> Result<((f64, f64), ControlledRange)> {
    let (lo, hi) = window_c(client, w)?;
    let range = client.enter_focal_power_mode(hi, lo).map_err(Error::lens)?;
    let flags = range.status_flags();
    if !flags.is_empty() {
        eprintln!("etlcal: warning: the driver's status: {}", flags.join(", "));
    }
    Ok(((lo, hi), range))
}

/// The mode and range as JSON fields.
fn range_json(window: (f64, f64), r: &ControlledRange) -> serde_json::Value {
    json!({
        "mode": "focal-power",
        "window_c": [window.0, window.1],
        "range_dpt": [r.min_dpt, r.max_dpt],
        "status": r.status_flags(),
    })
}

/// `etlcal lens set-focal-power DPT [--window LO_C HI_C]`.
pub fn set_focal_power(client: &LensClient, a: &SetFocalPowerArgs, json_out: bool) -> Result<()> {
    if !a.dpt.is_finite() {
        return Err(Error::invalid_value("DPT", a.dpt, format!("focal power {} dpt must be finite", compact(a.dpt))));
    }
    let (window, range) = enter(client, &a.window)?;
    let set = client.set_focal_power_dpt(a.dpt).map_err(Error::lens)?;
    let read_back = client.focal_power_dpt().map_err(Error::lens)?;
    if json_out {
        let mut j = range_json(window, &range);
        j["requested_dpt"] = json!(a.dpt);
        j["focal_power_dpt"] = json!(set);
        j["read_back_dpt"] = json!(read_back);
        print_json(&j);
    } else {
        outln!(
            "focal power set to {set:.3} dpt (reads back {read_back:.3} dpt); range {:.3}..{:.3} dpt over {}..{} degC",
            range.min_dpt,
            range.max_dpt,
            compact(window.0),
            compact(window.1)
        );
    }
    Ok(())
}

/// `etlcal lens focal-power`: what the driver reports (`PrDA`).
pub fn focal_power(client: &LensClient, json_out: bool) -> Result<()> {
    let dpt = client.focal_power_dpt().map_err(Error::lens)?;
    if json_out {
        print_json(&json!({ "focal_power_dpt": dpt }));
    } else {
        outln!("{dpt:.3} dpt");
    }
    Ok(())
}

/// `etlcal lens mode current|focal-power [--window LO_C HI_C]`.
pub fn mode(client: &LensClient, a: &ModeArgs, json_out: bool) -> Result<()> {
    let j = match a.mode {
        ModeChoice::Current => {
            client.set_mode(Mode::Current).map_err(Error::lens)?;
            json!({ "mode": "current" })
        }
        ModeChoice::FocalPower => {
            let (window, range) = enter(client, &a.window)?;
            range_json(window, &range)
        }
    };
    if json_out {
        print_json(&j);
    } else {
        outln!("mode: {}", j["mode"].as_str().unwrap_or("?"));
    }
    Ok(())
}
