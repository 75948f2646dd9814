//! The flags shared by the verbs that use a calibration at one lens setting (`measure`,
//! `export`, `undistort`, `diff`): `--calibration FILE (--e-in MA --t C | --e-com MA |
//! --dpt DPT --t C) [--allow-extrapolation]`.
//!
//! The setting is given in exactly one of three forms (clap's group `setting`: anything
//! else is a one-line usage error, exit 2): the driver current and the lens temperature,
//! turned into E_com by the calibration's thermal part; a known compensated current E_com
//! (a calibration without temperature compensation, or E_com compensated elsewhere); or,
//! for a focal-power calibration, the commanded focal power and the lens temperature.

use std::path::{Path, PathBuf};

use etl_formats::calibration::Calibration;
use etl_formats::{CameraAt, Error, Result, Trust};

/// `--calibration FILE (--e-in MA --t C | --e-com MA) [--allow-extrapolation]`.
#[derive(clap::Args, Debug, Clone)]
pub struct SettingArgs {
    /// The calibration (etlcal.calibration/1).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The setting.
    #[command(flatten)]
    pub flags: SettingFlags,
}

/// `(--e-in MA --t C | --e-com MA) [--allow-extrapolation]`: the setting of any number of
/// calibrations (`diff` takes two).
#[derive(clap::Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("setting").required(true).args(["e_in_ma", "e_com_ma", "focal_power_dpt"])))]
pub struct SettingFlags {
    /// Driver current, mA (with --t; E_com through the calibration's thermal part).
    #[arg(long = "e-in", value_name = "MA", requires = "temperature_c")]
    pub e_in_ma: Option<f64>,
    /// Lens temperature, degC (with --e-in or --dpt).
    #[arg(long = "t", value_name = "C")]
    pub temperature_c: Option<f64>,
    /// Commanded focal power, dpt (with --t): for a focal-power calibration, whose setting
    /// is the power the lens driver holds in its focal-power mode.
    #[arg(long = "dpt", value_name = "DPT", requires = "temperature_c", allow_negative_numbers = true)]
    pub focal_power_dpt: Option<f64>,
    /// A known compensated current E_com, mA (instead of --e-in and --t): for a calibration
    /// without temperature compensation ("temperature_compensation": "none").
    #[arg(long = "e-com", value_name = "MA", conflicts_with = "temperature_c")]
    pub e_com_ma: Option<f64>,
    /// Go on outside the calibrated temperature, current and E_com ranges (the result is
    /// marked `"extrapolated": true`); refused otherwise.
    #[arg(long)]
    pub allow_extrapolation: bool,
}

/// The lens setting the flags give.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setting {
    /// `--e-in MA --t C`.
    DriverCurrent {
        /// Driver current, mA.
        e_in_ma: f64,
        /// Lens temperature, degC.
        temperature_c: f64,
    },
    /// `--e-com MA`.
    Compensated {
        /// Compensated current, mA.
        e_com_ma: f64,
    },
    /// `--dpt DPT --t C`.
    FocalPower {
        /// Commanded focal power, dpt.
        focal_power_dpt: f64,
        /// Lens temperature, degC.
        temperature_c: f64,
    },
}

impl SettingFlags {
    /// The out-of-range policy the flags choose.
    pub fn trust(&self) -> Trust {
        crate::trust(self.allow_extrapolation)
    }

    /// The setting (clap's groups have made sure exactly one form is given).
    pub fn setting(&self) -> Result<Setting> {
        match (self.e_in_ma, self.temperature_c, self.e_com_ma, self.focal_power_dpt) {
            (Some(e_in_ma), Some(temperature_c), None, None) => Ok(Setting::DriverCurrent { e_in_ma, temperature_c }),
            (None, None, Some(e_com_ma), None) => Ok(Setting::Compensated { e_com_ma }),
            (None, Some(temperature_c), None, Some(focal_power_dpt)) => {
                Ok(Setting::FocalPower { focal_power_dpt, temperature_c })
            }
            _ => Err(Error::invalid(
                "--e-in",
                "give the setting as one of --e-in MA --t C, --e-com MA, or --dpt DPT --t C",
            )),
        }
    }

    /// The calibration at `calibration`, and the camera at the setting
    /// (`Calibration::at` or `Calibration::at_e_com`: the one range policy). A driver
    /// current given to a calibration without temperature compensation is refused, naming
    /// `--e-com`.
    pub fn camera_of(&self, calibration: &Path) -> Result<(Calibration, CameraAt)> {
        let cal = Calibration::load(calibration)?;
        let setting = self.setting()?;
        let focal = cal.setting_kind() == etl_formats::SettingKind::FocalPower;
        if focal != matches!(setting, Setting::FocalPower { .. }) {
            let (flag, why) = if focal {
                ("--dpt", "its setting is the focal power: give --dpt DPT --t C, not a current")
            } else {
                ("--e-in", "its setting is the lens current: give --e-in MA --t C or --e-com MA, not --dpt")
            };
            return Err(Error::invalid(flag, format!("{}: {why}", calibration.display())));
        }
        let camera = match setting {
            Setting::DriverCurrent { .. } if cal.thermal.is_none() => {
                return Err(Error::invalid(
                    "--e-in",
                    format!(
                        "{} has no temperature compensation (thermal): give the setting as --e-com MA, not --e-in/--t",
                        calibration.display()
                    ),
                ))
            }
            Setting::DriverCurrent { e_in_ma, temperature_c } => cal.at(e_in_ma, temperature_c, self.trust())?,
            Setting::Compensated { e_com_ma } => cal.at_e_com(e_com_ma, self.trust())?,
            Setting::FocalPower { focal_power_dpt, temperature_c } => {
                cal.at_focal_power(focal_power_dpt, temperature_c, self.trust())?
            }
        };
        Ok((cal, camera))
    }

    /// The `--json` keys of the setting: `e_in_ma` and `temperature_c` as given (null for
    /// `--e-com`), `e_com_ma` of the camera, `extrapolated`; for `--dpt`, `"setting":
    /// "focal_power"`, `focal_power_dpt` and `temperature_c` instead of the currents.
    pub fn json(&self, camera: &CameraAt) -> serde_json::Value {
        if let Some(dpt) = self.focal_power_dpt {
            return serde_json::json!({
                "setting": "focal_power",
                "focal_power_dpt": dpt,
                "temperature_c": self.temperature_c,
                "extrapolated": camera.extrapolated(),
            });
        }
        serde_json::json!({
            "e_in_ma": self.e_in_ma,
            "temperature_c": self.temperature_c,
            "e_com_ma": camera.e_com_ma(),
            "extrapolated": camera.extrapolated(),
        })
    }
}

impl SettingArgs {
    /// The calibration, and the camera at the setting ([`SettingFlags::camera_of`]).
    pub fn camera(&self) -> Result<(Calibration, CameraAt)> {
        self.flags.camera_of(&self.calibration)
    }

    /// The `--json` keys of the setting ([`SettingFlags::json`]).
    pub fn json(&self, camera: &CameraAt) -> serde_json::Value {
        self.flags.json(camera)
    }
}
