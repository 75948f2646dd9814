//! `etlcal focus --calibration FILE --distance-mm Z --t C [--json]`: the driver current
//! that focuses the calibrated camera at a distance, through the calibration's focus law
//! (E_com in focus at the distance) and its thermal surface (E_in giving that E_com at the
//! lens temperature).
//!
//! The distance is the depth of the plane in focus: its distance along the optical axis
//! from the camera's centre, mm (docs/METHOD.md, "The focus law"). A distance outside the
//! law's calibrated distances (+- 2 % of their span), a setting outside the calibrated
//! temperature and current ranges (unless `--allow-extrapolation`), or a calibration
//! without a focus law is a one-line error (exit status 1); so is a calibration without
//! temperature compensation, whose message gives the E_com in focus (for `--e-com`).
//! `--json` prints `{"e_in_ma", "e_com_ma", "distance_mm"}`; for a focal-power calibration
//! (`"setting": "focal_power"`) the focal power to command instead:
//! `{"focal_power_dpt", "distance_mm", "extrapolated"}`.

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use etl_formats::calibration::Calibration;
use etl_formats::Result;

/// Arguments of `etlcal focus`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The calibration (etlcal.calibration/1) with a focus law.
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// Distance to focus at, mm (along the optical axis from the camera's centre).
    #[arg(long = "distance-mm", value_name = "MM")]
    pub distance_mm: f64,
    /// Lens temperature, degC.
    #[arg(long = "t", value_name = "C")]
    pub temperature_c: f64,
    /// Outside the calibrated temperature and current ranges too (marked
    /// `"extrapolated": true`); the law's distance range is always enforced.
    #[arg(long)]
    pub allow_extrapolation: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal focus`: [`Calibration::focus_e_in`], and the E_com of the law.
pub fn run(args: Args) -> Result<()> {
    let cal = Calibration::load(&args.calibration)?;
    let trust = crate::trust(args.allow_extrapolation);
    if cal.setting_kind() == etl_formats::SettingKind::FocalPower {
        return focal_power(&cal, &args, trust);
    }
    if cal.thermal.is_none() {
        // No E_in can be had without the thermal part; the E_com in focus still can, and
        // is what the run-time verbs take.
        let e_com_ma = cal.focus_law()?.e_com_ma(args.distance_mm)?;
        return Err(etl_formats::Error::invalid(
            "--t",
            format!(
                "{} has no temperature compensation (thermal): no driver current can be given; the E_com in focus at \
                 {} mm is {e_com_ma:.3} mA (give it to export, measure, undistort as --e-com)",
                args.calibration.display(),
                args.distance_mm
            ),
        ));
    }
    let e_in_ma = cal.focus_e_in(args.distance_mm, args.temperature_c, trust)?;
    let extrapolated = cal.at(e_in_ma, args.temperature_c, trust)?.extrapolated();
    let e_com_ma = cal.focus_law()?.e_com_ma(args.distance_mm)?;
    let distance_mm = args.distance_mm;
    if args.json {
        print_json(&json!({"e_in_ma": e_in_ma, "e_com_ma": e_com_ma, "distance_mm": distance_mm,
            "extrapolated": extrapolated}));
    } else {
        outln!(
            "E_in {e_in_ma:.3} mA (E_com {e_com_ma:.3} mA) focuses at {distance_mm} mm at {} degC",
            args.temperature_c
        );
    }
    Ok(())
}

/// `etlcal focus` on a focal-power calibration: the focal power in focus
/// ([`Calibration::focus_focal_power_dpt`]).
fn focal_power(cal: &Calibration, args: &Args, trust: etl_formats::Trust) -> Result<()> {
    let dpt = cal.focus_focal_power_dpt(args.distance_mm, args.temperature_c, trust)?;
    let extrapolated = cal.at_focal_power(dpt, args.temperature_c, trust)?.extrapolated();
    let distance_mm = args.distance_mm;
    if args.json {
        print_json(&json!({"focal_power_dpt": dpt, "distance_mm": distance_mm, "extrapolated": extrapolated}));
    } else {
        outln!(
            "focal power {dpt:.4} dpt focuses at {distance_mm} mm at {} degC (the driver compensates)",
            args.temperature_c
        );
    }
    Ok(())
}
