//! The flags shared by the verbs that use a rig at one setting per camera (`triangulate`,
//! `rectify`): `--rig RIG.json --setting S0 S1 ... --t T0 T1 ... [--allow-extrapolation]`.
//!
//! A setting is each camera's calibration's own: a driver current E_in (mA, turned into
//! E_com by the calibration's thermal part at the camera's `--t`) or a commanded focal
//! power (dpt). It may carry its unit (`150mA`, `12.5dpt`), which is then checked against
//! the calibration's; a bare number is in the calibration's unit. One setting and one
//! temperature per camera of the rig, in the rig's order.

use std::path::PathBuf;

use etl_calib::rig::{Rig, RigAt, RigSetting};
use etl_formats::Result;
use serde_json::{json, Value};

/// `--rig RIG.json --setting S... --t C... [--allow-extrapolation]`.
#[derive(clap::Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct RigArgs {
    /// The rig (etlcal.rig/1): its cameras' calibrations and poses.
    #[arg(long, value_name = "RIG.json")]
    pub rig: PathBuf,
    /// One setting per camera, in the rig's order: E_in in mA for a current calibration,
    /// the focal power in dpt for a focal-power one (a unit suffix, 150mA or 12.5dpt, is
    /// checked against the calibration's).
    #[arg(long = "setting", required = true, num_args = 1.., value_name = "S")]
    pub settings: Vec<String>,
    /// One lens temperature per camera, degC, in the rig's order.
    #[arg(long = "t", required = true, num_args = 1.., value_name = "C")]
    pub temperatures_c: Vec<f64>,
    /// Go on outside the calibrated ranges (the result is marked "extrapolated": true);
    /// refused otherwise.
    #[arg(long)]
    pub allow_extrapolation: bool,
}

impl RigArgs {
    /// The rig and the rig at the settings. Errors: the rig's reader's, a setting that is
    /// not a number (naming `--setting`), the rig's own (counts, kinds, ranges).
    pub fn rig_at(&self) -> Result<(Rig, RigAt)> {
        let rig = Rig::load(&self.rig)?;
        let settings: Vec<RigSetting> = self
            .settings
            .iter()
            .map(|s| s.parse::<RigSetting>().map_err(|e| e.rename_input("settings", "--setting")))
            .collect::<Result<_>>()?;
        let at = rig
            .at(&settings, &self.temperatures_c, crate::trust(self.allow_extrapolation))
            .map_err(|e| e.rename_input("settings", "--setting").rename_input("temperatures_c", "--t"))?;
        Ok((rig, at))
    }

    /// The `--json` keys of the settings: each camera's name, setting, kind, E_com (for a
    /// current calibration) and temperature, and whether any is extrapolated.
    pub fn json(&self, at: &RigAt) -> Value {
        let cameras: Vec<Value> = at
            .cameras()
            .iter()
            .enumerate()
            .map(|(k, c)| {
                json!({
                    "name": at.name(k), "setting": c.setting_kind().name(),
                    "e_in_ma": c.e_in_ma().is_finite().then_some(c.e_in_ma()),
                    "e_com_ma": c.e_com_ma().is_finite().then_some(c.e_com_ma()),
                    "focal_power_dpt": c.focal_power_dpt().is_finite().then_some(c.focal_power_dpt()),
                    "temperature_c": c.temperature_c(), "extrapolated": c.extrapolated(),
                })
            })
            .collect();
        json!({"rig": self.rig.display().to_string(), "cameras": cameras, "extrapolated": at.extrapolated()})
    }
}

/// The camera `cam` names among a rig's cameras `names` (in the rig's order): an index, or
/// a name (`triangulate --pixel CAM:U,V`, `calibrate-rig --thermal CAM=FILE`).
pub fn camera_index<S: AsRef<str>>(names: &[S], cam: &str) -> Option<usize> {
    cam.parse::<usize>().ok().filter(|&k| k < names.len()).or_else(|| names.iter().position(|n| n.as_ref() == cam))
}
