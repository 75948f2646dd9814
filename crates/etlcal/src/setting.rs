//! The flags shared by the verbs that use a calibration at one lens setting (`measure`,
//! `export`, `undistort`): `--calibration FILE --e-in MA --t C [--allow-extrapolation]`.

use std::path::PathBuf;

use etl_formats::calibration::Calibration;
use etl_formats::{CameraAt, Result, Trust};

/// `--calibration FILE --e-in MA --t C [--allow-extrapolation]`.
#[derive(clap::Args, Debug, Clone)]
pub struct SettingArgs {
    /// The calibration (etlcal.calibration/1).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// Driver current, mA.
    #[arg(long = "e-in", value_name = "MA")]
    pub e_in_ma: f64,
    /// Lens temperature, degC.
    #[arg(long = "t", value_name = "C")]
    pub temperature_c: f64,
    /// Go on outside the calibrated temperature, current and E_com ranges (the result is
    /// marked `"extrapolated": true`); refused otherwise.
    #[arg(long)]
    pub allow_extrapolation: bool,
}

impl SettingArgs {
    /// The out-of-range policy the flags choose.
    pub fn trust(&self) -> Trust {
        crate::trust(self.allow_extrapolation)
    }

    /// The calibration, and the camera at the setting (`Calibration::at`: the one range
    /// policy).
    pub fn camera(&self) -> Result<(Calibration, CameraAt)> {
        let cal = Calibration::load(&self.calibration)?;
        let camera = cal.at(self.e_in_ma, self.temperature_c, self.trust())?;
        Ok((cal, camera))
    }
}
